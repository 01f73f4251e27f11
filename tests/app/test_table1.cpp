// `sandflow table1` end to end: the CSV's exact header and its row, the Markdown's reference
// figures, scenes skipped or failed, and the options it refuses. Every run is tiny (about a
// thousand grains of the floor scene, a few frames) so each test takes well under a second.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "cli_runner.hpp"

namespace fs = std::filesystem;

namespace {

using sandflow_test::read_text;
using sandflow_test::run_sandflow;
using sandflow_test::Sandbox;

const fs::path kScenes = fs::path(SANDFLOW_SOURCE_DIR) / "scenes";
const std::string kHeader =
    "scene,total,emitted,surface_simulated_mean,surface_s_per_frame,dem_simulated_mean,dem_s_per_"
    "frame,"
    "speedup,surface_rms_rel,grains_inside_geometry,max_overlap_surface_rel,impact_overlap,"
    "energy_added_by_waking_j";

std::vector<std::string> lines(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) out.push_back(line);
  return out;
}

std::vector<std::string> fields(const std::string& line) {
  std::vector<std::string> out;
  std::istringstream in(line);
  for (std::string f; std::getline(in, f, ',');) out.push_back(f);
  return out;
}

/// A scene folder holding a copy of the repository's floor scene (and nothing else).
fs::path floor_only(const Sandbox& box) {
  const fs::path dir = box.dir / "scenes";
  fs::create_directories(dir);
  fs::copy_file(kScenes / "floor.toml", dir / "floor.toml");
  return dir;
}

TEST(Table1, TinyFloorRowHasTheHeaderAndFiniteFigures) {
  Sandbox box;
  const fs::path out = box.dir / "t1";
  std::string log;
  ASSERT_EQ(run_sandflow("table1 --scale 0.01 --frames 3 --scenes floor --scene-dir " +
                             kScenes.string() + " --out " + out.string(),
                         &log),
            0)
      << log;
  const auto csv = lines(read_text(out / "table1.csv"));
  ASSERT_EQ(csv.size(), 2u) << read_text(out / "table1.csv");
  EXPECT_EQ(csv[0], kHeader);
  const auto names = fields(csv[0]);
  const auto f = fields(csv[1]);
  ASSERT_EQ(f.size(), names.size()) << csv[1];
  const auto at = [&](const std::string& name) {
    const auto k = std::find(names.begin(), names.end(), name) - names.begin();
    return f.at(static_cast<std::size_t>(k));
  };
  EXPECT_EQ(at("scene"), "floor");
  // round(F x the paper's 107,687 grains), and those poured in 3 frames
  EXPECT_EQ(std::stoll(at("total")), std::llround(0.01 * 107687));
  const auto j = nlohmann::json::parse(read_text(out / "floor" / "compare.json"));
  EXPECT_EQ(std::stoll(at("emitted")), j["n_total"].get<std::int64_t>());
  EXPECT_LT(std::stoll(at("emitted")), std::stoll(at("total")));
  // simulated means, seconds per frame and the speed-up must be positive
  for (const char* name : {"surface_simulated_mean", "surface_s_per_frame", "dem_simulated_mean",
                           "dem_s_per_frame", "speedup"}) {
    const double v = std::stod(at(name));
    EXPECT_TRUE(std::isfinite(v) && v > 0) << name << "\n" << kHeader << "\n" << csv[1];
  }
  // the surfaces' distance: none while no grain has reached the floor (null in compare.json),
  // else not negative
  if (j["surface_rms_rel"].is_null()) {
    EXPECT_EQ(at("surface_rms_rel"), "nan") << csv[1];
  } else {
    const double rms_rel = std::stod(at("surface_rms_rel"));
    EXPECT_TRUE(std::isfinite(rms_rel) && rms_rel >= 0) << csv[1];
  }
  EXPECT_EQ(std::stoll(at("grains_inside_geometry")), 0) << "grains inside the floor";
  // plain DEM simulates every grain present, so never fewer than the surface flow
  EXPECT_GE(std::stod(at("dem_simulated_mean")), std::stod(at("surface_simulated_mean")));
  // the surface runs' largest overlap beside the scene's limit, and the energy waking added
  EXPECT_NEAR(std::stod(at("max_overlap_surface_rel")), j["max_overlap_surface_rel"].get<double>(),
              1e-5);
  EXPECT_DOUBLE_EQ(std::stod(at("impact_overlap")), 0.25);  // the floor's stiffness.impact_overlap
  EXPECT_GE(std::stod(at("energy_added_by_waking_j")), 0.0);

  // the scene's comparison, as `compare` writes it
  const double speedup = j["speedup"].get<double>();
  EXPECT_NEAR(std::stod(at("speedup")), speedup, 1e-5 * speedup);  // the CSV keeps 6 digits
  EXPECT_TRUE(fs::exists(out / "floor" / "dem" / "summary.json"));
  EXPECT_TRUE(fs::exists(out / "floor" / "surface" / "summary.json"));

  // the Markdown: the row, the command and the paper's Table 1 (Zhu & Yang 2010) for reference
  const std::string md = read_text(out / "table1.md");
  EXPECT_NE(md.find("| floor | 1,077"), std::string::npos) << md;
  EXPECT_NE(md.find("table1 --scale 0.01 --frames 3"), std::string::npos) << md;
  EXPECT_NE(md.find("paper's hardware"), std::string::npos) << md;
  for (const char* figures : {"Floor 107,687 grains in total, 28,410 simulated, 8.62 s/frame",
                              "Terrain 199,039 grains in total, 48,423 simulated, 18.27 s/frame",
                              "Bowl 318,053 grains in total, 24,710 simulated, 11.01 s/frame",
                              "Dragon 192,975 grains in total, 40,043 simulated, 30.05 s/frame",
                              "Armadillo 207,020 grains in total, 58,540 simulated, 21.54 s/frame"})
    EXPECT_NE(md.find(figures), std::string::npos) << figures << "\n" << md;

  // progress names the scene, the mode and the scene's place in the run
  for (const char* s : {"scene 1 of 1: floor [surface]", "scene 1 of 1: floor [dem]"})
    EXPECT_NE(log.find(s), std::string::npos) << s << "\n" << log;

  // a second run into the same folder needs --force
  EXPECT_EQ(
      run_sandflow("table1 --scale 0.002 --frames 1 --scenes floor --out " + out.string(), &log),
      2);
  EXPECT_NE(log.find("--force"), std::string::npos) << log;
  EXPECT_EQ(
      run_sandflow("table1 --scale 0.002 --frames 1 --scenes floor --force --out " + out.string(),
                   &log),
      0)
      << log;
  EXPECT_EQ(fields(lines(read_text(out / "table1.csv"))[1])[1],
            std::to_string(std::llround(0.002 * 107687)));
}

