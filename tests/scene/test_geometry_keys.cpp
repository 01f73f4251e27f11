// Scene keys of the bowl and the heightmap: each key is read, each error names file, line and key.
// PNG heightmaps are written by the test itself (no binary files in the repository).
#include <gtest/gtest.h>
#include <png.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "geometry/heightmap.hpp"
#include "io/png_gray.hpp"
#include "scene/scene_loader.hpp"
#include "support/scene_errors.hpp"
#include "support/scratch.hpp"

namespace sandflow {
namespace {

namespace fs = std::filesystem;

constexpr const char* kEmitterLines = "[[emitter]]\ncount = 10\n";  // lines 1-2

using test::error_of;
using test::expect_error;

using TempDir = test::ScratchFolder;

TEST(GeometryKeys, BowlReadsEveryKey) {
  const SceneConfig c = load_scene_from_string(std::string(kEmitterLines) +
                                                   "[[geometry]]\n"
                                                   "type = \"bowl\"\n"
                                                   "center = [1, 2, 3]\n"
                                                   "radius = 0.3\n"
                                                   "wall_thickness = 0.01\n"
                                                   "depth = 0.2\n"
                                                   "rotation = [10, 0, 0]\n",
                                               "t.toml");
  const GeometryConfig& g = c.geometry.at(0);
  EXPECT_EQ(g.type, GeometryType::Bowl);
  EXPECT_EQ(g.center, Vec3(1, 2, 3));
  EXPECT_EQ(g.radius, 0.3);
  EXPECT_EQ(g.wall_thickness, 0.01);
  EXPECT_EQ(g.depth, 0.2);
  EXPECT_EQ(g.rotation_deg, Vec3(10, 0, 0));
  // defaults: a hemisphere (depth unset = radius) with 2 cm walls
  const SceneConfig d = load_scene_from_string(
      std::string(kEmitterLines) + "[[geometry]]\ntype = \"bowl\"\n", "t.toml");
  EXPECT_FALSE(d.geometry[0].depth.has_value());
  EXPECT_EQ(d.geometry[0].wall_thickness, 0.02);
}

TEST(GeometryKeys, BowlErrors) {
  const std::string head =
      std::string(kEmitterLines) + "[[geometry]]\ntype = \"bowl\"\nradius = 0.2\n";
  expect_error(head + "depth = 0.4\n",
               {"t.toml:6:1: geometry[0].depth = 0.4 is not below 2 * radius = 0.4"});
  expect_error(head + "depth = 0\n", {"t.toml:6:1: geometry[0].depth = 0 is not > 0"});
  expect_error(head + "wall_thickness = -1\n", {"t.toml:6:1: geometry[0].wall_thickness = -1"});
  expect_error(head + "height = 1\n",
               {"t.toml:6:1: geometry[0].height is not a key of a bowl", "depth"});
}

TEST(GeometryKeys, HeightmapInlineHeights) {
  const SceneConfig c = load_scene_from_string(std::string(kEmitterLines) +
                                                   "[[geometry]]\n"
                                                   "type = \"heightmap\"\n"
                                                   "extent = [0, 0, 2, 1]\n"
                                                   "base_thickness = 0.1\n"
                                                   "heights = [[0, 1, 2], [3, 4, 5]]\n",
                                               "t.toml");
  const GeometryConfig& g = c.geometry.at(0);
  EXPECT_EQ(g.type, GeometryType::Heightmap);
  EXPECT_EQ(g.height_source, HeightSource::Inline);
  EXPECT_EQ(g.extent, (std::array<Real, 4>{0, 0, 2, 1}));
  EXPECT_EQ(g.base_thickness, 0.1);
  EXPECT_EQ(g.heights.nx, 3);  // a row runs along x
  EXPECT_EQ(g.heights.ny, 2);
  EXPECT_EQ(g.heights.z, (std::vector<Real>{0, 1, 2, 3, 4, 5}));
}

TEST(GeometryKeys, HeightmapErrors) {
  const std::string head =
      std::string(kEmitterLines) + "[[geometry]]\ntype = \"heightmap\"\nextent = [0, 0, 1, 1]\n";
  expect_error(head + "heights = [[0, 1, 2], [3, 4]]\n",
               {"t.toml:6:23: geometry[0].heights[1] has 2 values but geometry[0].heights[0] has 3",
                "same length"});
  expect_error(head + "heights = [[0, 1], [3, nan]]\n",
               {"t.toml:6:24: geometry[0].heights[1][1] = nan is not a finite number"});
  expect_error(head + "heights = [[0, 1]]\n",
               {"t.toml:6:1: geometry[0].heights has 1 rows: expected 2 to 4096"});
  expect_error(head + "heights = [[0], [1]]\n", {"geometry[0].heights[0] has 1 values"});
  expect_error(head + "heights = [[0, 1], \"x\"]\n",
               {"geometry[0].heights[1]: expected a row of numbers, got a string"});
  std::string huge = head + "heights = [";
  for (int j = 0; j < 4097; ++j) huge += "[0, 0],";
  huge += "]\n";
  expect_error(huge, {"t.toml:6:1: geometry[0].heights has 4097 rows: expected 2 to 4096"});
  expect_error(head, {"t.toml:5:1: geometry[0].heights: a heightmap takes exactly one of "
                      "heights, file, noise, found none"});
  expect_error(head + "heights = [[0, 1], [2, 3]]\nfile = \"a.png\"\n",
               {"t.toml:7:1: geometry[0].file: a heightmap takes exactly one of", "heights and file"});
  expect_error(head + "heights = [[0, 1], [2, 3]]\nz_min = 1\n",
               {"t.toml:7:1: geometry[0].z_min is not a key of a heightmap with heights"});
  expect_error(std::string(kEmitterLines) +
                   "[[geometry]]\ntype = \"heightmap\"\nheights = [[0, 1], [2, 3]]\n",
               {"t.toml:3:1: geometry[0].extent is missing: expected [x0, y0, x1, y1]"});
  expect_error(
      std::string(kEmitterLines) +
          "[[geometry]]\ntype = \"heightmap\"\nextent = [1, 0, 0, 1]\nheights = [[0, 1], [2, 3]]\n",
      {"t.toml:5:1: geometry[0].extent = [1, 0, 0, 1]: expected [x0, y0, x1, y1] with x1 > x0"});
  expect_error(head + "noise = { wavelength = 0.1, amp = 2 }\n",
               {"t.toml:6:29: geometry[0].noise.amp is not a key of a heightmap's noise"});
  expect_error(head + "noise = { wavelength = 0.1 }\nz_min = 1\nz_max = 0.5\n",
               {"t.toml:8:1: geometry[0].z_max = 0.5 is not above geometry[0].z_min = 1"});
}

TEST(GeometryKeys, HeightmapNoise) {
  const SceneConfig c = load_scene_from_string(std::string(kEmitterLines) +
                                                   "[[geometry]]\n"
                                                   "type = \"heightmap\"\n"
                                                   "extent = [0, 0, 0.4, 0.3]\n"
                                                   "noise = { wavelength = 0.1, seed = 3 }\n"
                                                   "z_min = 0.01\n"
                                                   "z_max = 0.04\n",
                                               "t.toml");
  const GeometryConfig& g = c.geometry.at(0);
  EXPECT_EQ(g.height_source, HeightSource::Noise);
  EXPECT_EQ(g.noise_wavelength, 0.1);
  EXPECT_EQ(g.noise_seed, 3u);
  EXPECT_EQ(g.heights.z, noise_heights(g.extent, 0.1, 3, 0.01, 0.04).z);
}

TEST(GeometryKeys, HeightmapFromPngRelativeToTheScene) {
  const TempDir tmp;
  // 3 x 2 pixels; the top image row is the far edge y = y1
  const std::vector<double> grey{0.0, 0.5, 1.0,   // top row
                                 0.25, 0.75, 1.0};
  for (int bits : {8, 16}) {
    write_gray_png(tmp.path("h.png"), 3, 2, grey, bits);
    const std::string scene = tmp.write("s.toml", std::string(kEmitterLines) +
                                                      "[[geometry]]\n"
                                                      "type = \"heightmap\"\n"
                                                      "extent = [0, 0, 2, 1]\n"
                                                      "file = \"h.png\"\n"
                                                      "z_min = 1\n"
                                                      "z_max = 3\n");
    const SceneConfig c = load_scene(scene);
    const GeometryConfig& g = c.geometry.at(0);
    EXPECT_EQ(g.height_source, HeightSource::File);
    ASSERT_EQ(g.heights.nx, 3);
    ASSERT_EQ(g.heights.ny, 2);
    // row j = 0 (y = y0) is the bottom image row; z = z_min + grey (z_max - z_min), to 1/255
    const std::vector<Real> want{1.5, 2.5, 3.0, 1.0, 2.0, 3.0};
    for (std::size_t k = 0; k < want.size(); ++k)
      EXPECT_NEAR(g.heights.z[k], want[k], bits == 8 ? 2.0 / 255 : 2.0 / 65535) << bits;
  }
}

TEST(GeometryKeys, HeightmapFileErrors) {
  const TempDir tmp;
  const auto scene = [&](const std::string& file) {
    return tmp.write("s.toml", std::string(kEmitterLines) +
                                   "[[geometry]]\n"
                                   "type = \"heightmap\"\n"
                                   "extent = [0, 0, 1, 1]\n"
                                   "file = \"" +
                                   file + "\"\n");
  };
  const auto error_loading = [](const std::string& path) {
    try {
      load_scene(path);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  const std::string place = tmp.path("s.toml") + ":6:1: geometry[0].file = ";
  // missing
  std::string msg = error_loading(scene("none.png"));
  EXPECT_NE(msg.find(place + "\"none.png\": " + tmp.path("none.png") + ": cannot open the image"),
            std::string::npos)
      << msg;
  // not a PNG
  tmp.write("text.png", "hello");
  msg = error_loading(scene("text.png"));
  EXPECT_NE(msg.find("text.png: byte 0: not a PNG image"), std::string::npos) << msg;
  // colour
  {
    png_image img{};
    img.version = PNG_IMAGE_VERSION;
    img.width = 2;
    img.height = 2;
    img.format = PNG_FORMAT_RGB;
    const std::vector<unsigned char> rgb(12, 128);
    ASSERT_TRUE(png_image_write_to_file(&img, tmp.path("rgb.png").c_str(), 0, rgb.data(), 0, nullptr));
  }
  msg = error_loading(scene("rgb.png"));
  EXPECT_NE(msg.find("rgb.png: byte 25: a colour PNG (RGB): a heightmap must be a grey-scale PNG"),
            std::string::npos)
      << msg;
  // too large: refused from its header
  write_gray_png(tmp.path("wide.png"), 4097, 2, std::vector<double>(2 * 4097, 0.5), 8);
  msg = error_loading(scene("wide.png"));
  EXPECT_NE(msg.find("wide.png: byte 16: the image is 4097 x 2 pixels: at most 4096 x 4096"),
            std::string::npos)
      << msg;
  // too small
  write_gray_png(tmp.path("line.png"), 5, 1, std::vector<double>(5, 0.5), 8);
  msg = error_loading(scene("line.png"));
  EXPECT_NE(msg.find("is 5 x 1 pixels: a heightmap needs at least 2 x 2"), std::string::npos) << msg;
}

TEST(GeometryKeys, RemoveAtIsReadForSolidsAndRefusedForMeshes) {
  const SceneConfig c = load_scene_from_string(
      std::string(kEmitterLines) +
          "[[geometry]]\ntype = \"cylinder\"\ncontainer = true\nremove_at = 1.5\n",
      "t.toml");
  ASSERT_TRUE(c.geometry.at(0).remove_at.has_value());
  EXPECT_EQ(*c.geometry[0].remove_at, 1.5);
  const SceneConfig none = load_scene_from_string(
      std::string(kEmitterLines) + "[[geometry]]\ntype = \"plane\"\n", "t.toml");
  EXPECT_FALSE(none.geometry.at(0).remove_at.has_value());
  expect_error(std::string(kEmitterLines) + "[[geometry]]\ntype = \"box\"\nremove_at = -1\n",
               {"t.toml:5:1: geometry[0].remove_at = -1"});
  expect_error(std::string(kEmitterLines) +
                   "[[geometry]]\ntype = \"mesh\"\nfile = \"m.obj\"\nremove_at = 1\n",
               {"t.toml:", "geometry[0].remove_at", "a mesh cannot be removed"});
}

}  // namespace
}  // namespace sandflow
