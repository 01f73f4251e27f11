// `sandflow calibrate` and the angles a surface run takes from it: measured once per material,
// cached, recorded in run.json (so a resumed run uses the same) and in summary.json with their
// source. The ctest environment sets SANDFLOW_NO_CALIBRATION; these tests unset it.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>

#include <chrono>
#include <fstream>
#include <string>
#include <thread>

#include <nlohmann/json.hpp>

#include "cli_runner.hpp"

namespace {

using namespace sandflow_test;

// 1 cm sand-like grains (the shipped scenes' friction) in a small block: a run of a few frames
std::string sand_scene(const std::string& surface_keys = "") {
  return tiny_block_scene(60) + R"(
[simulation]
mode = "surface"
[stiffness]
from_load = true
impact_overlap = 0.25
)" + (surface_keys.empty() ? "" : "[surface]\n" + surface_keys);
}

// The word after `label` (and any spaces) in `text`, "" when `label` is not there. (No <regex>:
// GCC 12 warns inside it under the sanitizers, and CI treats warnings as errors.)
std::string word_after(const std::string& text, const std::string& label) {
  const std::size_t at = text.find(label);
  if (at == std::string::npos) return "";
  std::size_t b = at + label.size();
  while (b < text.size() && text[b] == ' ') ++b;
  std::size_t e = b;
  while (e < text.size() && text[e] != ' ' && text[e] != '\n' && text[e] != ')') ++e;
  return text.substr(b, e - b);
}

std::string calibrating(const Sandbox& box) {
  return "env -u SANDFLOW_NO_CALIBRATION SANDFLOW_CACHE_DIR=" + (box.dir / "cache").string() +
         " timeout 300";
}

TEST(Calibrate, MeasuresOnceThenReadsTheCache) {
  Sandbox box;
  const fs::path scene = box.write("t.toml", sand_scene());
  std::string out;
  // a small, fast rig: the default one takes a minute
  const std::string cmd = "calibrate " + scene.string() + " --trials 1 --base 7 --tilt-rate 6";
  ASSERT_EQ(run_sandflow(cmd + " --threads 1", &out, calibrating(box)), 0) << out;
  EXPECT_NE(out.find("s on 1 thread\n"), std::string::npos) << out;  // (--threads taken)
  // one trial: the standard deviation is 0
  const std::string theta0 = word_after(out, "\ntheta0 ");
  ASSERT_FALSE(theta0.empty()) << out;
  EXPECT_EQ(word_after(out, "\ntheta0           " + theta0 + " +-"), "0.00") << out;
  const std::string key = word_after(out, "material key");
  ASSERT_EQ(key.size(), 16u) << out;
  const fs::path cached = box.dir / "cache" / "calibration" / (key + ".json");
  ASSERT_TRUE(fs::exists(cached)) << out;
  EXPECT_NE(out.find("stored"), std::string::npos) << out;
  // a base under the default reads the angles low, and says so
  EXPECT_NE(out.find("warning: a base of 7 diameters measures the angles low"), std::string::npos)
      << out;
  const auto j = nlohmann::json::parse(read_text(cached));
  EXPECT_NEAR(j["theta0_deg"].get<double>(), std::stod(theta0), 0.005);
  EXPECT_GT(j["theta_max_deg"].get<double>(), j["theta0_deg"].get<double>());
  EXPECT_EQ(j["threads"], 1);

  // the second time costs nothing and says where the result came from
  ASSERT_EQ(run_sandflow(cmd, &out, calibrating(box)), 0) << out;
  EXPECT_NE(out.find("cached"), std::string::npos) << out;
  EXPECT_NE(out.find("theta0           " + theta0), std::string::npos) << out;
  // another material is another key
  ASSERT_EQ(run_sandflow(cmd + " --set material.friction=0.3", &out, calibrating(box)), 0) << out;
  EXPECT_NE(out.find("stored"), std::string::npos) << out;
}

TEST(Calibrate, ADamagedCacheFileIsMeasuredAgain) {
  Sandbox box;
  const fs::path scene = box.write("t.toml", sand_scene());
  std::string out;
  const std::string cmd = "calibrate " + scene.string() + " --trials 1 --base 7 --tilt-rate 6";
  ASSERT_EQ(run_sandflow(cmd, &out, calibrating(box)), 0) << out;
  const std::string key = word_after(out, "material key");
  ASSERT_EQ(key.size(), 16u) << out;
  const fs::path file = box.dir / "cache" / "calibration" / (key + ".json");
  // cut short, then whole but without the trials, then with an angle no heap stands at: each is
  // measured again, none is printed or used
  for (const std::string& damaged :
       {std::string("{\"key\":"),
        nlohmann::json{{"key", key}, {"theta0_deg", 30.0}, {"theta_max_deg", 40.0}}.dump(),
        nlohmann::json{{"key", key}, {"theta0_deg", 95.0}, {"theta_max_deg", 99.0}}.dump()}) {
    std::ofstream(file) << damaged;
    ASSERT_EQ(run_sandflow(cmd, &out, calibrating(box)), 0) << out;
    EXPECT_NE(out.find("stored"), std::string::npos) << damaged << "\n" << out;
    EXPECT_EQ(out.find("cached"), std::string::npos) << damaged << "\n" << out;
  }
}

