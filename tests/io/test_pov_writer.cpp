#include "io/pov_writer.hpp"

#include <gtest/gtest.h>
#include <png.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <unistd.h>

#include "core/error.hpp"
#include "core/rng.hpp"
#include "io/sand_colour.hpp"
#include "support/pov_grains.hpp"
#include "support/scratch.hpp"

namespace sandflow {
namespace {

namespace fs = std::filesystem;

struct Image {
  int width = 0, height = 0;
  std::vector<unsigned char> rgb;  // row-major, top row first
  const unsigned char* at(int x, int y) const { return &rgb[3 * (std::size_t(y) * width + x)]; }
};

Image read_png(const std::string& path) {
  png_image img{};
  img.version = PNG_IMAGE_VERSION;
  Image out;
  if (!png_image_begin_read_from_file(&img, path.c_str())) return out;
  img.format = PNG_FORMAT_RGB;
  out.rgb.resize(PNG_IMAGE_SIZE(img));
  if (!png_image_finish_read(&img, nullptr, out.rgb.data(), 0, nullptr)) {
    png_image_free(&img);
    out.rgb.clear();
    return out;
  }
  out.width = static_cast<int>(img.width);
  out.height = static_cast<int>(img.height);
  return out;
}

// Sand pixels are warm (red well above blue); the floor is grey and the sky blue-ish.
bool is_sand(const unsigned char* p) {
  return p[0] > p[2] + 40;
}

using PovTest = test::ScratchTest;
using test::read_bytes;

// ~200 grains in a small mound on the floor z = 0.
FrameData small_mound() {
  FrameData f;
  Rng rng(3);
  auto u = [&rng] { return static_cast<double>(rng.next() >> 11) * 0x1.0p-53; };
  const double r = 0.005;
  for (int i = 0; i < 200; ++i) {
    const double a = 2 * kPi * u(), rho = 0.06 * std::sqrt(u());
    const double top = 0.04 * (1 - rho / 0.06);
    f.position.push_back({0.3 + rho * std::cos(a), -0.2 + rho * std::sin(a), r + top * u()});
    f.radius.push_back(r);
    f.id.push_back(static_cast<std::uint32_t>(i));
  }
  return f;
}

std::size_t count_of(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (auto at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

GeometryConfig floor_plane() {
  GeometryConfig g;
  g.type = GeometryType::Plane;
  g.name = "floor";
  return g;
}

TEST_F(PovTest, SceneTextHasGrainsAndGeometry) {
  const FrameData f = small_mound();
  std::vector<GeometryConfig> geometry{floor_plane()};
  GeometryConfig box;
  box.type = GeometryType::Box;
  box.name = "tray";
  box.center = {0.3, -0.2, 0.05};
  box.size = {0.2, 0.2, 0.1};
  box.container = true;
  box.render = RenderStyle::Glass;
  geometry.push_back(box);
  GeometryConfig hidden;
  hidden.type = GeometryType::Sphere;
  hidden.name = "invisible";
  hidden.render = RenderStyle::Hidden;
  geometry.push_back(hidden);

  const std::string p = path("scene.pov");
  write_pov_scene(p, f, geometry, PovOptions{});
  EXPECT_FALSE(fs::exists(p + ".tmp"));
  const std::string text = read_bytes(p);
  EXPECT_NE(text.find("#version 3.7;"), std::string::npos);
  EXPECT_NE(text.find("assumed_gamma 1.0"), std::string::npos);
  EXPECT_NE(text.find("sky <0,0,1>"), std::string::npos);
  EXPECT_NE(text.find("right -x*"), std::string::npos);
  // Every grain once, where it is, in its own shade (the grains of a shade in one union).
  const std::vector<test::PovGrain> grains = test::pov_grains(text);
  ASSERT_EQ(grains.size(), f.size());
  std::vector<int> seen(f.size(), 0);
  for (const test::PovGrain& g : grains) {
    std::size_t i = 0;  // the grain at g's place (the mound's grains are millimetres apart)
    while (i < f.size() &&
           std::hypot(f.position[i].x - g.x, f.position[i].y - g.y, f.position[i].z - g.z) > 1e-6)
      ++i;
    ASSERT_LT(i, f.size()) << g.x << " " << g.y << " " << g.z;
    ++seen[i];
    EXPECT_DOUBLE_EQ(g.radius, f.radius[i]);
    EXPECT_EQ(g.shade, sand_shade(f.id[i])) << i;
  }
  EXPECT_EQ(std::count(seen.begin(), seen.end(), 1), static_cast<long>(f.size()));
  EXPECT_EQ(count_of(text, "union {  // Sand["), static_cast<std::size_t>(kSandShades));
  // The glass container: walls cut from a box, unrotated, centred on its centre.
  EXPECT_NE(text.find("// tray\ndifference { box"), std::string::npos);
  EXPECT_NE(text.find("texture { Glass } interior { GlassInterior } matrix <1,0,0,0,1,0,0,0,1,0.3,"
                      "-0.2,0.05>"),
            std::string::npos);
  EXPECT_EQ(text.find("invisible"), std::string::npos);

  EXPECT_THROW(write_pov_scene(path("no/such/dir/scene.pov"), f, geometry, PovOptions{}),
               OutputError);
}

// A 6 x 5 grid of columns of 1 cm with sand (h = 2 cm) in the two columns (2, 2) and (3, 2).
SandSurface two_sand_columns() {
  SandSurface sf;
  sf.origin_x = -0.03;
  sf.origin_y = -0.02;
  sf.cell = 0.01;
  sf.nx = 6;
  sf.ny = 5;
  sf.grain_diameter = 0.01;
  sf.z.assign(30, 0.0);
  sf.sand.assign(30, 0);
  for (int i : {2, 3}) {
    sf.z[2 * 6 + i] = 0.02;
    sf.sand[2 * 6 + i] = 1;
  }
  return sf;
}

TEST_F(PovTest, AShadeWithOneGrainIsATexturedSphereNotAUnion) {
  // POV-Ray warns of a union of one object: a lone grain of its shade is drawn on its own
  FrameData f;
  f.position = {{0.01, 0.02, 0.03}};
  f.radius = {0.004};
  f.id = {7};
  const std::string text = pov_scene_text(f, {floor_plane()}, PovOptions{});
  EXPECT_EQ(count_of(text, "union {  // Sand["), 0u);
  const std::vector<test::PovGrain> grains = test::pov_grains(text);
  ASSERT_EQ(grains.size(), 1u);
  EXPECT_EQ(grains[0].shade, sand_shade(7));
  EXPECT_DOUBLE_EQ(grains[0].z, 0.03);
}

TEST_F(PovTest, TheStaticLayerIsASmoothSurfaceOverTheCellsThatTouchSand) {
  const SandSurface sf = two_sand_columns();
  const std::string p = path("layer.pov");
  write_pov_scene(p, small_mound(), {floor_plane()}, PovOptions{}, {}, &sf);
  const std::string text = read_bytes(p);
  ASSERT_NE(text.find("mesh2 {"), std::string::npos);
  EXPECT_NE(text.find("texture { StaticSand }"), std::string::npos);
  EXPECT_NE(text.find("vertex_vectors { 30,"), std::string::npos);
  EXPECT_NE(text.find("normal_vectors { 30,"), std::string::npos);
  // the cells with a sand column at a corner: x cells 1..3, y cells 1..2, two triangles each
  EXPECT_NE(text.find("face_indices { 12,"), std::string::npos);
  // a sand column's vertex at its centre and height
  EXPECT_NE(text.find("<-0.005,0.005,0.02>"), std::string::npos);
  // the grains are still drawn, after the surface
  EXPECT_EQ(test::pov_grains(text).size(), small_mound().size());
  EXPECT_LT(text.find("mesh2 {"), text.find("// grains"));

  SandSurface bare = two_sand_columns();
  bare.sand.assign(bare.sand.size(), 0);
  write_pov_scene(p, small_mound(), {floor_plane()}, PovOptions{}, {}, &bare);
  EXPECT_EQ(read_bytes(p).find("mesh2 {"), std::string::npos) << "no sand: nothing drawn";
  write_pov_scene(p, small_mound(), {floor_plane()}, PovOptions{});
  EXPECT_EQ(read_bytes(p).find("mesh2 {"), std::string::npos);
}

// Sand does not climb a wall: a column without sand beside the sand, standing higher (a wall's
// top, a shelf), is drawn at the sand's height, not its own; a lower one (the floor at a heap's
// foot) keeps its height; one with no sand around keeps its own, and is in no face.
TEST_F(PovTest, TheStaticLayerRunsIntoAWallBesideItNotUpItsFace) {
  SandSurface sf = two_sand_columns();
  for (int j = 0; j < 5; ++j) sf.z[j * 6 + 4] = 0.5;  // a wall 0.5 m tall along x cell 4
  sf.z[2 * 6 + 0] = 0.3;                              // and a post away from the sand
  const std::string p = path("wall.pov");
  write_pov_scene(p, small_mound(), {floor_plane()}, PovOptions{}, {}, &sf);
  const std::string text = read_bytes(p);
  EXPECT_NE(text.find("<0.015,0.005,0.02>"), std::string::npos) << "the wall beside the sand";
  EXPECT_NE(text.find("<0.015,0.015,0.02>"), std::string::npos);
  EXPECT_EQ(text.find("<0.015,0.005,0.5>"), std::string::npos);
  EXPECT_NE(text.find("<0.015,-0.015,0.5>"), std::string::npos) << "the wall away from it";
  EXPECT_NE(text.find("<-0.015,0.005,0>"), std::string::npos) << "the floor at the foot";
  EXPECT_NE(text.find("<-0.025,0.005,0.3>"), std::string::npos) << "the post";
}

TEST(PovCamera, CoreBoundsLeaveOutAStrayGrain) {
  FrameData f;
  Rng rng(5);
  for (int i = 0; i < 2000; ++i) {
    f.position.push_back({rng.uniform(-0.1, 0.1), rng.uniform(-0.1, 0.1), rng.uniform(0, 0.1)});
    f.radius.push_back(0.005);
  }
  f.position.push_back({3.0, 0, 0});  // thrown far off
  f.radius.push_back(0.005);
  const ViewBounds all = grain_bounds(f), core = grain_core_bounds(f);
  EXPECT_NEAR(all.hi.x, 3.005, 1e-12);
  EXPECT_LT(core.hi.x, 0.106);
  EXPECT_GT(core.hi.x, 0.09);  // the heap itself is kept, to within its outer half percent
  EXPECT_LT(core.lo.x, -0.09);
  EXPECT_GT(core.hi.z, 0.09);
  // a small frame keeps every grain
  FrameData few;
  few.position = {{0, 0, 0}, {1, 0, 0}};
  few.radius = {0.01, 0.01};
  EXPECT_NEAR(grain_core_bounds(few).hi.x, 1.01, 1e-12);
}

TEST_F(PovTest, RotationMatchesRotationXyzDeg) {
  GeometryConfig box;
  box.type = GeometryType::Box;
  box.name = "tilted";
  box.rotation_deg = {10, 20, 30};
  write_pov_scene(path("rot.pov"), FrameData{}, {box}, PovOptions{});
  const std::string text = read_bytes(path("rot.pov"));
  // The matrix lists the images of the local axes: the columns of rotation_xyz_deg.
  const Mat3 m = rotation_xyz_deg(box.rotation_deg);
  const std::size_t at = text.find("matrix <", text.find("// tilted"));
  ASSERT_NE(at, std::string::npos);
  std::string rest = text.substr(at + 8);
  std::replace(rest.begin(), rest.end(), ',', ' ');
  std::istringstream in(rest);
  for (int col = 0; col < 3; ++col) {
    for (int row = 0; row < 3; ++row) {
      double v = 0;
      in >> v;
      EXPECT_NEAR(v, m.m[row][col], 1e-6) << "row " << row << " col " << col;
    }
  }
}

TEST_F(PovTest, RendersMoundOnFloor) {
  if (find_povray().empty()) GTEST_SKIP() << "povray is not installed";
  const FrameData f = small_mound();
  PovOptions opt;
  opt.width = 160;
  opt.height = 120;
  write_pov_scene(path("mound.pov"), f, {floor_plane()}, opt);
  render_pov(path("mound.pov"), path("mound.png"), opt.width, opt.height, 2);
  ASSERT_TRUE(fs::exists(path("mound.png")));
  EXPECT_GT(fs::file_size(path("mound.png")), 0u);
  EXPECT_FALSE(fs::exists(path("mound.png.partial.png")));
  EXPECT_TRUE(fs::exists(path("mound.png.log")));

  const Image img = read_png(path("mound.png"));
  ASSERT_EQ(img.width, 160);
  ASSERT_EQ(img.height, 120);
  // The picture is not flat: the pixel values spread.
  int lo = 255, hi = 0;
  for (unsigned char c : img.rgb) {
    lo = std::min<int>(lo, c);
    hi = std::max<int>(hi, c);
  }
  EXPECT_GT(hi - lo, 60);
  // The auto camera frames the grains: sand in the picture, clear of the borders, and wide.
  int x0 = img.width, x1 = -1, y0 = img.height, y1 = -1, sand = 0;
  for (int y = 0; y < img.height; ++y) {
    for (int x = 0; x < img.width; ++x) {
      if (!is_sand(img.at(x, y))) continue;
      ++sand;
      x0 = std::min(x0, x);
      x1 = std::max(x1, x);
      y0 = std::min(y0, y);
      y1 = std::max(y1, y);
    }
  }
  ASSERT_GT(sand, 0);
  EXPECT_GT(x0, 0);
  EXPECT_LT(x1, img.width - 1);
  EXPECT_GT(y0, 0);
  EXPECT_LT(y1, img.height - 1);
  EXPECT_GT(x1 - x0, img.width / 3);
}

// A 160 x 120 picture from a fixed camera on -y, 6 m out, looking along +y at (0, 0, 1), z up.
PovOptions side_view() {
  PovOptions opt;
  opt.width = 160;
  opt.height = 120;
  opt.auto_camera = false;
  opt.camera_position = {0, -6, 1};
  opt.camera_look_at = {0, 0, 1};
  return opt;
}

TEST_F(PovTest, PictureIsNotMirrored) {
  if (find_povray().empty()) GTEST_SKIP() << "povray is not installed";
  // Camera on -y looking along +y with z up: in a right-handed world +x is to the right.
  // One grain right of and above the look-at point must land in the upper-right quadrant.
  FrameData f;
  f.position = {{0.8, 0, 1.5}};
  f.radius = {0.3};
  const PovOptions opt = side_view();
  write_pov_scene(path("probe.pov"), f, {}, opt);
  render_pov(path("probe.pov"), path("probe.png"), opt.width, opt.height, 1);
  const Image img = read_png(path("probe.png"));
  ASSERT_EQ(img.width, 160);
  double sx = 0, sy = 0;
  int n = 0;
  for (int y = 0; y < img.height; ++y) {
    for (int x = 0; x < img.width; ++x) {
      if (is_sand(img.at(x, y))) {
        sx += x;
        sy += y;
        ++n;
      }
    }
  }
  ASSERT_GT(n, 20);
  EXPECT_GT(sx / n, img.width / 2.0);   // right
  EXPECT_LT(sy / n, img.height / 2.0);  // up (rows count from the top)
}

TEST_F(PovTest, RenderFailureIsOutputErrorWithLog) {
  if (find_povray().empty()) GTEST_SKIP() << "povray is not installed";
  {
    std::ofstream out(path("broken.pov"));
    out << "#version 3.7;\nsphere { <0,0,0>, \n";  // parse error
  }
  try {
    render_pov(path("broken.pov"), path("broken.png"), 32, 24, 1);
    FAIL() << "no error";
  } catch (const OutputError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find(path("broken.png")), std::string::npos) << msg;
    EXPECT_NE(msg.find("exit status"), std::string::npos) << msg;
  }
  EXPECT_FALSE(fs::exists(path("broken.png")));
}

// The part of a scene that must stay put across the frames of a run: camera and lights.
std::string camera_and_lights(const std::string& pov) {
  const std::size_t a = pov.find("camera {");
  const std::size_t b = pov.find("sky_sphere");
  return a == std::string::npos || b == std::string::npos ? "" : pov.substr(a, b - a);
}

// Sand pixels in the picture of `pov` (rendered 160 x 120).
int sand_pixels(const std::string& pov, const std::string& png) {
  render_pov(pov, png, 160, 120, 1, false);
  const Image img = read_png(png);
  int n = 0;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) n += is_sand(img.at(x, y)) ? 1 : 0;
  return n;
}

TEST_F(PovTest, ARemovedSolidIsDrawnUntilItsTimeOnly) {
  if (find_povray().empty()) GTEST_SKIP() << "povray is not installed";
  // a grain behind a gate, seen through it: hidden while the gate stands, seen once it is gone
  FrameData f;
  f.position = {{0, 0, 1}};
  f.radius = {0.3};
  GeometryConfig gate;
  gate.type = GeometryType::Box;
  gate.name = "gate";
  gate.center = {0, -2, 1};
  gate.size = {3, 0.1, 3};
  gate.remove_at = 0.5;
  PovOptions opt = side_view();
  for (const double t : {0.4, 0.5, 0.6}) {
    opt.time = t;
    write_pov_scene(path("gate.pov"), f, {gate}, opt);
    const int sand = sand_pixels(path("gate.pov"), path("gate.png"));
    if (t <= 0.5)
      EXPECT_EQ(sand, 0) << t;  // (in frame 0.5 s the gate still held the grains)
    else
      EXPECT_GT(sand, 100) << t;
  }
  // --export pov: the scene written once, without grains; each frame declares its time
  opt.time = 0;
  write_pov_scene(path("scene.inc"), FrameData{}, {gate}, opt);
  for (const double t : {0.4, 0.6}) {
    std::ofstream(path("frame.pov"))
        << "#version 3.7;\n#declare SandflowTime = " << t << ";\n#include \"scene.inc\"\n"
        << pov_grain_lines(f);
    const int sand = sand_pixels(path("frame.pov"), path("frame.png"));
    if (t < 0.5)
      EXPECT_EQ(sand, 0) << t;
    else
      EXPECT_GT(sand, 100) << t;
  }
}

TEST_F(PovTest, GivenBoundsFixTheCameraAndLightsAcrossFrames) {
  FrameData a = small_mound();
  FrameData b = a;
  for (Vec3& p : b.position) p += Vec3{0.1, 0.05, 0.2};  // the grains of a later frame
  PovOptions opt;
  write_pov_scene(path("a.pov"), a, {floor_plane()}, opt);
  write_pov_scene(path("b.pov"), b, {floor_plane()}, opt);
  // each frame framed alone: the camera follows the grains
  EXPECT_NE(camera_and_lights(read_bytes(path("a.pov"))),
            camera_and_lights(read_bytes(path("b.pov"))));
  // framed on the bounds of both: one camera, one light
  opt.bounds = grain_bounds(a);
  opt.bounds.add(grain_bounds(b));
  write_pov_scene(path("a.pov"), a, {floor_plane()}, opt);
  write_pov_scene(path("b.pov"), b, {floor_plane()}, opt);
  const std::string ca = camera_and_lights(read_bytes(path("a.pov")));
  ASSERT_FALSE(ca.empty());
  EXPECT_EQ(ca, camera_and_lights(read_bytes(path("b.pov"))));
}

TEST(PovCamera, AutoCameraFitsTheBoundsTightly) {
  struct Case {
    Vec3 lo, hi;
    int width, height;
    double fov;
  };
  const Case cases[] = {{{-0.5, -0.5, 0}, {0.5, 0.5, 0.2}, 1280, 720, 40},  // a flat heap
                        {{0, 0, 0}, {0.1, 0.1, 1.0}, 640, 480, 40},         // a tall column
                        {{-2, -0.2, 0}, {2, 0.2, 0.3}, 64, 48, 25}};        // a long strip
  for (const Case& c : cases) {
    ViewBounds b;
    b.add(c.lo, 0);
    b.add(c.hi, 0);
    PovOptions opt;
    opt.width = c.width;
    opt.height = c.height;
    opt.fov_deg = c.fov;
    const auto [location, look_at] = auto_camera(b, opt);
    // POV-Ray's camera: `angle` is the horizontal field of view, up is z
    const Vec3 fwd = (look_at - location) / norm(look_at - location);
    const Vec3 right = cross(fwd, Vec3{0, 0, 1}) / norm(cross(fwd, Vec3{0, 0, 1}));
    const Vec3 up = cross(right, fwd);
    const double tan_h = std::tan(deg_to_rad(c.fov) / 2);
    const double tan_v = tan_h * c.height / c.width;
    double fill = 0;  // the largest share of the half-width or half-height a corner takes
    for (int k = 0; k < 8; ++k) {
      const Vec3 p{k & 1 ? c.hi.x : c.lo.x, k & 2 ? c.hi.y : c.lo.y, k & 4 ? c.hi.z : c.lo.z};
      const Vec3 d = p - location;
      const double depth = dot(d, fwd);
      ASSERT_GT(depth, 0);
      fill = std::max(
          {fill, std::abs(dot(d, right)) / depth / tan_h, std::abs(dot(d, up)) / depth / tan_v});
    }
    // every corner inside the 10 % border, and the box as large as that allows
    EXPECT_LE(fill, 0.9 + 1e-9);
    EXPECT_GT(fill, 0.88);
  }
}

TEST_F(PovTest, DraftHasAPointLightFinalAnAreaLight) {
  PovOptions opt;
  write_pov_scene(path("final.pov"), small_mound(), {floor_plane()}, opt);
  opt.soft_light = false;
  write_pov_scene(path("draft.pov"), small_mound(), {floor_plane()}, opt);
  EXPECT_NE(read_bytes(path("final.pov")).find("area_light"), std::string::npos);
  EXPECT_EQ(read_bytes(path("draft.pov")).find("area_light"), std::string::npos);
}

TEST_F(PovTest, AFloorIsAddedOnlyWhenTheSceneHasNone) {
  const auto planes = [](const std::string& text) {
    int n = 0;
    for (std::size_t at = text.find("plane { z"); at != std::string::npos;
         at = text.find("plane { z", at + 1))
      ++n;
    return n;
  };
  const FrameData f = small_mound();
  write_pov_scene(path("with.pov"), f, {floor_plane()}, PovOptions{});
  EXPECT_EQ(planes(read_bytes(path("with.pov"))), 1);  // the scene's own
  write_pov_scene(path("without.pov"), f, {}, PovOptions{});
  const std::string text = read_bytes(path("without.pov"));
  ASSERT_EQ(planes(text), 1);
  // just under the lowest grain's bottom (z = 0 here), by a thousandth of the scene's size
  const std::size_t at = text.find("plane { z, ");
  const double z = std::stod(text.substr(at + 11));
  EXPECT_LT(z, 0.0);
  EXPECT_GT(z, -1e-3);
  PovOptions no_floor;
  no_floor.floor = false;
  write_pov_scene(path("none.pov"), f, {}, no_floor);
  EXPECT_EQ(planes(read_bytes(path("none.pov"))), 0);
}

TEST_F(PovTest, FixedCameraWritesItsUpDirection) {
  PovOptions opt;
  opt.auto_camera = false;
  opt.camera_position = {1, -2, 0.5};
  opt.camera_look_at = {0, 0, 0};
  opt.camera_up = {0, 1, 1};
  opt.fov_deg = 30;
  write_pov_scene(path("fixed.pov"), small_mound(), {floor_plane()}, opt);
  const std::string text = read_bytes(path("fixed.pov"));
  EXPECT_NE(text.find("location <1,-2,0.5>"), std::string::npos);
  EXPECT_NE(text.find("sky <0,1,1>"), std::string::npos);
  EXPECT_NE(text.find("angle 30"), std::string::npos);
  EXPECT_NE(text.find("look_at <0,0,0>"), std::string::npos);
}

}  // namespace
}  // namespace sandflow
