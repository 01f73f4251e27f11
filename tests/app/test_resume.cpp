// Long runs end to end (docs/checkpoints.md): a run stopped by SIGINT, killed at random moments,
// stopped by a full disk or by a guard is resumed with `sandflow run --resume DIR` and ends
// exactly as the same run uninterrupted: the same state hash, summary figures (timings aside),
// statistics rows and frame files, none missing, duplicated or corrupt.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cctype>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "checkpoint/checkpoint.hpp"
#include "cli_runner.hpp"
#include "io/ply.hpp"

namespace fs = std::filesystem;

namespace {

using sandflow_test::read_text;
using sandflow_test::run_sandflow;
using sandflow_test::Sandbox;
using sandflow_test::spawn;
using sandflow_test::tetrahedron_stl;
using sandflow_test::wait_for;

// A pour onto a floor in surface mode: ~1 s for 40 frames in Release.
const char* kPourScene = R"(
[scene]
name = "pour"
[material]
diameter = 0.01
diameter_spread = 0.1
k_n = 1.0e4
[simulation]
dt_fraction = 0.2
[output]
fps = 30
[[geometry]]
type = "plane"
[[emitter]]
type = "pour"
count = 300
center = [0.0, 0.0, 0.1]
radius = 0.04
rate = 1500
velocity = [0, 0, -1]
)";

constexpr int kFrames = 40;

/// Waits until `file` appears (or `pid` ends), then sends `pid` SIGINT, stopped first: on a
/// loaded machine a run of 40 short frames could otherwise finish between the file and the signal
/// (it did once). The SIGINT waits, pending, until the run goes on.
void interrupt_once_written(pid_t pid, const fs::path& file) {
  while (!fs::exists(file) && waitpid(pid, nullptr, WNOHANG) == 0)
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  kill(pid, SIGSTOP);
  kill(pid, SIGINT);
  kill(pid, SIGCONT);
}

/// The whole number that follows the first `prefix` in `text` (-1 when there is none). (No
/// std::regex: GCC 12 warns about its internals under the sanitizers.)
long long number_after(const std::string& text, const std::string& prefix) {
  const std::size_t at = text.find(prefix);
  if (at == std::string::npos) return -1;
  std::size_t end = at + prefix.size();
  while (end < text.size() && std::isdigit(static_cast<unsigned char>(text[end]))) ++end;
  if (end == at + prefix.size()) return -1;
  return std::stoll(text.substr(at + prefix.size(), end - at - prefix.size()));
}

std::vector<std::string> lines(const fs::path& p) {
  std::vector<std::string> out;
  std::ifstream in(p);
  for (std::string l; std::getline(in, l);) out.push_back(l);
  return out;
}

/// The run in `got` is the run in `want`: same summary figures (timings aside), statistics (the
/// wall-clock column aside) and frame files, every frame there and readable, no temporary file.
void expect_same_run(const fs::path& want, const fs::path& got) {
  auto summary = [](const fs::path& dir) {
    auto j = nlohmann::json::parse(read_text(dir / "summary.json"));
    for (const char* timing :
         {"wall_seconds", "seconds_per_frame", "stage_seconds", "threads", "peak_memory_bytes"})
      j.erase(timing);
    return j;
  };
  ASSERT_TRUE(fs::exists(got / "summary.json")) << got;
  EXPECT_EQ(summary(got)["state_hash"], summary(want)["state_hash"]);
  EXPECT_EQ(summary(got), summary(want));
  const auto a = lines(want / "stats.csv"), b = lines(got / "stats.csv");
  ASSERT_EQ(a.size(), static_cast<std::size_t>(kFrames) + 1);
  ASSERT_EQ(b.size(), a.size());
  for (std::size_t k = 0; k < a.size(); ++k)
    EXPECT_EQ(b[k].substr(0, b[k].rfind(',')), a[k].substr(0, a[k].rfind(','))) << "row " << k;
  for (int f = 1; f <= kFrames; ++f) {
    const std::string name = fmt::format("frames/{:04d}.ply", f);
    ASSERT_TRUE(fs::exists(got / name)) << name << " is missing";
    EXPECT_EQ(read_text(got / name), read_text(want / name)) << name << " differs";
    EXPECT_NO_THROW(sandflow::read_ply((got / name).string())) << name;
  }
  EXPECT_FALSE(fs::exists(got / fmt::format("frames/{:04d}.ply", kFrames + 1)));
  std::error_code ignored;  // (a run without height exports has no heightfield/)
  for (const fs::path& dir : {got, got / "frames", got / "heightfield"})
    for (const auto& e :
         fs::directory_iterator(dir, std::filesystem::directory_options::none, ignored))
      EXPECT_NE(e.path().extension(), ".tmp") << e.path() << " was left behind";
}