// The key a surface run of `scene` looks up, as `run --check` prints it.
std::string key_of(const Sandbox& box, const fs::path& scene) {
  std::string out;
  EXPECT_EQ(run_sandflow("run " + scene.string() + " --check", &out, calibrating(box)), 0) << out;
  const std::string key = word_after(out, "cached as");
  EXPECT_EQ(key.size(), 16u) << out;
  return key;
}

// A cache folder that cannot be made stops `calibrate` before it measures, not after (the minutes
// of a calibration were lost), and says how to move the folder.
TEST(Calibrate, ACacheFolderThatCannotBeMadeStopsItBeforeItMeasures) {
  Sandbox box;
  const fs::path scene = box.write("t.toml", sand_scene());
  const fs::path file = box.write("a-file", "");
  std::string out;
  EXPECT_EQ(run_sandflow("calibrate " + scene.string() + " --trials 1 --base 7 --tilt-rate 6", &out,
                         "env -u SANDFLOW_NO_CALIBRATION SANDFLOW_CACHE_DIR=" + file.string() +
                             " timeout 300"),
            4)
      << out;
  EXPECT_NE(out.find(file.string() + "/calibration: cannot make the calibration cache folder"),
            std::string::npos)
      << out;
  EXPECT_NE(out.find("set SANDFLOW_CACHE_DIR"), std::string::npos) << out;
  EXPECT_EQ(out.find("calibrating:"), std::string::npos) << out;  // nothing measured
}

// A cache file that cannot be written after minutes of measuring (a disk that filled meanwhile;
// here `ulimit -f 0`) loses the measurement, but says the angles, which a scene can take by hand.
TEST(Calibrate, AnglesMeasuredButNotKeptAreSaid) {
#if defined(__clang__)
  // (the program and the tests are built by one compiler)
  GTEST_SKIP() << "LLVM's OpenMP runtime sizes a file in /dev/shm as the program loads, before "
                  "main: under ulimit -f 0 the program cannot start (docs/known-issues.md)";
#endif
  Sandbox box;
  const fs::path scene = box.write("t.toml", sand_scene());
  const fs::path log = box.dir / "log";
  // (the output through a pipe: the limit would stop its writes to a file too)
  const std::string command = "(ulimit -f 0; env -u SANDFLOW_NO_CALIBRATION SANDFLOW_CACHE_DIR=" +
                              (box.dir / "cache").string() + " timeout 300 " + SANDFLOW_BINARY +
                              " calibrate " + scene.string() +
                              " --trials 1 --base 7 --tilt-rate 6; echo status $?) 2>&1 | cat > " +
                              log.string();
  ASSERT_EQ(std::system(command.c_str()), 0);
  const std::string out = read_text(log);
  EXPECT_NE(out.find("status 4"), std::string::npos) << out;
  EXPECT_NE(out.find("cannot write: File too large\n  the angles measured are not kept: theta0 "),
            std::string::npos)
      << out;
  EXPECT_NE(out.find(" deg (a scene takes them as [surface] repose_angle and max_angle)"),
            std::string::npos)
      << out;
}

/// Starts `args` with the calibration on, waits until it measures, then sends SIGINT; its exit
/// status, with its output in `out`.
int interrupt_while_calibrating(const Sandbox& box, const std::string& args, std::string& out) {
  const fs::path log = box.dir / "interrupted.log";
  fs::remove(log);  // (not the last call's words, read before this one's start)
  const pid_t pid =
      spawn(args, log, RLIM_INFINITY,
            "env -u SANDFLOW_NO_CALIBRATION SANDFLOW_CACHE_DIR=" + (box.dir / "cache").string());
  while (read_text(log).find("calibrating:") == std::string::npos &&
         waitpid(pid, nullptr, WNOHANG) == 0)
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  kill(pid, SIGINT);
  const int status = wait_for(pid);
  out = read_text(log);
  return status;
}

