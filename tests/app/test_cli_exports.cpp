// `--export` and `--up-axis` end to end: which files a run writes for each choice, in both modes,
// and what is refused.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include <nlohmann/json.hpp>

#include "cli_runner.hpp"
#include "io/ply.hpp"
#include "io/png_gray.hpp"
#include "support/houdini_geo.hpp"
#include "support/xml_tags.hpp"

namespace fs = std::filesystem;

namespace {

using sandflow_test::read_text;
using sandflow_test::run_sandflow;
using sandflow_test::Sandbox;

// 200 grains settling on a floor: a fraction of a second a run.
const std::string kExportScene = sandflow_test::tiny_block_scene(200);

std::string frame(int n, const char* ext) {
  char buf[16];
  std::snprintf(buf, sizeof buf, "%04d%s", n, ext);
  return buf;
}

TEST(CliExports, EveryFormatForEveryFrame) {
  Sandbox box;
  const auto scene = box.write("tiny.toml", kExportScene);
  const auto out = box.dir / "out";
  std::string log;
  ASSERT_EQ(
      run_sandflow("run " + scene.string() +
                       " --frames 3 --export ply,vtk,geo,geo_gz,pov,csv --out " + out.string(),
                   &log),
      0)
      << log;
  for (int n = 1; n <= 3; ++n)
    for (const char* ext : {".ply", ".vtk", ".vtp", ".pov", ".csv"})
      EXPECT_TRUE(fs::exists(out / "frames" / frame(n, ext))) << frame(n, ext);
  EXPECT_TRUE(fs::exists(out / "frames" / "pov_scene.inc"));
  // Houdini's frames: sand.0001 at the start (t = 0) to sand.0004 at t = 3 / fps, each the
  // other exports' frame one lower; plain and gzipped, the same geometry
  for (int n = 1; n <= 4; ++n) {
    const std::string geo = "sand." + frame(n, ".geo");
    const std::string plain = read_text(out / "frames" / geo);
    const auto g = sandflow::test::parse_geo(plain);
    EXPECT_EQ(sandflow::test::gunzip(read_text(out / "frames" / (geo + ".gz"))), plain) << geo;
    if (n == 1) {
      EXPECT_TRUE(g.points.empty()) << geo;  // the block's grains appear in the first step
      continue;
    }
    const auto ply = sandflow::read_ply((out / "frames" / frame(n - 1, ".ply")).string());
    ASSERT_EQ(g.points.size(), ply.size()) << geo;
    ASSERT_GT(ply.size(), 0u);
    for (std::size_t i = 0; i < ply.size(); ++i)
      for (int c = 0; c < 3; ++c) ASSERT_EQ(g.points[i].P[c], ply.position[i][c]) << geo;
  }
  for (const char* missing : {"sand.0000.geo", "sand.0005.geo", "sand.0005.geo.gz", "0001.geo"})
    EXPECT_FALSE(fs::exists(out / "frames" / missing)) << missing;
  // the series lists the three frames with their times (fps 30)
  const std::string pvd = read_text(out / "frames.pvd");
  int k = 0;
  for (const auto& set : sandflow::test::xml_tags(pvd, "DataSet")) {
    ++k;
    EXPECT_NEAR(std::stod(set.at("timestep")), k / 30.0, 1e-12);
    EXPECT_EQ(set.at("file"), "frames/" + frame(k, ".vtp"));
  }
  EXPECT_EQ(k, 3);
  // the height field was not asked for
  EXPECT_FALSE(fs::exists(out / "heightfield"));
  const auto summary = nlohmann::json::parse(std::ifstream(out / "summary.json"));
  EXPECT_EQ(summary["exports"]["formats"],
            nlohmann::json({"ply", "vtk", "geo", "geo_gz", "pov", "csv"}));
  // no temporary file is left behind
  for (const auto& e : fs::recursive_directory_iterator(out))
    EXPECT_NE(e.path().extension(), ".tmp") << e.path();
}

TEST(CliExports, SurfaceModeWritesTheHeightFieldByDefaultAndDemSkipsIt) {
  Sandbox box;
  const auto scene = box.write("tiny.toml", kExportScene);
  std::string log;
  const auto surf = box.dir / "surf";
  ASSERT_EQ(run_sandflow("run " + scene.string() + " --frames 10 --out " + surf.string(), &log), 0)
      << log;
  for (const char* f : {"H_0001.png", "h_0001.png", "H_0010.png", "h_0010.png", "heightfield.json"})
    EXPECT_TRUE(fs::exists(surf / "heightfield" / f)) << f;
  EXPECT_FALSE(fs::exists(surf / "heightfield" / "H_0001.obj"));  // height_obj is not a default
  // The heights decoded with the sidecar's range: bare floor (z = 0) at a corner; in the middle,
  // the top of the grains settled there (final_grains.ply: the same state) as the height field's
  // thick ray (radius cell/2) meets them, within 0.1 mm (the grains move that little, if at all,
  // after the last height-field update of the frame; the 16-bit step is 2 um here).
  const auto side = nlohmann::json::parse(std::ifstream(surf / "heightfield" / "heightfield.json"));
  const double z0 = side["png"]["z_min"], z1 = side["png"]["z_max"], cell = side["cell_size"];
  const int nx = side["nx"], ny = side["ny"];
  const sandflow::GrayImage img =
      sandflow::read_gray_png((surf / "heightfield" / "H_0010.png").string(), 4096);
  ASSERT_EQ(img.width, nx);
  ASSERT_EQ(img.height, ny);
  const auto height = [&](int i, int j) {  // image row 0 holds the highest y
    return z0 + img.value[static_cast<std::size_t>(ny - 1 - j) * nx + i] * (z1 - z0);
  };
  EXPECT_NEAR(height(0, 0), 0.0, 1e-4);
  const int i = nx / 2, j = ny / 2;
  const double cx = side["origin"][0].get<double>() + (i + 0.5) * cell;
  const double cy = side["origin"][1].get<double>() + (j + 0.5) * cell;
  const auto grains = sandflow::read_ply((surf / "final_grains.ply").string());
  double top = 0;
  for (std::size_t k = 0; k < grains.size(); ++k) {
    const double r = grains.radius[k];
    const double e = std::hypot(grains.position[k].x - cx, grains.position[k].y - cy) - 0.5 * cell;
    if (e < r) top = std::max(top, grains.position[k].z + (e <= 0 ? r : std::sqrt(r * r - e * e)));
  }
  EXPECT_GT(top, 0.015);  // at least two layers of the block
  EXPECT_NEAR(height(i, j), top, 1e-4);

  // plain DEM: the default has no height field; asking for it warns and writes none
  const auto dem = box.dir / "dem";
  ASSERT_EQ(run_sandflow("run " + scene.string() +
                             " --mode dem --frames 1 --export ply,height --out " + dem.string(),
                         &log),
            0)
      << log;
  EXPECT_NE(log.find("warning:"), std::string::npos) << log;
  EXPECT_NE(log.find("height fields exist only in surface mode"), std::string::npos) << log;
  EXPECT_FALSE(fs::exists(dem / "heightfield"));
  EXPECT_TRUE(fs::exists(dem / "frames" / "0001.ply"));
}

TEST(CliExports, UpAxisYRotatesFramesAndMeasureStillSeesTheSceneFrame) {
  Sandbox box;
  const auto scene = box.write("tiny.toml", kExportScene);
  std::string log_z, log_y;
  const auto z = box.dir / "z", y = box.dir / "y";
  ASSERT_EQ(
      run_sandflow("run " + scene.string() + " --mode dem --frames 2 --out " + z.string(), &log_z),
      0)
      << log_z;
  ASSERT_EQ(
      run_sandflow("run " + scene.string() +
                       " --mode dem --frames 2 --up-axis y --export ply,csv --out " + y.string(),
                   &log_y),
      0)
      << log_y;
  // the same run, written the other way up: read_ply gives the same grains back
  const auto fz = sandflow::read_ply((z / "frames" / "0002.ply").string());
  const auto fy = sandflow::read_ply((y / "frames" / "0002.ply").string());
  ASSERT_EQ(fz.size(), fy.size());
  for (std::size_t i = 0; i < fz.size(); ++i) EXPECT_EQ(fz.position[i], fy.position[i]) << i;
  // the CSV holds the rotated heights: y is the scene's z (above the floor), z its -y
  const std::string csv = read_text(y / "frames" / "0002.csv");
  const auto row = csv.substr(csv.find('\n') + 1);
  double id, cx, cy, cz;
  ASSERT_EQ(std::sscanf(row.c_str(), "%lf,%lf,%lf,%lf", &id, &cx, &cy, &cz), 4) << row;
  ASSERT_EQ(fz.id[0], static_cast<std::uint32_t>(id));
  EXPECT_NEAR(cy, fz.position[0].z, 1e-6);
  EXPECT_NEAR(cz, -fz.position[0].y, 1e-6);
  // measure reads the y-up frames as the scene's
  std::string mz, my;
  ASSERT_EQ(run_sandflow("measure " + z.string(), &mz), 0) << mz;
  ASSERT_EQ(run_sandflow("measure " + y.string(), &my), 0) << my;
  EXPECT_EQ(mz.substr(mz.find('\n')), my.substr(my.find('\n')));  // all but the file's name
}

TEST(CliExports, UnknownExportIsRefusedListingTheKnownOnesAndWritesNothing) {
  Sandbox box;
  const auto scene = box.write("tiny.toml", kExportScene);
  const auto out = box.dir / "out";
  std::string log;
  EXPECT_EQ(
      run_sandflow("run " + scene.string() + " --export ply,vtkk --out " + out.string(), &log), 2);
  EXPECT_NE(log.find("--export ply,vtkk: unknown export \"vtkk\""), std::string::npos) << log;
  EXPECT_NE(log.find("ply, vtk, geo, geo_gz, pov, csv, height, height_obj"), std::string::npos)
      << log;
  EXPECT_FALSE(fs::exists(out));
  EXPECT_EQ(run_sandflow("compare " + scene.string() + " --up-axis x --out " + out.string(), &log),
            2);
  EXPECT_NE(log.find("--up-axis"), std::string::npos) << log;
  EXPECT_FALSE(fs::exists(out));
}

TEST(CliExports, CompareAppliesTheChoiceToBothRuns) {
  Sandbox box;
  const auto scene = box.write("tiny.toml", kExportScene);
  const auto out = box.dir / "cmp";
  std::string log;
  ASSERT_EQ(run_sandflow("compare " + scene.string() + " --frames 1 --export csv,height --out " +
                             out.string(),
                         &log),
            0)
      << log;
  for (const char* mode : {"surface", "dem"}) {
    EXPECT_TRUE(fs::exists(out / mode / "frames" / "0001.csv")) << mode;
    EXPECT_FALSE(fs::exists(out / mode / "frames" / "0001.ply")) << mode;
  }
  EXPECT_TRUE(fs::exists(out / "surface" / "heightfield" / "H_0001.png"));
  EXPECT_FALSE(fs::exists(out / "dem" / "heightfield"));
}

}  // namespace