/// A comparison's compare.json without its timings (which no two runs share).
nlohmann::json comparison_figures(const fs::path& dir) {
  auto j = nlohmann::json::parse(read_text(dir / "compare.json"));
  for (const char* timing :
       {"speedup", "seconds_per_frame_dem", "seconds_per_frame_surface", "wall_seconds_dem",
        "wall_seconds_surface", "speedup_equal_stiffness", "wall_seconds_dem_equal_stiffness",
        "speedup_per_seed", "speedup_min", "speedup_max"})
    j.erase(timing);
  for (auto& run : j["runs"]) run.erase("wall_seconds");
  return j;
}

/// The runs of a comparison of pour.toml with two seeds and the equal-stiffness run.
constexpr const char* kComparisonOptions = "--seeds 2 --equal-stiffness";
constexpr const char* kComparisonRuns[] = {"surface", "dem", "seed-2/surface", "seed-2/dem",
                                           "dem-equal-stiffness"};

/// Runs that comparison straight into `out`; its exit status.
int compare_straight(const Sandbox& box, const fs::path& out, std::string& log) {
  return run_sandflow(
      fmt::format("compare {} --frames {} {} --out {}", (box.dir / "pour.toml").string(), kFrames,
                  kComparisonOptions, out.string()),
      &log);
}

/// The same runs (state, statistics, frames) and the same compare.json, timings aside.
void expect_same_comparison(const fs::path& want, const fs::path& got) {
  for (const char* run : kComparisonRuns) expect_same_run(want / run, got / run);
  EXPECT_EQ(comparison_figures(got), comparison_figures(want));
}