// Ctrl-C while the angles are measured stops the measuring within a frame of the rig and says so;
// nothing half-measured is cached. (Without the handler the process died of the signal, also 130,
// without a word; so the words are checked.)
TEST(Calibrate, CtrlCWhileMeasuringStopsItSaysSoAndKeepsNothing) {
  Sandbox box;
  const fs::path scene = box.write("t.toml", sand_scene());
  std::string out;
  EXPECT_EQ(interrupt_while_calibrating(
                box, "calibrate " + scene.string() + " --trials 1 --base 7 --tilt-rate 6", out),
            130)
      << out;
  EXPECT_NE(out.find("interrupted: nothing measured was kept"), std::string::npos) << out;
  const auto cached = [&] {
    std::error_code ec;
    return fs::exists(box.dir / "cache" / "calibration", ec) &&
           !fs::is_empty(box.dir / "cache" / "calibration", ec);
  };
  EXPECT_FALSE(cached());

  // a run that measures first: stopped before its first frame, its folder is taken again without
  // --force by the same command
  const fs::path run = box.dir / "run";
  const std::string run_args = "run " + scene.string() + " --frames 2 --out " + run.string();
  EXPECT_EQ(interrupt_while_calibrating(box, run_args, out), 130) << out;
  EXPECT_NE(out.find("interrupted while measuring the material's angles, before the run's first "
                     "frame: nothing measured was kept; the same command starts it again"),
            std::string::npos)
      << out;
  EXPECT_FALSE(cached());
  EXPECT_FALSE(fs::exists(run / "run.json"));
  EXPECT_EQ(run_sandflow(run_args, &out, "env SANDFLOW_NO_CALIBRATION=1"), 0) << out;

  // a comparison: its own way on
  const fs::path cmp = box.dir / "cmp";
  EXPECT_EQ(
      interrupt_while_calibrating(
          box, "compare " + scene.string() + " --seeds 1 --frames 2 --out " + cmp.string(), out),
      130)
      << out;
  EXPECT_NE(out.find("interrupted while measuring the material's angles: nothing measured was "
                     "kept; resume with: sandflow compare --resume " +
                     cmp.string()),
            std::string::npos)
      << out;
  EXPECT_FALSE(cached());
}

TEST(Calibrate, ASurfaceRunTakesTheAnglesItsSceneLeavesUnsetFromTheCalibration) {
  Sandbox box;
  const fs::path scene = box.write("t.toml", sand_scene());
  const std::string key = key_of(box, scene);
  ASSERT_FALSE(key.empty());
  // what a calibration of this material left in the cache (the values are the test's)
  fs::create_directories(box.dir / "cache" / "calibration");
  std::ofstream(box.dir / "cache" / "calibration" / (key + ".json"))
      << nlohmann::json{{"key", key}, {"theta0_deg", 30.5}, {"theta_max_deg", 41.25}}.dump();
  std::string out;
  const fs::path run = box.dir / "run";
  ASSERT_EQ(run_sandflow("run " + scene.string() + " --frames 3 --out " + run.string(), &out,
                         calibrating(box)),
            0)
      << out;
  const auto summary = nlohmann::json::parse(read_text(run / "summary.json"));
  const auto& hf = summary["height_field"];
  EXPECT_DOUBLE_EQ(hf["repose_angle_deg"].get<double>(), 30.5);
  EXPECT_DOUBLE_EQ(hf["max_angle_deg"].get<double>(), 41.25);
  EXPECT_EQ(hf["angles_source"].get<std::string>(), "calibration " + key + " (cached)");
  // run.json keeps them: a resumed run uses these whatever the cache holds then
  const auto record = nlohmann::json::parse(read_text(run / "run.json"));
  EXPECT_DOUBLE_EQ(record["surface_angles"]["repose_angle_deg"].get<double>(), 30.5);

  // an angle the scene sets wins over the calibration; the other one still comes from it
  const fs::path set = box.write("set.toml", sand_scene("repose_angle = 28\n"));
  ASSERT_EQ(run_sandflow("run " + set.string() + " --frames 2 --out " + (box.dir / "set").string(),
                         &out, calibrating(box)),
            0)
      << out;
  const auto s2 = nlohmann::json::parse(read_text(box.dir / "set" / "summary.json"));
  EXPECT_DOUBLE_EQ(s2["height_field"]["repose_angle_deg"].get<double>(), 28.0);
  EXPECT_DOUBLE_EQ(s2["height_field"]["max_angle_deg"].get<double>(), 41.25);
  EXPECT_EQ(s2["height_field"]["angles_source"].get<std::string>(),
            "scene and calibration " + key + " (cached)");
}

TEST(Calibrate, WithoutCalibrationTheBuiltInAnglesAreUsedAndSaidSo) {
  Sandbox box;
  const fs::path scene = box.write("t.toml", sand_scene());
  std::string out;
  ASSERT_EQ(run_sandflow("run " + scene.string() + " --frames 2 --out " + (box.dir / "r").string(),
                         &out, "env SANDFLOW_NO_CALIBRATION=1"),
            0)
      << out;
  const auto summary = nlohmann::json::parse(read_text(box.dir / "r" / "summary.json"));
  EXPECT_DOUBLE_EQ(summary["height_field"]["repose_angle_deg"].get<double>(), 32.0);
  EXPECT_NE(summary["height_field"]["angles_source"].get<std::string>().find("built-in"),
            std::string::npos);
  // both set: nothing to calibrate
  const fs::path both = box.write("both.toml", sand_scene("repose_angle = 31\nmax_angle = 37\n"));
  ASSERT_EQ(run_sandflow("run " + both.string() + " --frames 2 --out " + (box.dir / "b").string(),
                         &out, calibrating(box)),
            0)
      << out;
  const auto s2 = nlohmann::json::parse(read_text(box.dir / "b" / "summary.json"));
  EXPECT_EQ(s2["height_field"]["angles_source"].get<std::string>(), "scene");
  EXPECT_FALSE(fs::exists(box.dir / "cache"));
}

}  // namespace
