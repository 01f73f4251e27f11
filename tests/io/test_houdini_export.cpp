// The Houdini exports (`geo`, `geo_gz`): the frames are numbered on Houdini's time line (file N
// holds t = (N - 1) / fps, from the start of the run), the .geo.gz files are gzip data of the same
// geometry, orient is the identity and each grain's Cd is the colour `sandflow render` gives it,
// as linear light. Files are read back by the reader of tests/support/houdini_geo.hpp (zlib's
// gunzip and a parser written from the format's documentation).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "io/export_formats.hpp"
#include "io/frame_exporter.hpp"
#include "io/ply.hpp"
#include "io/pov_writer.hpp"
#include "scene/scene_loader.hpp"
#include "sim/world.hpp"
#include "support/houdini_geo.hpp"
#include "support/pov_grains.hpp"
#include "support/scratch.hpp"

namespace sandflow {
namespace {

namespace fs = std::filesystem;

using HoudiniTest = test::ScratchTest;
using test::read_bytes;

float as_float32(double v) {
  return static_cast<float>(v);
}

// n grains on a jittered lattice with distinct ids, radii and velocities.
FrameData lattice_frame(std::size_t n) {
  FrameData f;
  for (std::size_t i = 0; i < n; ++i) {
    const double j = std::sin(1.7 * static_cast<double>(i)) * 1e-4;
    f.position.push_back({0.01 * static_cast<double>(i % 20) + j,
                          0.01 * static_cast<double>(i / 20 % 20) - j,
                          0.005 + 0.01 * static_cast<double>(i / 400)});
    f.radius.push_back(0.005 * (1 + 0.1 * std::cos(static_cast<double>(i))));
    f.velocity.push_back({0.1 * j, -0.2, 0.3 * std::cos(static_cast<double>(i))});
    f.id.push_back(static_cast<std::uint32_t>(3 * i + 11));
    f.state.push_back(static_cast<std::uint8_t>(i % 2));
  }
  return f;
}

// ---- gzip
// -----------------------------------------------------------------------------------------

TEST_F(HoudiniTest, GeoGzIsGzipDataOfThePlainFile) {
  const FrameData f = lattice_frame(2000);
  write_houdini_geo(path("f.geo"), f, UpAxis::Z);
  write_houdini_geo(path("f.geo.gz"), f, UpAxis::Z);
  const std::string plain = read_bytes(path("f.geo")), gz = read_bytes(path("f.geo.gz"));
  ASSERT_GE(gz.size(), 18u);
  EXPECT_EQ(static_cast<unsigned char>(gz[0]), 0x1f);  // gzip's magic bytes (RFC 1952)
  EXPECT_EQ(static_cast<unsigned char>(gz[1]), 0x8b);
  EXPECT_EQ(test::gunzip(gz), plain);
  // compressed: 32 bytes a grain against 127 on these grains (docs/scenes.md gives a run's)
  EXPECT_LT(gz.size(), plain.size() / 2) << gz.size() << " against " << plain.size();
  const test::Geo g = test::parse_geo(test::gunzip(gz));
  ASSERT_EQ(g.points.size(), f.size());
  ASSERT_EQ(g.part.size(), f.size());
  for (std::size_t i = 0; i < f.size(); ++i) {
    const test::GeoPoint& p = g.points[i];
    EXPECT_EQ(g.part[i], i);
    for (int c = 0; c < 3; ++c) EXPECT_EQ(p.P[c], as_float32(f.position[i][c])) << i;
    EXPECT_EQ(as_float32(p.attr.at("pscale")[0]), as_float32(f.radius[i])) << i;
    EXPECT_EQ(p.attr.at("id")[0], f.id[i]);
    EXPECT_EQ(p.attr.at("Cd").size(), 3u);
    EXPECT_EQ(p.attr.at("orient").size(), 4u);
  }
  for (const auto& e : fs::directory_iterator(dir_)) EXPECT_NE(e.path().extension(), ".tmp");
}

TEST_F(HoudiniTest, AnUnwritableGeoGzNamesItsPath) {
  const std::string bad = path("no_such_folder/f.geo.gz");
  try {
    write_houdini_geo(bad, lattice_frame(10), UpAxis::Z);
    ADD_FAILURE() << "no error";
  } catch (const OutputError& e) {
    EXPECT_EQ(std::string(e.what()).rfind(bad + ":", 0), 0u) << e.what();
  }
}

// ---- orient -------------------------------------------------------------------------------------

TEST_F(HoudiniTest, OrientIsTheIdentityForEveryGrainWhateverTheUpAxis) {
  // the simulation tracks no orientation (export_formats.hpp): a shape copied onto the points
  // stands as it was modelled, in Houdini's frame, z up or y up
  const FrameData f = lattice_frame(50);
  for (const UpAxis up : {UpAxis::Z, UpAxis::Y}) {
    write_houdini_geo(path("f.geo"), f, up);
    const test::Geo g = test::parse_geo(read_bytes(path("f.geo")));
    ASSERT_EQ(g.points.size(), f.size());
    for (const test::GeoPoint& p : g.points)
      EXPECT_EQ(p.attr.at("orient"), (std::vector<double>{0, 0, 0, 1}));
  }
}

// ---- Cd -----------------------------------------------------------------------------------------

// sRGB-encoded to linear light, IEC 61966-2-1.
double linear(double v) {
  return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4);
}

TEST_F(HoudiniTest, CdIsTheColourOfTheGrainInPovRayAsLinearLight) {
  const FrameData f = lattice_frame(64);
  write_houdini_geo(path("f.geo"), f, UpAxis::Z);
  write_pov_scene(path("f.pov"), f, {}, PovOptions{});
  // the POV-Ray scene: the sand textures' sRGB colours, then each grain's texture
  std::vector<Vec3> srgb;
  std::istringstream pov(read_bytes(path("f.pov")));
  for (std::string line; std::getline(pov, line);) {
    Vec3 c;
    if (std::sscanf(line.c_str(), "  texture { pigment { srgb <%lf,%lf,%lf>", &c.x, &c.y, &c.z) ==
        3)
      srgb.push_back(c);
  }
  ASSERT_EQ(srgb.size(), 8u);
  const std::vector<test::PovGrain> drawn = test::pov_grains(read_bytes(path("f.pov")));
  ASSERT_EQ(drawn.size(), f.size());
  std::vector<int> texture(f.size(), -1);
  for (const test::PovGrain& d : drawn)
    for (std::size_t i = 0; i < f.size(); ++i)
      if (std::hypot(f.position[i].x - d.x, f.position[i].y - d.y, f.position[i].z - d.z) < 1e-6)
        texture[i] = d.shade;
  const test::Geo g = test::parse_geo(read_bytes(path("f.geo")));
  ASSERT_EQ(g.points.size(), f.size());
  std::set<int> shades;
  for (std::size_t i = 0; i < f.size(); ++i) {
    const std::vector<double>& cd = g.points[i].attr.at("Cd");
    ASSERT_EQ(cd.size(), 3u);
    ASSERT_GE(texture[i], 0) << i;
    const Vec3 want = srgb.at(static_cast<std::size_t>(texture[i]));
    // POV-Ray's colours are printed to 7 digits
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(cd[c], linear(want[c]), 1e-6) << i;
    EXPECT_TRUE(cd[0] > cd[1] && cd[1] > cd[2] && cd[2] > 0 && cd[0] < 1) << i;  // sand
    shades.insert(texture[i]);
  }
  EXPECT_GE(shades.size(), 6u);  // 64 grains show (nearly) every shade
}

// ---- Frame numbers ------------------------------------------------------------------------------

const char* kBlockScene = R"(
[material]
diameter = 0.01
k_n = 1.0e4
[output]
fps = 24
export = ["ply", "geo", "geo_gz"]
[[geometry]]
type = "plane"
[[emitter]]
type = "block"
count = 40
center = [0.0, 0.0, 0.05]
size = [0.04, 0.04, 0.06]
velocity = [0.2, 0.0, 0.0]
)";