/// The straight run every test compares with.
fs::path straight_run(const Sandbox& box, double* seconds = nullptr) {
  const fs::path out = box.dir / "straight";
  const auto t0 = std::chrono::steady_clock::now();
  std::string log;
  EXPECT_EQ(run_sandflow(fmt::format("run {} --frames {} --out {}",
                                     (box.dir / "pour.toml").string(), kFrames, out.string()),
                         &log),
            0)
      << log;
  if (seconds)
    *seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

TEST(Resume, SigintFinishesTheFrameCheckpointsAndSaysHowToResume) {
  Sandbox box;
  box.write("pour.toml", kPourScene);
  const fs::path want = straight_run(box);
  const fs::path out = box.dir / "run";
  // checkpoints only when asked: the one found afterwards is SIGINT's
  const pid_t pid = spawn(fmt::format("run {} --frames {} --checkpoint-every 0 --out {}",
                                      (box.dir / "pour.toml").string(), kFrames, out.string()),
                          box.dir / "run.log");
  interrupt_once_written(pid, out / "frames" / "0005.ply");
  EXPECT_EQ(wait_for(pid), 130);
  const std::string log = read_text(box.dir / "run.log");
  const long long frame = number_after(log, "interrupted at frame ");
  ASSERT_GT(frame, 0) << log;
  EXPECT_NE(log.find(fmt::format("interrupted at frame {}; resume with: sandflow run --resume {}\n",
                                 frame, out.string())),
            std::string::npos)
      << log;
  EXPECT_GE(frame, 5);
  EXPECT_LT(frame, kFrames);
  EXPECT_EQ(sandflow::read_checkpoint((out / "checkpoint.bin").string()).world.frame, frame);
  EXPECT_FALSE(fs::exists(out / "summary.json"));
  // the command it printed
  std::string resumed;
  ASSERT_EQ(run_sandflow("run --resume " + out.string(), &resumed), 0) << resumed;
  EXPECT_NE(resumed.find(fmt::format("resuming {} from its checkpoint at frame {}", out.string(),
                                     frame)),
            std::string::npos)
      << resumed;
  expect_same_run(want, out);
  // and a finished run says so
  EXPECT_EQ(run_sandflow("run --resume " + out.string(), &resumed), 0);
  EXPECT_NE(resumed.find("this run is finished"), std::string::npos) << resumed;
}

// A kill after summary.json but inside report.html's writing leaves the run finished with its
// report half written: resuming it removes the half and writes the report
TEST(Resume, AFinishedRunKilledWhileWritingItsReportGetsItsReportOnResume) {
  Sandbox box;
  box.write("pour.toml", kPourScene);
  const fs::path out = straight_run(box);
  const std::string report = read_text(out / "report.html");
  fs::remove(out / "report.html");
  box.write("straight/report.html.tmp", "<html><head>");
  box.write("straight/frames/0003.ply.tmp", "ply\n");
  box.write("straight/heightfield/h_0003.png.tmp", "half");
  std::string log;
  ASSERT_EQ(run_sandflow("run --resume " + out.string(), &log), 0) << log;
  EXPECT_NE(log.find("this run is finished"), std::string::npos) << log;
  EXPECT_NE(log.find("written now"), std::string::npos) << log;
  EXPECT_EQ(read_text(out / "report.html"), report);
  EXPECT_FALSE(fs::exists(out / "report.html.tmp"));
  EXPECT_FALSE(fs::exists(out / "frames" / "0003.ply.tmp"));
  EXPECT_FALSE(fs::exists(out / "heightfield" / "h_0003.png.tmp"));
  // and once it is there, nothing is written again
  ASSERT_EQ(run_sandflow("run --resume " + out.string(), &log), 0) << log;
  EXPECT_EQ(log.find("written now"), std::string::npos) << log;
}

// `compare` is resumable runs: stopped in the plain-DEM run of its second seed, it goes on with
// `compare --resume DIR` (its seeds and equal-stiffness run as it was started) to the comparison
// it would have made uninterrupted.
TEST(Resume, AComparisonStoppedInItsDemRunGoesOnToTheSameComparison) {
  Sandbox box;
  box.write("pour.toml", kPourScene);
  const std::string scene = (box.dir / "pour.toml").string();
  const fs::path want = box.dir / "straight", out = box.dir / "cmp";
  std::string log;
  ASSERT_EQ(compare_straight(box, want, log), 0) << log;
  const pid_t pid = spawn(fmt::format("compare {} --frames {} {} --out {}", scene, kFrames,
                                      kComparisonOptions, out.string()),
                          box.dir / "cmp.log");
  interrupt_once_written(pid, out / "seed-2" / "dem" / "frames" / "0005.ply");
  EXPECT_EQ(wait_for(pid), 130);
  log = read_text(box.dir / "cmp.log");
  EXPECT_NE(log.find("; resume with: sandflow compare --resume " + out.string() + "\n"),
            std::string::npos)
      << log;
  EXPECT_FALSE(fs::exists(out / "compare.json"));
  // options belong to the comparison as it was started; --frames runs it on, never back, and
  // --seeds adds seeds, never drops them
  for (const char* option : {" --grains 100", " --set simulation.seed=7", " --export none"}) {
    EXPECT_EQ(run_sandflow("compare --resume " + out.string() + option, &log), 2) << option;
    EXPECT_NE(log.find("takes no scene"), std::string::npos) << option << log;
  }
  EXPECT_EQ(run_sandflow("compare --resume " + out.string() + " --seeds 1", &log), 2);
  EXPECT_NE(log.find("--seeds 1 is fewer than the 2 seeds"), std::string::npos) << log;
  EXPECT_EQ(run_sandflow("compare --resume " + out.string() + " --frames 3", &log), 2);
  EXPECT_NE(log.find("--frames 3 is before frame 40"), std::string::npos) << log;
  EXPECT_EQ(run_sandflow("compare --resume " + (box.dir / "nothing").string(), &log), 2);
  EXPECT_NE(log.find("no comparison to resume here"), std::string::npos) << log;

  ASSERT_EQ(run_sandflow("compare --resume " + out.string(), &log), 0) << log;
  EXPECT_NE(log.find((out / "seed-2" / "surface").string() + " is finished"), std::string::npos)
      << log;
  EXPECT_NE(log.find("resuming " + (out / "seed-2" / "dem").string() + " from its checkpoint"),
            std::string::npos)
      << log;
  expect_same_comparison(want, out);
  EXPECT_EQ(comparison_figures(out)["runs"].size(), 5u);
  // one of its runs run on to another frame is no longer the comparison's run
  ASSERT_EQ(
      run_sandflow(fmt::format("run --resume {} --frames {}", (out / "dem").string(), kFrames + 2),
                   &log),
      0)
      << log;
  fs::remove(out / "compare.json");
  EXPECT_EQ(run_sandflow("compare --resume " + out.string(), &log), 2);
  EXPECT_NE(log.find("run on to another frame"), std::string::npos) << log;

  // `--frames N` runs every run of the comparison on to frame N: those at 40 run on, the one
  // already at N is read back, one that is missing starts anew to end at N
  const int on = kFrames + 2;
  fs::remove_all(out / "dem-equal-stiffness");
  ASSERT_EQ(run_sandflow(fmt::format("compare --resume {} --frames {}", out.string(), on), &log), 0)
      << log;
  EXPECT_NE(log.find((out / "surface").string() + ": running on to frame 42"), std::string::npos)
      << log;
  EXPECT_EQ(log.find((out / "dem").string() + ": running on to frame"), std::string::npos) << log;
  for (const char* run : kComparisonRuns) {
    EXPECT_EQ(lines(out / run / "stats.csv").size(), static_cast<std::size_t>(on) + 1) << run;
    EXPECT_EQ(nlohmann::json::parse(read_text(out / run / "run.json"))["run_to_frame"], on) << run;
  }
  EXPECT_EQ(nlohmann::json::parse(read_text(out / "compare.json"))["frames"], on);
  EXPECT_EQ(nlohmann::json::parse(read_text(out / "compare_plan.json"))["run_to_frame"], on);
  // resumed again, the comparison reads its runs back as they are
  fs::remove(out / "compare.json");
  ASSERT_EQ(run_sandflow("compare --resume " + out.string(), &log), 0) << log;
  EXPECT_EQ(log.find("running on to frame"), std::string::npos) << log;
  EXPECT_TRUE(fs::exists(out / "compare.json"));
  EXPECT_EQ(
      run_sandflow(fmt::format("compare --resume {} --frames {}", out.string(), kFrames), &log), 2);
  EXPECT_NE(log.find("not back"), std::string::npos) << log;
}

// A finished comparison grows: `compare --resume DIR --seeds K` adds the seeds it lacks and
// `--equal-stiffness` the plain-DEM run at the surface run's stiffness, keeping the runs it has
// (read back, not run again), to the comparison started with them all.
TEST(Resume, AFinishedComparisonGrowsBySeedsAndTheEqualStiffnessRun) {
  Sandbox box;
  box.write("pour.toml", kPourScene);
  const std::string scene = (box.dir / "pour.toml").string();
  const fs::path want = box.dir / "straight", out = box.dir / "cmp";
  std::string log;
  ASSERT_EQ(compare_straight(box, want, log), 0) << log;
  ASSERT_EQ(run_sandflow(fmt::format("compare {} --frames {} --seeds 1 --out {}", scene, kFrames,
                                     out.string()),
                         &log),
            0)
      << log;
  const std::string first_dem = read_text(out / "dem" / "stats.csv");
  EXPECT_EQ(nlohmann::json::parse(read_text(out / "compare.json"))["seeds"], 1);

  ASSERT_EQ(run_sandflow("compare --resume " + out.string() + " --seeds 2", &log), 0) << log;
  EXPECT_NE(log.find(out.string() + ": adding seeds 2 to 2 to the comparison"), std::string::npos)
      << log;
  EXPECT_NE(log.find((out / "dem").string() + " is finished"), std::string::npos) << log;
  EXPECT_EQ(read_text(out / "dem" / "stats.csv"), first_dem);  // read back, not run again
  EXPECT_EQ(nlohmann::json::parse(read_text(out / "compare_plan.json"))["seeds"], 2);
  EXPECT_FALSE(fs::exists(out / "dem-equal-stiffness"));

  ASSERT_EQ(run_sandflow("compare --resume " + out.string() + " --equal-stiffness", &log), 0)
      << log;
  EXPECT_NE(log.find("adding plain DEM at the surface run's stiffness"), std::string::npos) << log;
  EXPECT_EQ(log.find("adding seeds"), std::string::npos) << log;
  EXPECT_TRUE(nlohmann::json::parse(read_text(out / "compare_plan.json"))["equal_stiffness"]);

  expect_same_comparison(want, out);
  // asked again for what it has, it adds nothing and reads its runs back
  ASSERT_EQ(run_sandflow("compare --resume " + out.string() + " --seeds 2 --equal-stiffness", &log),
            0)
      << log;
  EXPECT_EQ(log.find("adding"), std::string::npos) << log;
  EXPECT_EQ(comparison_figures(out), comparison_figures(want));
}

// `compare --dem-from DIR` takes an earlier comparison's plain-DEM runs that were started as its
// own would be (copied in, read back, not made again) and makes the others: the comparison is
// the one made whole. A run of a seed started otherwise is refused before anything runs, and so
// is a source within the comparison's own folder.
TEST(Resume, AComparisonTakesAnEarlierOnesPlainDemRunsWithDemFrom) {
  Sandbox box;
  box.write("pour.toml", kPourScene);
  const std::string scene = (box.dir / "pour.toml").string();
  const fs::path want = box.dir / "straight", first = box.dir / "first", out = box.dir / "cmp";
  std::string log;
  ASSERT_EQ(compare_straight(box, want, log), 0) << log;
  ASSERT_EQ(run_sandflow(fmt::format("compare {} --frames {} --seeds 1 --out {}", scene, kFrames,
                                     first.string()),
                         &log),
            0)
      << log;
  ASSERT_EQ(run_sandflow(fmt::format("compare {} --frames {} {} --dem-from {} --out {}", scene,
                                     kFrames, kComparisonOptions, first.string(), out.string()),
                         &log),
            0)
      << log;
  EXPECT_NE(log.find((out / "dem").string() + ": plain DEM taken from " + (first / "dem").string()),
            std::string::npos)
      << log;
  EXPECT_NE(log.find((out / "seed-2" / "dem").string() + ": --dem-from has no run in"),
            std::string::npos)
      << log;
  EXPECT_NE(log.find("plain DEM's runs taken from " + first.string()), std::string::npos) << log;
  // taken, not made again: its wall times too are the first comparison's
  EXPECT_EQ(read_text(out / "dem" / "stats.csv"), read_text(first / "dem" / "stats.csv"));
  EXPECT_EQ(nlohmann::json::parse(read_text(out / "dem" / "run.json"))["resume_with"],
            "sandflow run --resume " + (out / "dem").string());
  EXPECT_FALSE(fs::exists(out / "dem.copying"));
  for (const char* run : kComparisonRuns) expect_same_run(want / run, out / run);
  nlohmann::json got = comparison_figures(out), wanted = comparison_figures(want);
  EXPECT_EQ(got["dem_from"], first.string());
  EXPECT_TRUE(wanted["dem_from"].is_null());
  got.erase("dem_from");
  wanted.erase("dem_from");
  EXPECT_EQ(got, wanted);
  // the plan keeps the source: resumed, the comparison reads its runs back
  EXPECT_EQ(nlohmann::json::parse(read_text(out / "compare_plan.json"))["dem_from"],
            first.string());
  fs::remove(out / "compare.json");
  ASSERT_EQ(run_sandflow("compare --resume " + out.string(), &log), 0) << log;
  EXPECT_EQ(log.find("taken from " + (first / "dem").string()), std::string::npos) << log;
  EXPECT_EQ(
      run_sandflow("compare --resume " + out.string() + " --dem-from " + first.string(), &log), 2);
  EXPECT_NE(log.find("takes no scene"), std::string::npos) << log;

  // refused: runs of another scene's options, before any run is made; its own folder; no runs
  const fs::path other = box.dir / "other";
  EXPECT_EQ(run_sandflow(fmt::format("compare {} --frames {} --seeds 1 --set material.friction=0.5 "
                                     "--dem-from {} --out {}",
                                     scene, kFrames, first.string(), other.string()),
                         &log),
            2);
  EXPECT_NE(log.find("cannot stand for it"), std::string::npos) << log;
  EXPECT_FALSE(fs::exists(other / "surface" / "run.json"));
  EXPECT_EQ(
      run_sandflow(fmt::format("compare {} --frames {} --seeds 1 --force --dem-from {} --out {}",
                               scene, kFrames, first.string(), first.string()),
                   &log),
      2);
  EXPECT_NE(log.find("within the comparison's own output folder"), std::string::npos) << log;
  EXPECT_TRUE(fs::exists(first / "dem" / "run.json"));
  EXPECT_EQ(run_sandflow(fmt::format("compare {} --frames {} --dem-from {} --out {}", scene,
                                     kFrames, (box.dir / "nothing").string(), other.string()),
                         &log),
            2);
  EXPECT_NE(log.find("not a comparison folder with a plain-DEM run"), std::string::npos) << log;
}

// The exports go on where the checkpoint left them: a resumed run's ParaView series lists every
// frame, the ones before the interruption too, as the same run uninterrupted does.
TEST(Resume, TheExportsOfAResumedRunAreThoseOfTheRunUninterrupted) {
  Sandbox box;
  box.write("pour.toml", kPourScene);
  const std::string scene = (box.dir / "pour.toml").string();
  const fs::path want = box.dir / "straight";
  ASSERT_EQ(run_sandflow(fmt::format("run {} --frames {} --export ply,vtk,geo_gz --out {}", scene,
                                     kFrames, want.string())),
            0);
  const fs::path out = box.dir / "run";
  const pid_t pid = spawn(fmt::format("run {} --frames {} --export ply,vtk,geo_gz --out {}", scene,
                                      kFrames, out.string()),
                          box.dir / "run.log");
  interrupt_once_written(pid, out / "frames" / "0005.vtp");
  ASSERT_EQ(wait_for(pid), 130) << read_text(box.dir / "run.log");
  std::string log;
  ASSERT_EQ(run_sandflow("run --resume " + out.string(), &log), 0) << log;
  expect_same_run(want, out);
  EXPECT_EQ(read_text(out / "frames.pvd"), read_text(want / "frames.pvd"));
  for (int f = 1; f <= kFrames; ++f) {
    const std::string name = fmt::format("frames/{:04d}.vtk", f);
    EXPECT_EQ(read_text(out / name), read_text(want / name)) << name << " differs";
  }
  // Houdini's frames, from the start (written once, before the interruption) to the end
  for (int f = 1; f <= kFrames + 1; ++f) {
    const std::string name = fmt::format("frames/sand.{:04d}.geo.gz", f);
    ASSERT_TRUE(fs::exists(out / name)) << name;
    EXPECT_EQ(read_text(out / name), read_text(want / name)) << name << " differs";
  }
  EXPECT_FALSE(fs::exists(out / fmt::format("frames/sand.{:04d}.geo.gz", kFrames + 2)));
}

TEST(Resume, KilledAtRandomMomentsItResumesToTheSameRun) {
  Sandbox box;
  box.write("pour.toml", kPourScene);
  double seconds = 0;
  const fs::path want = straight_run(box, &seconds);
  const fs::path out = box.dir / "run";
  const std::string start = fmt::format("run {} --frames {} --checkpoint-every 2 --out {}",
                                        (box.dir / "pour.toml").string(), kFrames, out.string());
  // SIGKILL at random moments of each attempt (seeded: the moments of a failure can be re-run),
  // within 40 % of the whole run's time so that several land before the end: at start-up, in a
  // frame, while a frame or a checkpoint is written
  const unsigned seed = 20240611;
  SCOPED_TRACE("seed " + std::to_string(seed));
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> moment(0.0, 1.0);
  double window = 0.4 * seconds;
  int kills = 0;
  bool finished = false;
  for (int attempt = 0; attempt < 16 && !(finished && kills >= 3); ++attempt) {
    if (finished) {
      // done before three kills: the attempts ran faster than the straight run (timed while other
      // tests loaded the machine), so again from the start, the kills twice as early
      fs::remove_all(out);
      finished = false;
      kills = 0;
      window /= 2;
    }
    // (a kill before run.json was written leaves no run to resume: start it again)
    const bool fresh = !fs::exists(out / "run.json");
    const std::string args =
        fresh ? start + " --force" : "run --resume " + out.string() + (attempt % 2 ? " --threads 2" : "");
    const pid_t pid = spawn(args, box.dir / "attempt.log");
    const double at = window * moment(rng);
    std::this_thread::sleep_for(std::chrono::duration<double>(at));
    kill(pid, SIGKILL);
    const int status = wait_for(pid);
    if (status == 128 + SIGKILL) {
      ++kills;
      continue;
    }
    ASSERT_EQ(status, 0) << read_text(box.dir / "attempt.log");
    finished = true;
  }
  EXPECT_GE(kills, 3) << "the kills came too late to test anything";
  if (!finished) {
    std::string log;
    ASSERT_EQ(run_sandflow("run --resume " + out.string(), &log), 0) << log;
  }
  expect_same_run(want, out);
}

TEST(Resume, AFullDiskStopsWithAClearErrorAndKeepsTheLastGoodCheckpoint) {
  Sandbox box;
  box.write("pour.toml", kPourScene);
  const fs::path want = straight_run(box);
  // the checkpoint of frame 2: the pour emits its grains until frame 6, so every later checkpoint
  // holds more grains and is larger (by a sixth or more; the pair lists, which shrink as the heap
  // settles and the allowances with the grains' speeds, do not make up for that)
  const fs::path probe = box.dir / "probe";
  ASSERT_EQ(run_sandflow(fmt::format("run {} --frames 2 --checkpoint-every 2 --out {}",
                                     (box.dir / "pour.toml").string(), probe.string())),
            0);
  const auto limit = static_cast<rlim_t>(fs::file_size(probe / "checkpoint.bin"));
  // every file is limited to that size: a checkpoint past frame 2 cannot be written (EFBIG, as
  // ENOSPC would be for a full disk)
  const fs::path out = box.dir / "run";
  const pid_t pid = spawn(fmt::format("run {} --frames {} --checkpoint-every 1 --out {}",
                                      (box.dir / "pour.toml").string(), kFrames, out.string()),
                          box.dir / "run.log", limit);
  EXPECT_EQ(wait_for(pid), 4);
  const std::string log = read_text(box.dir / "run.log");
  const long long frame = number_after(log, "the run can go on from the last checkpoint (frame ");
  ASSERT_GT(frame, 0) << log;
  EXPECT_NE(log.find(fmt::format("output error: {}/checkpoint.bin: cannot write: File too large\n"
                                 "  the run can go on from the last checkpoint (frame {}): make "
                                 "room (or make the folder writable), then: sandflow run --resume "
                                 "{}\n",
                                 out.string(), frame, out.string())),
            std::string::npos)
      << log;
  EXPECT_EQ(frame, 2);
  // the last good checkpoint is intact and the half-written one is gone
  EXPECT_EQ(sandflow::read_checkpoint((out / "checkpoint.bin").string()).world.frame, frame);
  EXPECT_FALSE(fs::exists(out / "checkpoint.bin.tmp"));
  std::string resumed;
  ASSERT_EQ(run_sandflow("run --resume " + out.string(), &resumed), 0) << resumed;
  expect_same_run(want, out);
}

TEST(Resume, ABlowUpNamesTheStepTheGrainAndTheCommandThatReproducesIt) {
  Sandbox box;
  // a grain thrown onto a floor of soft springs sinks through it in frame 2
  box.write("blow.toml", R"(
[material]
k_n = 10.0
[[geometry]]
type = "plane"
name = "floor"
[[emitter]]
type = "block"
count = 1
center = [0.0, 0.0, 0.3]
size = [0.011, 0.011, 0.011]
velocity = [0.0, 0.0, -5.0]
)");
  const fs::path out = box.dir / "run";
  std::string log;
  ASSERT_EQ(run_sandflow(fmt::format("run {} --mode dem --checkpoint-every 1 --out {}",
                                     (box.dir / "blow.toml").string(), out.string()),
                         &log),
            3)
      << log;
  ASSERT_GT(number_after(log, "simulation stopped: step "), 0) << log;
  const std::string first_line = log.substr(log.find("simulation stopped"));
  const std::string stop = first_line.substr(0, first_line.find('\n'));
  EXPECT_NE(stop.find(" (frame 2, t = "), std::string::npos) << stop;
  EXPECT_NE(stop.find("): grain 0 overlaps geometry[0] ('floor') by "), std::string::npos) << stop;
  EXPECT_NE(stop.find(" % of its diameter, above simulation.max_overlap_stop = 60 %;"),
            std::string::npos)
      << stop;
  EXPECT_NE(first_line.find("\n  reproduce it from the last checkpoint (frame 1): sandflow run "
                            "--resume " + out.string() + "\n"),
            std::string::npos)
      << log;
  // the command given stops at the same step with the same words
  std::string again;
  EXPECT_EQ(run_sandflow("run --resume " + out.string(), &again), 3);
  EXPECT_NE(again.find(stop), std::string::npos) << again;
}

// `--resume DIR --frames N` runs a run on to frame N, a finished one too: stopped on the way and
// resumed without --frames, it still goes to N, and ends as the run started with --frames N.
TEST(Resume, FramesRunsAFinishedRunOnToTheSameLongerRun) {
  Sandbox box;
  box.write("pour.toml", kPourScene);
  const fs::path want = straight_run(box);
  const fs::path out = box.dir / "run";
  std::string log;
  ASSERT_EQ(run_sandflow(fmt::format("run {} --frames 10 --out {}",
                                     (box.dir / "pour.toml").string(), out.string()),
                         &log),
            0)
      << log;
  ASSERT_TRUE(fs::exists(out / "summary.json"));
  // not to a frame before its checkpoint (the last frame, 10): refused, the run left finished
  EXPECT_EQ(run_sandflow("run --resume " + out.string() + " --frames 9", &log), 2);
  EXPECT_NE(log.find("--frames 9 is before the run's checkpoint at frame 10"), std::string::npos)
      << log;
  EXPECT_TRUE(fs::exists(out / "summary.json"));
  const pid_t pid =
      spawn(fmt::format("run --resume {} --frames {}", out.string(), kFrames), box.dir / "on.log");
  interrupt_once_written(pid, out / "frames" / "0015.ply");
  EXPECT_EQ(wait_for(pid), 130) << read_text(box.dir / "on.log");
  EXPECT_FALSE(fs::exists(out / "summary.json"));
  ASSERT_EQ(run_sandflow("run --resume " + out.string(), &log), 0) << log;
  expect_same_run(want, out);
  EXPECT_EQ(nlohmann::json::parse(read_text(out / "run.json"))["run_to_frame"], kFrames);
}

TEST(Resume, RefusesWhatItCannotContinueAndSaysWhy) {
  Sandbox box;
  box.write("pour.toml", kPourScene);
  const fs::path out = box.dir / "run";
  const std::string scene = (box.dir / "pour.toml").string();
  std::string log;
  // no scene and no --resume
  EXPECT_EQ(run_sandflow("run", &log), 2);
  EXPECT_NE(log.find("give a scene file"), std::string::npos) << log;
  // a folder that holds no run
  fs::create_directories(box.dir / "empty");
  EXPECT_EQ(run_sandflow("run --resume " + (box.dir / "empty").string(), &log), 2);
  EXPECT_NE(log.find("no run.json"), std::string::npos) << log;
  // a run to play with, stopped at frame 4 (its checkpoint)
  ASSERT_EQ(run_sandflow(fmt::format("run {} --frames 4 --checkpoint-every 2 --out {}", scene,
                                     out.string())),
            0);
  fs::remove(out / "summary.json");
  // options that would change the run
  EXPECT_EQ(run_sandflow("run --resume " + out.string() + " --set material.friction=0.1", &log), 2);
  EXPECT_NE(log.find("continues a run exactly as it was started"), std::string::npos) << log;
  EXPECT_EQ(run_sandflow("run " + scene + " --resume " + out.string(), &log), 2);
  // a non-empty folder without --force or --resume
  EXPECT_EQ(run_sandflow(fmt::format("run {} --out {}", scene, out.string()), &log), 2);
  EXPECT_NE(log.find("--force"), std::string::npos) << log;
  EXPECT_NE(log.find("--resume"), std::string::npos) << log;
  // a corrupt checkpoint
  const fs::path ck = out / "checkpoint.bin";
  const std::string good = read_text(ck);
  std::string bad = good;
  bad[bad.size() / 2] = static_cast<char>(bad[bad.size() / 2] ^ 0x40);
  std::ofstream(ck, std::ios::binary | std::ios::trunc) << bad;
  EXPECT_EQ(run_sandflow("run --resume " + out.string(), &log), 2);
  EXPECT_NE(log.find(ck.string() + ": the data is corrupt"), std::string::npos) << log;
  // a truncated one
  std::ofstream(ck, std::ios::binary | std::ios::trunc) << good.substr(0, good.size() - 100);
  EXPECT_EQ(run_sandflow("run --resume " + out.string(), &log), 2);
  EXPECT_NE(log.find(ck.string() + ": truncated"), std::string::npos) << log;
  // one written by another version of sandflow
  sandflow::Checkpoint c = sandflow::parse_checkpoint(good, "good");
  c.sandflow_version = "9.9.9";
  std::ofstream(ck, std::ios::binary | std::ios::trunc) << sandflow::encode_checkpoint(c);
  EXPECT_EQ(run_sandflow("run --resume " + out.string(), &log), 2);
  EXPECT_NE(log.find("written by sandflow 9.9.9"), std::string::npos) << log;
  // (a refused checkpoint leaves the folder as it was)
  EXPECT_TRUE(fs::exists(out / "frames" / "0004.ply"));
  // one of another run (another scene)
  const fs::path other = box.dir / "other";
  ASSERT_EQ(run_sandflow(fmt::format(
                "run {} --frames 2 --checkpoint-every 2 --set material.friction=0.3 --out {}",
                scene, other.string())),
            0);
  fs::copy_file(other / "checkpoint.bin", ck, fs::copy_options::overwrite_existing);
  // (a frame after the checkpoint, as a killed run leaves it: kept while the checkpoint is refused)
  fs::copy_file(out / "frames" / "0004.ply", out / "frames" / "0005.ply");
  EXPECT_EQ(run_sandflow("run --resume " + out.string(), &log), 2);
  EXPECT_NE(log.find("written for another scene"), std::string::npos) << log;
  EXPECT_TRUE(fs::exists(out / "frames" / "0005.ply"));
  // the good one again: it resumes, and the frame after it is made again
  std::ofstream(ck, std::ios::binary | std::ios::trunc) << good;
  EXPECT_EQ(run_sandflow("run --resume " + out.string(), &log), 0) << log;
  EXPECT_FALSE(fs::exists(out / "frames" / "0005.ply"));
}

// A start stopped before its run.json (Ctrl-C while the run measured its material's angles) leaves
// an empty frames/ folder, which the same command may fill without --force; anything more it may
// not.
TEST(Resume, AStartStoppedBeforeItsRecordNeedsNoForce) {
  Sandbox box;
  const std::string scene = box.write("pour.toml", kPourScene).string();
  const fs::path out = box.dir / "run";
  fs::create_directories(out / "frames");
  const std::string cmd = fmt::format("run {} --frames 1 --out {}", scene, out.string());
  std::string log;
  EXPECT_EQ(run_sandflow(cmd, &log), 0) << log;
  // killed as it wrote its record: the half-written record is nothing to keep, and goes
  fs::remove_all(out);
  fs::create_directories(out / "frames");
  box.write("run/run.json.tmp", "{\"sta");
  EXPECT_EQ(run_sandflow(cmd, &log), 0) << log;
  EXPECT_FALSE(fs::exists(out / "run.json.tmp"));
  // a run replaced with --force leaves none of the old run's half-written files (frames.pvd:
  // one this run, without a VTK export, does not write again over it)
  box.write("run/frames.pvd.tmp", "half");
  EXPECT_EQ(run_sandflow(cmd + " --force", &log), 0) << log;
  EXPECT_FALSE(fs::exists(out / "frames.pvd.tmp"));
  fs::remove_all(out);
  fs::create_directories(out / "frames");
  box.write("run/frames/0001.ply", "not a frame");
  EXPECT_EQ(run_sandflow(cmd, &log), 2) << log;
  EXPECT_NE(log.find("the output folder is not empty"), std::string::npos) << log;
}

// A mesh file edited since the run started is not the run's mesh: the checkpoint is refused, even
// when the edit leaves the mesh's particles as they were (a face given twice: the same samples,
// another inside test for the emitters).
TEST(Resume, AMeshEditedSinceTheStartIsRefused) {
  Sandbox box;
  box.write("tet.stl", tetrahedron_stl(0.1));
  const std::string scene =
      box.write("pour.toml", std::string(kPourScene) +
                                 "[[geometry]]\ntype = \"mesh\"\nname = \"tet\"\n"
                                 "file = \"tet.stl\"\nposition = [0.3, 0.0, 0.0]\n")
          .string();
  const fs::path out = box.dir / "run";
  std::string log;
  ASSERT_EQ(run_sandflow(fmt::format("run {} --mode dem --frames 4 --checkpoint-every 2 --out {}",
                                     scene, out.string()),
                         &log),
            0)
      << log;
  fs::remove(out / "summary.json");
  const auto particles = [&] {
    std::string check;
    EXPECT_EQ(run_sandflow("run " + scene + " --check", &check), 0) << check;
    return check.substr(0, check.find(" boundary particles"));
  };
  const std::string before = particles();
  box.write("tet.stl", tetrahedron_stl(0.1, true));
  ASSERT_EQ(particles(), before);  // (the edit this test is about: the particles stay)
  EXPECT_EQ(run_sandflow("run --resume " + out.string(), &log), 2) << log;
  EXPECT_NE(log.find("written for another scene"), std::string::npos) << log;
  box.write("tet.stl", tetrahedron_stl(0.1));
  EXPECT_EQ(run_sandflow("run --resume " + out.string(), &log), 0) << log;
}

}  // namespace