TEST(Table1, ResumeKeepsWhatRanAndRefusesOtherOptions) {
  Sandbox box;
  const fs::path out = box.dir / "t1";
  const std::string cmd = "table1 --scale 0.002 --frames 2 --scenes floor --out " + out.string();
  std::string log;
  ASSERT_EQ(run_sandflow(cmd, &log), 0) << log;
  const auto first = nlohmann::json::parse(read_text(out / "floor" / "compare.json"));
  // the same table goes on: both runs are read back from their last checkpoints, not run again
  ASSERT_EQ(run_sandflow(cmd + " --resume", &log), 0) << log;
  for (const char* mode : {"surface", "dem"})
    EXPECT_NE(log.find((out / "floor" / mode).string() +
                       " is finished: reading it back from its checkpoint at frame 2"),
              std::string::npos)
        << log;
  const auto again = nlohmann::json::parse(read_text(out / "floor" / "compare.json"));
  EXPECT_EQ(again["speedup"], first["speedup"]);  // the frames' own times, summed again
  EXPECT_EQ(again["surface_rms_rel"], first["surface_rms_rel"]);
  // other options are not this table: refused before anything is written
  const std::string table = read_text(out / "table1.csv");
  EXPECT_EQ(
      run_sandflow("table1 --scale 0.002 --frames 3 --scenes floor --resume --out " + out.string(),
                   &log),
      2);
  EXPECT_NE(log.find("holds a run started otherwise"), std::string::npos) << log;
  EXPECT_EQ(read_text(out / "table1.csv"), table);
  EXPECT_EQ(nlohmann::json::parse(read_text(out / "floor" / "surface" / "summary.json"))["frames"],
            2);
  EXPECT_EQ(run_sandflow(cmd + " --resume --force", &log), 2);
  EXPECT_NE(log.find("give one of them"), std::string::npos) << log;
}