TEST_F(HoudiniTest, FileNHoldsTheStateAtTimeNMinusOneOverFps) {
  const SceneConfig scene = load_scene_from_string(kBlockScene, "block.toml");
  World world(scene);
  fs::create_directories(dir_ / "frames");
  FrameExporter exporter(world, dir_.string());
  const fs::path frames = dir_ / "frames";
  // What file N of each Houdini series must hold: the state at t = (N - 1) / fps, N = 1, 2, ...
  const auto check = [&](int n) {
    SCOPED_TRACE("sand." + std::to_string(n));
    EXPECT_NEAR(world.time(), (n - 1) / 24.0, 1e-12);
    const FrameData want = world.visible_frame();
    const std::string name = fs::path(houdini_frame_name(world.frame(), false)).string();
    char expected[32];
    std::snprintf(expected, sizeof expected, "sand.%04d.geo", n);
    EXPECT_EQ(name, expected);
    // among the files a checkpoint flushes (after the frame's PLY)
    const std::vector<std::string>& written = exporter.written();
    ASSERT_GE(written.size(), 2u);
    EXPECT_EQ(std::vector<std::string>(written.end() - 2, written.end()),
              (std::vector<std::string>{(frames / expected).string(),
                                        (frames / (std::string(expected) + ".gz")).string()}));
    const std::string plain = read_bytes((frames / expected).string());
    EXPECT_EQ(test::gunzip(read_bytes((frames / (std::string(expected) + ".gz")).string())), plain);
    const test::Geo g = test::parse_geo(plain);
    ASSERT_EQ(g.points.size(), want.size());
    for (std::size_t i = 0; i < want.size(); ++i) {
      EXPECT_EQ(g.points[i].attr.at("id")[0], want.id[i]);
      for (int c = 0; c < 3; ++c) EXPECT_EQ(g.points[i].P[c], as_float32(want.position[i][c]));
    }
  };
  const auto points = [&](const char* name) {
    return test::parse_geo(read_bytes((frames / name).string())).points;
  };
  // the start: frame 1 (the emitter places its grains in the first step: none yet)
  ASSERT_EQ(world.frame(), 0);
  exporter.write_start(world);
  check(1);
  EXPECT_TRUE(points("sand.0001.geo").empty());
  for (int frame = 1; frame <= 3; ++frame) {
    world.advance_frame();
    exporter.write(world);
    check(frame + 1);
    const auto g = points(("sand.000" + std::to_string(frame + 1) + ".geo").c_str());
    EXPECT_EQ(g.size(), 40u);
    // the PLY frame of the same moment is numbered `frame`: the same grains
    const FrameData ply = read_ply((frames / ("000" + std::to_string(frame) + ".ply")).string());
    ASSERT_EQ(ply.size(), g.size());
    for (std::size_t i = 0; i < ply.size(); ++i)
      for (int c = 0; c < 3; ++c) EXPECT_EQ(g[i].P[c], ply.position[i][c]);
  }
  // the grains moved between the frames (so that the frames are told apart above)
  EXPECT_NE(read_bytes((frames / "sand.0003.geo").string()),
            read_bytes((frames / "sand.0004.geo").string()));
  EXPECT_FALSE(fs::exists(frames / "sand.0000.geo"));
  EXPECT_FALSE(fs::exists(frames / "sand.0005.geo"));
  EXPECT_FALSE(fs::exists(frames / "0001.geo"));  // the old name
}

}  // namespace
}  // namespace sandflow
