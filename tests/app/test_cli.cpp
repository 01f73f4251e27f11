// The sandflow command end to end: exit codes, what it writes, and what it refuses.
#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "cli_runner.hpp"
#include "io/ply.hpp"
#include "support/sanitizers.hpp"

namespace fs = std::filesystem;

namespace {

using sandflow_test::run_sandflow;
using sandflow_test::Sandbox;

const std::string kTinyScene = sandflow_test::tiny_block_scene(200);

TEST(Cli, RunWritesStatsSummaryAndFrames) {
  Sandbox box;
  const auto scene = box.write("tiny.toml", kTinyScene);
  const auto out = box.dir / "out";
  std::string log;
  ASSERT_EQ(
      run_sandflow("run " + scene.string() + " --mode dem --frames 3 --out " + out.string(), &log),
      0)
      << log;
  // stats.csv: a header and one row per frame
  std::ifstream csv(out / "stats.csv");
  std::string line;
  int rows = -1;
  while (std::getline(csv, line)) ++rows;
  EXPECT_EQ(rows, 3);
  // summary.json: the keys the issue asks for
  const auto summary = nlohmann::json::parse(std::ifstream(out / "summary.json"));
  for (const char* key : {"scene", "mode", "frames", "n_total", "n_simulated_mean",
                          "seconds_per_frame", "dt_mean", "repose_angle_deg",
                          "grains_inside_geometry", "state_hash"})
    EXPECT_TRUE(summary.contains(key)) << key;
  EXPECT_EQ(summary["n_total"], 200);
  EXPECT_EQ(summary["frames"], 3);
  EXPECT_EQ(summary["mode"], "dem");
  EXPECT_EQ(summary["grains_inside_geometry"], 0);
  // the last frame reads back with every grain
  EXPECT_EQ(sandflow::read_ply((out / "frames" / "0003.ply").string()).size(), 200u);
  // measure reads it again
  EXPECT_EQ(run_sandflow("measure " + out.string(), &log), 0) << log;
}

// Without --threads or the scene's simulation.threads, a run takes OMP_NUM_THREADS when it holds a
// count (how a user or a scheduler shares the cores out among jobs), else every core
TEST(Cli, ThreadsComeFromTheOptionTheSceneOmpNumThreadsThenTheCores) {
  Sandbox box;
  const auto scene = box.write("tiny.toml", kTinyScene);
  const auto threads_of = [&](const std::string& env, const std::string& args) {
    const auto out = box.dir / "out";
    std::string log;
    EXPECT_EQ(run_sandflow("run " + scene.string() + " --mode dem --frames 1 --force --out " +
                               out.string() + args,
                           &log, env),
              0)
        << log;
    return nlohmann::json::parse(std::ifstream(out / "summary.json"))["threads"].get<int>();
  };
  EXPECT_EQ(threads_of("env OMP_NUM_THREADS=3", ""), 3);
  EXPECT_EQ(threads_of("env OMP_NUM_THREADS=3,1", ""), 3);  // (nested levels: the outer one)
  EXPECT_EQ(threads_of("env OMP_NUM_THREADS=3", " --threads 1"), 1);
  EXPECT_EQ(threads_of("env OMP_NUM_THREADS=3", " --set simulation.threads=2"), 2);
  EXPECT_EQ(threads_of("env -u OMP_NUM_THREADS", ""), omp_get_num_procs());
  EXPECT_EQ(threads_of("env OMP_NUM_THREADS=many", ""), omp_get_num_procs());  // not a count
  // the option and the scene key end at the same count (OMP_NUM_THREADS too: src/core/threads.hpp)
  std::string log;
  // and OpenMP is never handed more: 100,000 threads crashed libgomp while the World was built
  // (a segmentation fault on a machine that can start 96,364 processes), where it takes the count
  // in OMP_NUM_THREADS as it stands
  EXPECT_EQ(threads_of("env OMP_NUM_THREADS=100000", ""), omp_get_num_procs());
  EXPECT_EQ(run_sandflow("run " + scene.string() + " --check", &log, "env OMP_NUM_THREADS=100000"),
            0)
      << log;
  EXPECT_NE(log.find("warning: OMP_NUM_THREADS=100000 is not a count of threads from 1 to 4096: "
                     "ignored"),
            std::string::npos)
      << log;
  // OMP_THREAD_LIMIT caps what OpenMP gives a region: the run says the count it runs on
  EXPECT_EQ(threads_of("env OMP_THREAD_LIMIT=2", " --threads 3"), 2);
  EXPECT_EQ(threads_of("env OMP_THREAD_LIMIT=1 OMP_NUM_THREADS=3", ""), 1);
  EXPECT_EQ(run_sandflow("run " + scene.string() + " --mode dem --frames 1 --threads 3 --out " +
                             (box.dir / "limited").string(),
                         &log, "env OMP_THREAD_LIMIT=2"),
            0);
  EXPECT_NE(log.find("warning: OMP_THREAD_LIMIT=2 holds this job to 2 threads (3 asked)"),
            std::string::npos)
      << log;
  // a CPU list for a larger machine: libgomp stops the program when it binds a thread there
  // ("Thread creation failed: Invalid argument", status 1), so the variable is named first
  run_sandflow("run " + scene.string() + " --mode dem --frames 1 --threads 2 --force --out " +
                   (box.dir / "bound").string(),
               &log, "env GOMP_CPU_AFFINITY='0 100000'");
  EXPECT_NE(log.find("warning: GOMP_CPU_AFFINITY=0 100000 names a CPU this process cannot run "
                     "on (100000)"),
            std::string::npos)
      << log;
  for (const std::string args : {" --threads 4097", " --set simulation.threads=4097"}) {
    EXPECT_EQ(
        run_sandflow("run " + scene.string() + " --out " + (box.dir / "big").string() + args, &log),
        2)
        << args;
    EXPECT_NE(log.find("4096"), std::string::npos) << log;
  }
}

TEST(Cli, BadSceneExitsTwoNamingThePlaceAndWritesNothing) {
  Sandbox box;
  std::string text = kTinyScene;
  text.replace(text.find("k_n = 1.0e4"), 11, "k_n = -5.0");
  const auto scene = box.write("bad.toml", text);
  const auto out = box.dir / "out";
  std::string log;
  EXPECT_EQ(run_sandflow("run " + scene.string() + " --out " + out.string(), &log), 2);
  EXPECT_NE(log.find("bad.toml:6:1: material.k_n"), std::string::npos) << log;
  EXPECT_FALSE(fs::exists(out));
  // a bad --set is refused the same way
  EXPECT_EQ(run_sandflow("run " + box.write("ok.toml", kTinyScene).string() +
                             " --set material.friction=-1 --out " + out.string(),
                         &log),
            2);
  EXPECT_NE(log.find("material.friction"), std::string::npos) << log;
  EXPECT_FALSE(fs::exists(out));
}

TEST(Cli, SurfaceModeReportsTransitionsAndTheHeightField) {
  Sandbox box;
  const auto out = box.dir / "out";
  std::string log;
  ASSERT_EQ(run_sandflow("run " + box.write("t.toml", kTinyScene).string() +
                             " --mode surface --out " + out.string(),
                         &log),
            0)
      << log;
  std::ifstream stats(out / "stats.csv");
  std::string header;
  std::getline(stats, header);
  for (const char* column : {"trapped", "dislodged", "slept", "woken", "n_static"})
    EXPECT_NE(header.find(column), std::string::npos) << column;
  std::ifstream in(out / "summary.json");
  const auto summary = nlohmann::json::parse(in);
  EXPECT_EQ(summary["mode"], "surface");
  for (const char* key : {"cells", "rolling_mean", "rolling_max", "static_volume"})
    EXPECT_TRUE(summary["height_field"].contains(key)) << key;
  EXPECT_TRUE(summary["transitions"].contains("trapped"));
  EXPECT_EQ(summary["n_total"], 200);
}

// A surface run's frames hold only the grains it simulates: measured before its end, the heap is
// read from the last checkpoint, every grain, and a run with no checkpoint yet is refused.
TEST(Cli, MeasureReadsAnUnfinishedSurfaceRunFromItsCheckpointWithEveryGrain) {
  Sandbox box;
  const auto out = box.dir / "out";
  std::string log;
  // the block settles and its columns close within the run, so grains go to sleep
  ASSERT_EQ(run_sandflow("run " + box.write("t.toml", kTinyScene).string() +
                             " --mode surface --frames 30 --set surface.close_after=0.1 --out " +
                             out.string(),
                         &log),
            0)
      << log;
  const auto summary = nlohmann::json::parse(std::ifstream(out / "summary.json"));
  ASSERT_GT(summary["n_static_final"].get<int>(), 0) << "no grain asleep: the test shows nothing";
  ASSERT_LT(sandflow::read_ply((out / "frames" / "0030.ply").string()).size(), 200u);
  // the run as it stood at its last checkpoint, before it finished
  const std::string summary_text = sandflow_test::read_text(out / "summary.json");
  fs::remove(out / "final_grains.ply");
  fs::remove(out / "summary.json");
  ASSERT_EQ(run_sandflow("measure " + out.string(), &log), 0) << log;
  EXPECT_NE(log.find("(frame 30, every grain)"), std::string::npos) << log;
  EXPECT_NE(log.find("grains           200\n"), std::string::npos) << log;
  EXPECT_NE(log.find("the run is not finished"), std::string::npos) << log;
  fs::remove(out / "checkpoint.bin");
  EXPECT_EQ(run_sandflow("measure " + out.string(), &log), 2) << log;
  EXPECT_NE(log.find("no checkpoint yet"), std::string::npos) << log;
  // a finished run whose final state and checkpoint were deleted is not called unfinished
  std::ofstream(out / "summary.json") << summary_text;
  EXPECT_EQ(run_sandflow("measure " + out.string(), &log), 2) << log;
  EXPECT_NE(log.find("the run finished, but its final_grains.ply and checkpoint.bin are gone"),
            std::string::npos)
      << log;
}

// measure --frame reads one frame of a plain-DEM run (every grain is in it); --slower-than leaves
// out the grains as fast as V or faster; a surface run's frame is refused, by its run.json or,
// without one, by the INTERFACE grains only its frames hold.
TEST(Cli, MeasureReadsAFrameOfEitherModeAndLeavesOutFastGrains) {
  Sandbox box;
  const auto scene = box.write("t.toml", kTinyScene);
  const auto out = box.dir / "dem";
  std::string log;
  ASSERT_EQ(
      run_sandflow("run " + scene.string() + " --mode dem --frames 3 --out " + out.string(), &log),
      0)
      << log;
  ASSERT_EQ(run_sandflow("measure " + out.string() + " --frame 2", &log), 0) << log;
  EXPECT_NE(log.find("frames/0002.ply"), std::string::npos) << log;
  EXPECT_NE(log.find("frame 2 of the run"), std::string::npos) << log;
  // the grains left out are those at least as fast as the bound: half of them at their median
  const sandflow::FrameData f = sandflow::read_ply((out / "frames" / "0002.ply").string());
  std::vector<double> speeds;
  for (const auto& v : f.velocity) speeds.push_back(std::sqrt(sandflow::norm2(v)));
  std::sort(speeds.begin(), speeds.end());
  const double bound = speeds[speeds.size() / 2];
  ASSERT_GT(bound, speeds.front()) << "the grains all move alike: the test shows nothing";
  const auto fast =
      std::count_if(speeds.begin(), speeds.end(), [&](double s) { return s >= bound; });
  ASSERT_EQ(
      run_sandflow(fmt::format("measure {} --frame 2 --slower-than {:.17g}", out.string(), bound),
                   &log),
      0)
      << log;
  EXPECT_NE(log.find(fmt::format("left out         {} grains as fast as", fast)), std::string::npos)
      << log;
  // a series: a line a frame, and each line is that frame's own measure
  ASSERT_EQ(run_sandflow("measure " + out.string() + " --frames 1:3:2", &log), 0) << log;
  EXPECT_NE(log.find("1 to 3 in steps of 2: 2 frames"), std::string::npos) << log;
  EXPECT_EQ(log.find("\n     2 "), std::string::npos) << log;
  EXPECT_NE(log.find("\n     3 "), std::string::npos) << log;
  for (const char* bad : {"1:3:0", "3:1", "1:9", "x", "1:2:3:4"})
    EXPECT_EQ(run_sandflow("measure " + out.string() + " --frames " + bad, &log), 2) << bad;
  EXPECT_NE(run_sandflow("measure " + out.string() + " --frames 1:3 --frame 2", &log), 0) << log;
  // a frame the run did not write names those it did
  EXPECT_EQ(run_sandflow("measure " + out.string() + " --frame 9", &log), 2) << log;
  EXPECT_NE(log.find("0009.ply: no such frame; this folder's frames are 1 to 3"), std::string::npos)
      << log;
  // the last frame is the highest number, not the last name: 10000 follows 9999
  fs::remove(out / "final_grains.ply");
  fs::copy_file(out / "frames" / "0002.ply", out / "frames" / "9999.ply");
  fs::copy_file(out / "frames" / "0003.ply", out / "frames" / "10000.ply");
  ASSERT_EQ(run_sandflow("measure " + out.string(), &log), 0) << log;
  EXPECT_NE(log.find("frames/10000.ply"), std::string::npos) << log;

  // a surface run's frame: its grains, and the static sand under them from the frame's h image
  const auto surface = box.dir / "surface";
  ASSERT_EQ(run_sandflow("run " + scene.string() +
                             " --mode surface --frames 30 --set surface.close_after=0.1 --out " +
                             surface.string(),
                         &log),
            0)
      << log;
  const sandflow::FrameData s = sandflow::read_ply((surface / "frames" / "0030.ply").string());
  ASSERT_TRUE(std::any_of(s.state.begin(), s.state.end(), [](std::uint8_t k) { return k != 0; }))
      << "no INTERFACE grain in the frame: the test shows nothing";
  ASSERT_EQ(run_sandflow("measure " + surface.string() + " --frame 30", &log), 0) << log;
  EXPECT_NE(log.find(fmt::format("grains           {}\n", s.size())), std::string::npos) << log;
  EXPECT_NE(log.find("static sand      heightfield/h_0030.png: "), std::string::npos) << log;
  // without the frame's h image, or without the run's record of its scene, it cannot say
  const auto bare = box.dir / "bare";
  fs::create_directories(bare / "frames");
  fs::copy_file(surface / "frames" / "0030.ply", bare / "frames" / "0030.ply");
  EXPECT_EQ(run_sandflow("measure " + bare.string() + " --frame 30", &log), 2) << log;
  EXPECT_NE(log.find("a surface run's frames hold only the grains it simulates"), std::string::npos)
      << log;
  EXPECT_NE(log.find("without the run's run.json"), std::string::npos) << log;
  fs::remove(surface / "heightfield" / "h_0030.png");
  EXPECT_EQ(run_sandflow("measure " + surface.string() + " --frame 30", &log), 2) << log;
  EXPECT_NE(log.find("which this run did not write for that frame"), std::string::npos) << log;
  const auto plain = box.dir / "surface_ply";
  ASSERT_EQ(run_sandflow("run " + scene.string() +
                             " --mode surface --frames 3 --export ply --out " + plain.string(),
                         &log),
            0)
      << log;
  EXPECT_EQ(run_sandflow("measure " + plain.string() + " --frame 3", &log), 2) << log;
  EXPECT_NE(log.find("which this run left out"), std::string::npos) << log;
}

// The heap of a surface run's frame, its static sand standing in as one grain a column whose top
// is h, against the same run's final state with every static grain. Columns at rest close after
// 0.2 s, so that most of the heap's top is static sand, missing from the frame's grains. A static
// grain sleeps below h - T / cos(theta) (docs/physics.md, step 6), its top below h by up to about a
// grain (T, the sleeping margin and the gaps of a packing), so the heap's height agrees within a
// diameter (0.1-5.0 mm with and without the calibration when this test was written). The angle:
// within twice the two fits' combined standard error, on a heap six grains high whose fits have
// 1.1-2.4 degrees each (1.4-1.5 degrees apart when this test was written, 2.9 degrees with
// standard errors of about 2 each once the flow eroded only the static top it reaches). Without
// the static sand the frame's 28-82 grains give no angle at all.
TEST(Cli, MeasureOfASurfaceRunsFrameStandsItsStaticTopInForTheSleepingSand) {
  if constexpr (sandflow::test::kSanitizers)
    GTEST_SKIP() << "a long run, left to the Release suite";
  Sandbox box;
  const auto out = box.dir / "floor";
  std::string log;
  ASSERT_EQ(run_sandflow("run " + (fs::path(SANDFLOW_SOURCE_DIR) / "scenes/floor.toml").string() +
                             " --grains 2000 --threads 1 --set surface.close_after=0.2 --out " +
                             out.string(),
                         &log),
            0)
      << log;
  auto read = [&](const std::string& what, const std::string& args) {
    EXPECT_EQ(run_sandflow("measure " + out.string() + args, &log), 0) << log;
    const std::size_t at = log.find(what);
    EXPECT_NE(at, std::string::npos) << log;
    return at == std::string::npos ? std::nan("") : std::stod(log.substr(at + what.size()));
  };
  const double angle = read("repose_angle_deg", ""), height = read("heap height", "");
  const double error = read("(standard error", "");
  const double frame_angle = read("repose_angle_deg", " --frame 449");
  const double frame_error = read("(standard error", " --frame 449");
  const double frame_height = read("heap height", " --frame 449");
  EXPECT_NE(log.find("static sand      heightfield/h_0449.png"), std::string::npos) << log;
  EXPECT_NEAR(frame_height, height, 0.01) << log;
  EXPECT_LT(std::hypot(error, frame_error), 3.5) << log;  // (else the bound below says little)
  EXPECT_NEAR(frame_angle, angle, 2 * std::hypot(error, frame_error)) << log;
  // the series' last line is that frame's own measure, its mean the mean of its lines
  const double slow_angle = read("repose_angle_deg", " --frame 449 --slower-than 0.3");
  ASSERT_EQ(
      run_sandflow("measure " + out.string() + " --frames 409:449:20 --slower-than 0.3", &log), 0)
      << log;
  std::vector<double> angles;
  for (int n : {409, 429, 449}) {
    const std::size_t at = log.find(fmt::format("\n{:>6} ", n));
    ASSERT_NE(at, std::string::npos) << log;
    angles.push_back(std::stod(log.substr(at + 8)));
  }
  EXPECT_EQ(fmt::format("{:.2f}", angles.back()), fmt::format("{:.2f}", slow_angle)) << log;
  const std::size_t at = log.find("mean             ");
  ASSERT_NE(at, std::string::npos) << log;
  // (the mean and the angles are printed to two decimals: each is within 0.005 of its value)
  EXPECT_NEAR(std::stod(log.substr(at + 17)), (angles[0] + angles[1] + angles[2]) / 3, 0.011)
      << log;
}

TEST(Cli, CompareWritesBothRunsAndTheTable) {
  Sandbox box;
  const auto out = box.dir / "cmp";
  std::string log;
  ASSERT_EQ(run_sandflow("compare " + box.write("t.toml", kTinyScene).string() +
                             " --frames 10 --out " + out.string(),
                         &log),
            0)
      << log;
  EXPECT_TRUE(fs::exists(out / "dem" / "summary.json"));
  EXPECT_TRUE(fs::exists(out / "surface" / "summary.json"));
  std::ifstream in(out / "compare.json");
  const auto j = nlohmann::json::parse(in);
  for (const char* key : {"speedup", "simulated_fraction_mean", "simulated_fraction_last_half",
                          "surface_rms_rel", "repose_angle_dem_deg", "repose_angle_surface_deg",
                          "n_total", "dt_dem", "dt_surface", "same_stiffness"})
    EXPECT_TRUE(j.contains(key)) << key;
  EXPECT_EQ(j["n_total"], 200);
  EXPECT_GT(j["speedup"].get<double>(), 0);
  EXPECT_LE(j["simulated_fraction_mean"].get<double>(), 1.0);
  EXPECT_NE(log.find("speed-up"), std::string::npos) << log;
  // --mode makes no sense for a comparison
  EXPECT_EQ(run_sandflow("compare " + (box.dir / "t.toml").string() + " --mode dem --out " +
                         (box.dir / "x").string()),
            2);
}

// --seeds K runs each mode K times with seeds S, S+1, ...; the means, the spread of the plain-DEM
// seeds and the distances between their surfaces are what compare.json reads against.
TEST(Cli, CompareRunsEachSeedInBothModesAndTheEqualStiffnessRun) {
  Sandbox box;
  const auto out = box.dir / "cmp";
  std::string log;
  ASSERT_EQ(run_sandflow("compare " + box.write("t.toml", kTinyScene).string() +
                             " --frames 8 --seeds 2 --equal-stiffness --set simulation.seed=5 "
                             "--set camera.fov=1 --out " +
                             out.string(),
                         &log),
            0)
      << log;
  // the scene's warning once, not once for each of its five runs
  const std::string warning = "camera.fov = 1 is in degrees";
  const std::size_t first = log.find(warning);
  EXPECT_NE(first, std::string::npos) << log;
  EXPECT_EQ(log.find(warning, first + 1), std::string::npos) << log;
  const auto j = nlohmann::json::parse(std::ifstream(out / "compare.json"));
  EXPECT_EQ(j["seeds"], 2);
  EXPECT_EQ(j["seed_values"], nlohmann::json::array({5, 6}));
  ASSERT_EQ(j["runs"].size(), 5u);
  std::vector<double> dem_angles, surface_angles;
  std::set<std::string> dem_hashes;
  for (const auto& run : j["runs"]) {
    const fs::path dir = out / run["folder"].get<std::string>();
    const auto summary = nlohmann::json::parse(std::ifstream(dir / "summary.json"));
    EXPECT_EQ(summary["state_hash"], run["state_hash"]) << dir;
    const std::string mode = run["mode"];
    if (mode == "dem") {
      dem_hashes.insert(run["state_hash"].get<std::string>());
      if (run["repose_angle_deg"].is_number()) dem_angles.push_back(run["repose_angle_deg"]);
    } else if (mode == "surface" && run["repose_angle_deg"].is_number()) {
      surface_angles.push_back(run["repose_angle_deg"]);
    }
  }
  EXPECT_TRUE(fs::exists(out / "surface" / "summary.json"));
  EXPECT_TRUE(fs::exists(out / "seed-6" / "dem" / "summary.json"));
  EXPECT_EQ(dem_hashes.size(), 2u);  // the two seeds made two different runs
  // the figures follow from the runs
  if (dem_angles.size() == 2) {
    EXPECT_NEAR(j["repose_angle_dem_spread_deg"].get<double>(),
                std::abs(dem_angles[0] - dem_angles[1]), 1e-9);
    EXPECT_NEAR(j["repose_angle_dem_deg"].get<double>(), 0.5 * (dem_angles[0] + dem_angles[1]),
                1e-9);
  }
  if (dem_angles.size() == 2 && surface_angles.size() == 2) {
    EXPECT_NEAR(j["repose_angle_diff_deg"].get<double>(),
                std::abs(0.5 * (surface_angles[0] + surface_angles[1]) -
                         0.5 * (dem_angles[0] + dem_angles[1])),
                1e-9);
  }
  for (const char* key : {"surface_rms_rel", "surface_rms_d", "surface_rms_dem_vs_dem_rel",
                          "surface_rms_dem_vs_dem_d", "max_overlap_surface_rel",
                          "max_overlap_dem_rel", "speedup_equal_stiffness"})
    EXPECT_TRUE(j[key].is_number()) << key;
  EXPECT_NEAR(j["surface_rms_d"].get<double>() * 0.01, j["surface_rms"].get<double>(), 1e-12);
  // the equal-stiffness run is plain DEM at the surface run's k_n and dt
  const auto eq = nlohmann::json::parse(std::ifstream(out / "dem-equal-stiffness" / "summary.json"));
  EXPECT_EQ(eq["mode"], "dem");
  EXPECT_DOUBLE_EQ(eq["k_n"].get<double>(), j["k_n_surface"].get<double>());
  EXPECT_DOUBLE_EQ(eq["dt_mean"].get<double>(), j["dt_surface"].get<double>());
  EXPECT_NE(log.find("speed-up at equal stiffness"), std::string::npos) << log;
  // each seed's speed-up: its plain-DEM run's time over its surface run's, and their range
  std::map<std::int64_t, std::map<std::string, double>> wall;
  for (const auto& run : j["runs"])
    wall[run["seed"].get<std::int64_t>()][run["mode"].get<std::string>()] = run["wall_seconds"];
  ASSERT_EQ(j["speedup_per_seed"].size(), 2u);
  for (int k = 0; k < 2; ++k)
    EXPECT_DOUBLE_EQ(j["speedup_per_seed"][k].get<double>(),
                     wall[5 + k]["dem"] / wall[5 + k]["surface"])
        << k;
  EXPECT_EQ(j["speedup_min"], std::min(j["speedup_per_seed"][0], j["speedup_per_seed"][1]));
  EXPECT_EQ(j["speedup_max"], std::max(j["speedup_per_seed"][0], j["speedup_per_seed"][1]));
  EXPECT_NE(log.find("x by seed"), std::string::npos) << log;
  EXPECT_EQ(run_sandflow("compare " + (box.dir / "t.toml").string() + " --seeds 0 --out " +
                         (box.dir / "y").string()),
            2);
}

TEST(Cli, NonEmptyOutputFolderNeedsForce) {
  Sandbox box;
  const auto scene = box.write("t.toml", kTinyScene);
  const auto out = box.dir / "out";
  ASSERT_EQ(run_sandflow("run " + scene.string() + " --mode dem --frames 1 --out " + out.string()),
            0);
  std::string log;
  EXPECT_EQ(
      run_sandflow("run " + scene.string() + " --mode dem --frames 1 --out " + out.string(), &log),
      2);
  EXPECT_NE(log.find("--force"), std::string::npos) << log;
  EXPECT_EQ(run_sandflow("run " + scene.string() + " --mode dem --frames 1 --force --out " +
                         out.string()),
            0);
}

TEST(Cli, CompareForceReplacesAnEarlierComparison) {
  Sandbox box;
  const auto scene = box.write("t.toml", kTinyScene);
  const std::string args =
      "compare " + scene.string() + " --frames 2 --out " + (box.dir / "cmp").string();
  ASSERT_EQ(run_sandflow(args), 0);
  std::string log;
  EXPECT_EQ(run_sandflow(args, &log), 2);
  EXPECT_NE(log.find("--force"), std::string::npos) << log;
  // the earlier dem/ and surface/ are replaced, not refused
  EXPECT_EQ(run_sandflow(args + " --force", &log), 0) << log;
  EXPECT_TRUE(fs::exists(box.dir / "cmp" / "compare.json"));
  EXPECT_TRUE(fs::exists(box.dir / "cmp" / "surface" / "stats.csv"));
}

TEST(Cli, CheckValidatesWithoutRunning) {
  Sandbox box;
  std::string log;
  EXPECT_EQ(run_sandflow(
                "run " + box.write("t.toml", kTinyScene).string() + " --check --grains 300", &log),
            0);
  EXPECT_NE(log.find("300 grains"), std::string::npos) << log;
  // a time step above the stable bound is refused with the bound
  EXPECT_EQ(run_sandflow("run " + box.write("t2.toml", kTinyScene).string() +
                             " --check --set simulation.dt=0.01",
                         &log),
            2);
  EXPECT_NE(log.find("stable bound"), std::string::npos) << log;
}

TEST(Cli, AnOverlapPastTheImpactLimitIsNamedWithTheSpeedThatHoldsIt) {
  // 20 grains poured from 0.3 m land at 2.4 m/s: sized for that, they stay under 10 % of a
  // diameter; sized for 1 m/s they reach 19 %, and the run names the frame and an impact speed
  // whose spring holds them under 10 % again
  Sandbox box;
  const auto scene =
      box.write("landing.toml",
                sandflow_test::tiny_pour_scene(
                    20, 0.3, 100, "", "[stiffness]\nfrom_load = true\nimpact_overlap = 0.1\n"));
  const auto out = box.dir / "out";
  const std::string run = "run " + scene.string() + " --mode dem --frames 12 --force --out " +
                          out.string() + " --export none";
  std::string log;
  ASSERT_EQ(run_sandflow(run, &log), 0) << log;
  EXPECT_EQ(log.find("passed stiffness.impact_overlap"), std::string::npos) << log;

  ASSERT_EQ(run_sandflow(run + " --set stiffness.impact_speed=1", &log), 0) << log;
  const auto summary = nlohmann::json::parse(std::ifstream(out / "summary.json"));
  const double reached = summary["max_overlap_rel"].get<double>();
  EXPECT_GT(reached, 0.1);
  const std::string named = fmt::format(
      "{:.1f} % of a diameter in frame {}, passed "
      "stiffness.impact_overlap = 10 %",
      100 * reached, summary["max_overlap_frame"].get<int>());
  EXPECT_NE(log.find("warning: the largest overlap, " + named), std::string::npos) << log;
  const std::string key = "set stiffness.impact_speed = ";
  const std::size_t at = log.find(key);
  ASSERT_NE(at, std::string::npos) << log;
  const std::string speed =
      log.substr(at + key.size(), log.find(' ', at + key.size()) - at - key.size());
  ASSERT_EQ(run_sandflow(run + " --set stiffness.impact_speed=" + speed, &log), 0) << log;
  EXPECT_LE(
      nlohmann::json::parse(std::ifstream(out / "summary.json"))["max_overlap_rel"].get<double>(),
      0.1);
  EXPECT_EQ(log.find("passed stiffness.impact_overlap"), std::string::npos) << log;
}

// A pour thrown sideways that cannot fall as a stream says so when the run starts (and with
// --check), naming the spacing that would let it; summary.json records each pour's stream_lead.
TEST(Cli, APourThatFallsAsDiscsSaysSoAndTheSummaryRecordsItsLead) {
  Sandbox box;
  auto scene = [&](const char* name, const char* velocity, double spacing) {
    return box
        .write(name,
               sandflow_test::tiny_pour_scene(
                   60, 0.1, 400, fmt::format("spacing = {}\nvelocity = {}", spacing, velocity)))
        .string();
  };
  std::string log;
  const std::string slanted = scene("slanted.toml", "[0.5, 0, -1]", 1.05);
  ASSERT_EQ(run_sandflow("run " + slanted + " --check", &log), 0) << log;
  EXPECT_NE(log.find("warning: " + slanted), std::string::npos) << log;
  EXPECT_NE(log.find("falls as discs"), std::string::npos) << log;
  EXPECT_NE(log.find("lets it fall as a stream"), std::string::npos) << log;
  EXPECT_NE(log.find("facing = \"velocity\" turns its area across its throw"), std::string::npos)
      << log;
  const auto out = box.dir / "out";
  ASSERT_EQ(run_sandflow("run " + slanted + " --mode dem --frames 2 --out " + out.string(), &log),
            0)
      << log;
  EXPECT_NE(log.find("falls as discs"), std::string::npos) << log;
  const auto summary = nlohmann::json::parse(std::ifstream(out / "summary.json"));
  EXPECT_EQ(summary["emitters"][0]["stream_lead"], 0.0);
  // straight down: a whole stream, and nothing said
  const std::string straight = scene("straight.toml", "[0, 0, -1]", 1.05);
  const auto out2 = box.dir / "out2";
  ASSERT_EQ(run_sandflow("run " + straight + " --mode dem --frames 2 --out " + out2.string(), &log),
            0)
      << log;
  EXPECT_EQ(log.find("off the vertical"), std::string::npos) << log;
  EXPECT_EQ(
      nlohmann::json::parse(std::ifstream(out2 / "summary.json"))["emitters"][0]["stream_lead"],
      1.0);
  // the slanted pour as a nozzle: its batches one behind the other along the throw, nothing said
  const std::string nozzle = scene("nozzle.toml", "[0.5, 0, -1]", 1.05);
  std::ofstream(nozzle, std::ios::app) << "facing = \"velocity\"\n";
  const auto out3 = box.dir / "out3";
  ASSERT_EQ(run_sandflow("run " + nozzle + " --mode dem --frames 2 --out " + out3.string(), &log),
            0)
      << log;
  EXPECT_EQ(log.find("off the vertical"), std::string::npos) << log;
  const auto emitter3 = nlohmann::json::parse(std::ifstream(out3 / "summary.json"))["emitters"][0];
  EXPECT_EQ(emitter3["facing"], "velocity");
  EXPECT_GT(emitter3["emitted"].get<int>(), 0);
}

}  // namespace