TEST(Table1, MissingSceneIsSkippedAndTheOthersRun) {
  Sandbox box;
  const fs::path scenes = floor_only(box), out = box.dir / "t1";
  std::string log;
  ASSERT_EQ(run_sandflow("table1 --scale 0.005 --frames 2 --scenes floor,terrain --scene-dir " +
                             scenes.string() + " --out " + out.string(),
                         &log),
            0)
      << log;
  EXPECT_NE(log.find("terrain skipped: no scene file"), std::string::npos) << log;
  const std::string md = read_text(out / "table1.md");
  EXPECT_NE(md.find("| terrain | missing |"), std::string::npos) << md;
  EXPECT_NE(md.find("terrain: skipped: no scene file"), std::string::npos) << md;
  // the CSV holds the scenes that ran
  const auto csv = lines(read_text(out / "table1.csv"));
  ASSERT_EQ(csv.size(), 2u);
  EXPECT_EQ(fields(csv[1])[0], "floor");
  EXPECT_FALSE(fs::exists(out / "terrain"));

  // when no scene file is found at all, nothing ran: an error
  EXPECT_EQ(run_sandflow("table1 --scale 0.005 --frames 2 --scenes terrain,bowl --scene-dir " +
                             scenes.string() + " --out " + (box.dir / "none").string(),
                         &log),
            2);
  EXPECT_NE(log.find("no scene ran"), std::string::npos) << log;
}

TEST(Table1, FailedSceneIsReportedAndTheOthersStillRun) {
  Sandbox box;
  const fs::path scenes = floor_only(box), out = box.dir / "t1";
  // a terrain scene with an out-of-range value fails when it is loaded
  std::string text = read_text(scenes / "floor.toml");
  const std::string good = "restitution = 0.3";
  ASSERT_NE(text.find(good), std::string::npos);
  text.replace(text.find(good), good.size(), "restitution = 1.4");
  std::ofstream(scenes / "terrain.toml") << text;
  std::string log;
  // terrain first: floor still runs after it fails; the status is that of bad input
  EXPECT_EQ(run_sandflow("table1 --scale 0.005 --frames 2 --scenes terrain,floor --scene-dir " +
                             scenes.string() + " --out " + out.string(),
                         &log),
            2)
      << log;
  EXPECT_NE(log.find("terrain failed:"), std::string::npos) << log;
  const std::string md = read_text(out / "table1.md");
  EXPECT_NE(md.find("| terrain | failed |"), std::string::npos) << md;
  EXPECT_NE(md.find("material.restitution"), std::string::npos) << md;
  const auto csv = lines(read_text(out / "table1.csv"));
  ASSERT_EQ(csv.size(), 2u);
  EXPECT_EQ(fields(csv[1])[0], "floor");
}

TEST(Table1, BadScaleIsRefusedBeforeAnythingIsWritten) {
  Sandbox box;
  const fs::path out = box.dir / "t1";
  for (const char* scale : {"0", "-0.5", "nan", "inf", "1000", "1e-9"}) {
    std::string log;
    EXPECT_EQ(
        run_sandflow(
            std::string("table1 --scenes floor --scale ") + scale + " --out " + out.string(), &log),
        2)
        << scale << ": " << log;
    EXPECT_NE(log.find("--scale"), std::string::npos) << scale << ": " << log;
    EXPECT_FALSE(fs::exists(out)) << scale;
  }
}

TEST(Table1, UnknownSceneIsRefusedNamingTheKnownOnes) {
  Sandbox box;
  const fs::path out = box.dir / "t1";
  std::string log;
  EXPECT_EQ(run_sandflow("table1 --scenes floor,nosuch --out " + out.string(), &log), 2);
  EXPECT_NE(log.find("'nosuch'"), std::string::npos) << log;
  EXPECT_NE(log.find("floor, terrain, bowl, dragon, armadillo"), std::string::npos) << log;
  EXPECT_FALSE(fs::exists(out));
  EXPECT_EQ(run_sandflow("table1 --scenes floor,floor --out " + out.string(), &log), 2);
  EXPECT_NE(log.find("listed twice"), std::string::npos) << log;
}

}  // namespace
