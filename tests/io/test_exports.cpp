// The export writers (export_formats.hpp, height_export.hpp, the PLY's up axis): each file is read
// back by a small reader written here from the format's documentation, not by the writer's code,
// and compared with the frame that was written. Values are stored as float32, so they are compared
// with the float they were rounded to (exactly), or within one float ulp for the text formats that
// print a float's shortest form (which reads back to the same float).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <unistd.h>

#include <nlohmann/json.hpp>

#include "core/error.hpp"
#include "io/export_formats.hpp"
#include "io/frame_exporter.hpp"
#include "io/height_export.hpp"
#include "io/ply.hpp"
#include "io/png_gray.hpp"
#include "io/pov_writer.hpp"
#include "scene/scene_loader.hpp"
#include "sim/world.hpp"
#include "support/houdini_geo.hpp"
#include "support/pov_grains.hpp"
#include "support/scratch.hpp"
#include "support/xml_tags.hpp"
#include "surface/surface_params.hpp"

namespace sandflow {
namespace {

namespace fs = std::filesystem;

using ExportTest = test::ScratchTest;

using test::read_bytes;

// Three grains with distinct values in every field, and one frame velocity that is not axial.
FrameData sample_frame() {
  FrameData f;
  f.position = {{0.125, -0.5, 1.75}, {1.0 / 3, 2.0 / 7, -0.1}, {-3.25, 0.0625, 0.001}};
  f.radius = {0.005, 0.0045, 0.0055};
  f.velocity = {{1, 2, 3}, {-0.25, 0.5, -9.81}, {0, 0, 0}};
  f.id = {7, 42, 4000000000u};
  f.state = {0, 1, 0};
  return f;
}

float as_float(double v) {
  return static_cast<float>(v);
}

// ---- A reader of legacy VTK (binary POLYDATA) -------------------------------------------------

struct VtkData {
  std::string title;
  std::vector<float> points;
  std::vector<std::int32_t> verts;
  std::map<std::string, std::vector<double>> arrays;  // by name, components flattened
};

template <class T>
T big_endian(const std::string& s, std::size_t& p) {
  if (p + sizeof(T) > s.size()) throw std::runtime_error("vtk: data ends early");
  char b[sizeof(T)];
  std::memcpy(b, s.data() + p, sizeof(T));
  if (std::endian::native == std::endian::little) std::reverse(b, b + sizeof(T));
  T v;
  std::memcpy(&v, b, sizeof(T));
  p += sizeof(T);
  return v;
}

VtkData read_vtk(const std::string& path) {
  const std::string s = read_bytes(path);
  std::size_t p = 0;
  const auto line = [&] {
    const std::size_t nl = s.find('\n', p);
    if (nl == std::string::npos) throw std::runtime_error("vtk: no newline");
    std::string l = s.substr(p, nl - p);
    p = nl + 1;
    return l;
  };
  // Binary sections end with a newline before the next keyword.
  const auto keyword_line = [&] {
    std::string l;
    while ((l = line()).empty()) {
    }
    return l;
  };
  VtkData d;
  if (line() != "# vtk DataFile Version 3.0") throw std::runtime_error("vtk: bad first line");
  d.title = line();
  if (line() != "BINARY") throw std::runtime_error("vtk: not BINARY");
  if (line() != "DATASET POLYDATA") throw std::runtime_error("vtk: not POLYDATA");
  std::size_t n = 0;
  {
    std::istringstream h(keyword_line());
    std::string kw, type;
    h >> kw >> n >> type;
    if (kw != "POINTS" || type != "float") throw std::runtime_error("vtk: bad POINTS");
    for (std::size_t i = 0; i < 3 * n; ++i) d.points.push_back(big_endian<float>(s, p));
  }
  {
    std::istringstream h(keyword_line());
    std::string kw;
    std::size_t cells = 0, size = 0;
    h >> kw >> cells >> size;
    if (kw != "VERTICES") throw std::runtime_error("vtk: bad VERTICES");
    for (std::size_t i = 0; i < size; ++i) d.verts.push_back(big_endian<std::int32_t>(s, p));
  }
  {
    std::istringstream h(keyword_line());
    std::string kw;
    std::size_t m = 0;
    h >> kw >> m;
    if (kw != "POINT_DATA" || m != n) throw std::runtime_error("vtk: bad POINT_DATA");
  }
  while (p < s.size()) {
    std::string l = line();
    if (l.empty()) continue;
    std::istringstream h(l);
    std::string kw, name, type;
    int comps = 1;
    h >> kw >> name >> type;
    if (kw == "SCALARS") {
      h >> comps;
      if (line() != "LOOKUP_TABLE default") throw std::runtime_error("vtk: no LOOKUP_TABLE");
    } else if (kw == "VECTORS") {
      comps = 3;
    } else {
      throw std::runtime_error("vtk: unexpected " + l);
    }
    auto& a = d.arrays[name];
    for (std::size_t i = 0; i < n * comps; ++i) {
      if (type == "float")
        a.push_back(big_endian<float>(s, p));
      else if (type == "unsigned_char")
        a.push_back(big_endian<std::uint8_t>(s, p));
      else if (type == "unsigned_int")
        a.push_back(big_endian<std::uint32_t>(s, p));
      else
        throw std::runtime_error("vtk: type " + type);
    }
  }
  return d;
}

TEST_F(ExportTest, LegacyVtkReadsBackEveryArray) {
  const FrameData f = sample_frame();
  write_vtk_legacy(path("f.vtk"), f, UpAxis::Z, "frame 3, t = 0.1 s");
  const VtkData d = read_vtk(path("f.vtk"));
  EXPECT_EQ(d.title, "frame 3, t = 0.1 s");
  ASSERT_EQ(d.points.size(), 9u);
  ASSERT_EQ(d.verts.size(), 6u);
  for (std::size_t i = 0; i < 3; ++i) {
    for (int c = 0; c < 3; ++c) {
      EXPECT_EQ(d.points[3 * i + c], as_float(f.position[i][c])) << i << " " << c;
      EXPECT_EQ(d.arrays.at("velocity")[3 * i + c], as_float(f.velocity[i][c]));
    }
    EXPECT_EQ(d.verts[2 * i], 1);  // one point per vertex cell
    EXPECT_EQ(d.verts[2 * i + 1], static_cast<std::int32_t>(i));
    EXPECT_EQ(d.arrays.at("radius")[i], as_float(f.radius[i]));
    EXPECT_EQ(d.arrays.at("state")[i], f.state[i]);
    EXPECT_EQ(d.arrays.at("id")[i], f.id[i]);
  }
}

TEST_F(ExportTest, LegacyVtkOfNoGrainsIsWellFormed) {
  write_vtk_legacy(path("e.vtk"), FrameData{}, UpAxis::Z, "empty");
  const VtkData d = read_vtk(path("e.vtk"));
  EXPECT_TRUE(d.points.empty());
  EXPECT_EQ(d.arrays.size(), 4u);  // radius, velocity, state, id, each empty
}

// ---- VTK XML PolyData ---------------------------------------------------------------------------

TEST_F(ExportTest, VtpAppendedBlocksHoldTheArrays) {
  const FrameData f = sample_frame();
  write_vtp(path("f.vtp"), f, UpAxis::Z);
  const std::string s = read_bytes(path("f.vtp"));
  EXPECT_NE(s.find("NumberOfPoints=\"3\" NumberOfVerts=\"3\""), std::string::npos);
  const std::size_t start = s.find("<AppendedData encoding=\"raw\">");
  ASSERT_NE(start, std::string::npos);
  const std::size_t base = s.find('_', start) + 1;
  // every DataArray: its name, type and offset into the appended data
  std::map<std::string, std::vector<double>> arrays;
  for (const auto& a : test::xml_tags(s.substr(0, start), "DataArray")) {
    const std::string type = a.at("type"), name = a.at("Name");
    std::size_t p = base + std::stoul(a.at("offset"));
    std::uint64_t bytes = 0;
    std::memcpy(&bytes, s.data() + p, 8);  // little-endian, as the header says (this machine too)
    p += 8;
    const std::size_t size = type == "UInt8" ? 1 : 4;
    ASSERT_LE(p + bytes, s.size()) << name;
    for (std::size_t k = 0; k < bytes / size; ++k, p += size) {
      if (type == "Float32") {
        float v;
        std::memcpy(&v, s.data() + p, 4);
        arrays[name].push_back(v);
      } else if (type == "UInt8") {
        arrays[name].push_back(static_cast<std::uint8_t>(s[p]));
      } else if (type == "UInt32") {
        std::uint32_t v;
        std::memcpy(&v, s.data() + p, 4);
        arrays[name].push_back(v);
      } else {
        std::int32_t v;
        std::memcpy(&v, s.data() + p, 4);
        arrays[name].push_back(v);
      }
    }
  }
  ASSERT_EQ(arrays.size(), 7u);  // Points, radius, velocity, state, id, connectivity, offsets
  for (std::size_t i = 0; i < 3; ++i) {
    for (int c = 0; c < 3; ++c) {
      EXPECT_EQ(arrays["Points"][3 * i + c], as_float(f.position[i][c]));
      EXPECT_EQ(arrays["velocity"][3 * i + c], as_float(f.velocity[i][c]));
    }
    EXPECT_EQ(arrays["radius"][i], as_float(f.radius[i]));
    EXPECT_EQ(arrays["state"][i], f.state[i]);
    EXPECT_EQ(arrays["id"][i], f.id[i]);
    EXPECT_EQ(arrays["connectivity"][i], static_cast<double>(i));
    EXPECT_EQ(arrays["offsets"][i], static_cast<double>(i + 1));
  }
}

TEST_F(ExportTest, PvdListsFilesAndTimesInOrder) {
  write_pvd(path("s.pvd"), {{1.0 / 30, "frames/0001.vtp"}, {2.0 / 30, "frames/0002.vtp"}});
  const std::string s = read_bytes(path("s.pvd"));
  EXPECT_NE(s.find("<VTKFile type=\"Collection\""), std::string::npos);
  std::vector<std::pair<double, std::string>> got;
  for (const auto& set : test::xml_tags(s, "DataSet"))
    got.emplace_back(std::stod(set.at("timestep")), set.at("file"));
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(got[0].first, 1.0 / 30);  // printed in full: the times read back exactly
  EXPECT_EQ(got[1].first, 2.0 / 30);
  EXPECT_EQ(got[0].second, "frames/0001.vtp");
  EXPECT_EQ(got[1].second, "frames/0002.vtp");
}

// ---- Houdini classic .geo -----------------------------------------------------------------------

// The reader: tests/support/houdini_geo.hpp. Houdini's own frames are checked further in
// tests/io/test_houdini_export.cpp (gzip, orient, Cd, the frame numbers).
TEST_F(ExportTest, HoudiniGeoHasPVelocityPscaleColourAndOrient) {
  const FrameData f = sample_frame();
  write_houdini_geo(path("f.geo"), f, UpAxis::Z);
  const test::Geo g = test::parse_geo(read_bytes(path("f.geo")));
  std::vector<std::string> names;
  for (const test::GeoAttribute& a : g.dictionary) names.push_back(a.name + " " + a.type);
  EXPECT_EQ(names, (std::vector<std::string>{"Cd float", "v vector", "pscale float", "orient float",
                                             "id int", "state int"}));
  ASSERT_EQ(g.points.size(), 3u);
  EXPECT_EQ(g.part, (std::vector<std::size_t>{0, 1, 2}));
  for (std::size_t i = 0; i < 3; ++i) {
    const test::GeoPoint& p = g.points[i];
    for (int c = 0; c < 3; ++c) {
      EXPECT_EQ(p.P[c], as_float(f.position[i][c]));
      EXPECT_EQ(as_float(p.attr.at("v")[c]), as_float(f.velocity[i][c]));
    }
    EXPECT_EQ(as_float(p.attr.at("pscale")[0]), as_float(f.radius[i]));
    EXPECT_EQ(p.attr.at("id")[0], f.id[i]);
    EXPECT_EQ(p.attr.at("state")[0], f.state[i]);
    // the grain's colour (its values: test_houdini_export.cpp) and no turn
    EXPECT_EQ(p.attr.at("Cd").size(), 3u);
    EXPECT_EQ(p.attr.at("orient"), (std::vector<double>{0, 0, 0, 1}));
  }
  // no grains: no primitive either
  write_houdini_geo(path("e.geo"), FrameData{}, UpAxis::Z);
  const test::Geo e = test::parse_geo(read_bytes(path("e.geo")));
  EXPECT_TRUE(e.points.empty());
  EXPECT_TRUE(e.part.empty());
}

// ---- CSV ----------------------------------------------------------------------------------------

TEST_F(ExportTest, CsvRowsHoldEveryField) {
  const FrameData f = sample_frame();
  write_grains_csv(path("f.csv"), f, UpAxis::Z);
  std::istringstream in(read_bytes(path("f.csv")));
  std::string row;
  std::getline(in, row);
  EXPECT_EQ(row, "id,x,y,z,radius,vx,vy,vz,state");
  for (std::size_t i = 0; i < 3; ++i) {
    ASSERT_TRUE(std::getline(in, row));
    std::vector<double> v;
    std::stringstream cells(row);
    for (std::string c; std::getline(cells, c, ',');) v.push_back(std::stod(c));
    ASSERT_EQ(v.size(), 9u) << row;
    EXPECT_EQ(v[0], f.id[i]);
    for (int c = 0; c < 3; ++c) {
      EXPECT_EQ(as_float(v[1 + c]), as_float(f.position[i][c])) << row;
      EXPECT_EQ(as_float(v[5 + c]), as_float(f.velocity[i][c])) << row;
    }
    EXPECT_EQ(as_float(v[4]), as_float(f.radius[i]));
    EXPECT_EQ(v[8], f.state[i]);
  }
  EXPECT_FALSE(std::getline(in, row));
}

// ---- The up axis --------------------------------------------------------------------------------

TEST(UpAxis, YUpIsARightHandedRotationTakingZToY) {
  const Vec3 x{1, 0, 0}, y{0, 1, 0}, z{0, 0, 1};
  EXPECT_EQ(to_up_axis(z, UpAxis::Y), y);  // the scene's up is y
  EXPECT_EQ(to_up_axis(x, UpAxis::Y), x);
  EXPECT_EQ(to_up_axis(y, UpAxis::Y), (Vec3{0, 0, -1}));
  // a rotation: the images keep their handedness, x' cross y' = z'
  EXPECT_EQ(cross(to_up_axis(x, UpAxis::Y), to_up_axis(y, UpAxis::Y)), to_up_axis(z, UpAxis::Y));
  const Vec3 v{0.3, -1.7, 2.5};
  EXPECT_EQ(to_up_axis(v, UpAxis::Y), (Vec3{0.3, 2.5, 1.7}));
  EXPECT_EQ(from_up_axis(to_up_axis(v, UpAxis::Y), UpAxis::Y), v);
  EXPECT_EQ(to_up_axis(v, UpAxis::Z), v);
}

TEST_F(ExportTest, YUpRotatesEveryGrainFormatAndPlyReadsBack) {
  const FrameData f = sample_frame();
  const Vec3 up_x = to_up_axis(f.position[1], UpAxis::Y),
             up_v = to_up_axis(f.velocity[1], UpAxis::Y);
  write_vtk_legacy(path("f.vtk"), f, UpAxis::Y, "y");
  const VtkData d = read_vtk(path("f.vtk"));
  write_grains_csv(path("f.csv"), f, UpAxis::Y);
  write_houdini_geo(path("f.geo"), f, UpAxis::Y);
  const auto g = test::parse_geo(read_bytes(path("f.geo"))).points;
  for (int c = 0; c < 3; ++c) {
    EXPECT_EQ(d.points[3 + c], as_float(up_x[c]));
    EXPECT_EQ(d.arrays.at("velocity")[3 + c], as_float(up_v[c]));
    EXPECT_EQ(g[1].P[c], as_float(up_x[c]));
    EXPECT_EQ(as_float(g[1].attr.at("v")[c]), as_float(up_v[c]));
  }
  // PLY: the raw vertex is rotated, the header says so, and read_ply gives the scene's frame
  write_ply(path("f.ply"), f, UpAxis::Y);
  const std::string raw = read_bytes(path("f.ply"));
  EXPECT_NE(raw.find("comment up_axis y\n"), std::string::npos);
  const std::size_t body = raw.find("end_header\n") + 11;
  float first[3];
  std::memcpy(first, raw.data() + body, 12);
  for (int c = 0; c < 3; ++c)
    EXPECT_EQ(first[c], as_float(to_up_axis(f.position[0], UpAxis::Y)[c]));
  const FrameData back = read_ply(path("f.ply"));
  for (std::size_t i = 0; i < 3; ++i)
    for (int c = 0; c < 3; ++c) {
      EXPECT_EQ(back.position[i][c], as_float(f.position[i][c]));
      EXPECT_EQ(back.velocity[i][c], as_float(f.velocity[i][c]));
    }
  write_ply(path("z.ply"), f);
  EXPECT_NE(read_bytes(path("z.ply")).find("comment up_axis z\n"), std::string::npos);
}

// ---- POV-Ray frames -----------------------------------------------------------------------------

TEST(PovGrains, FrameLinesAreTheSceneWritersLines) {
  // the lines a frame file holds are those write_pov_scene writes for the same grains
  const FrameData f = sample_frame();
  const fs::path p =
      fs::temp_directory_path() / ("sandflow_pov_lines_" + std::to_string(::getpid()) + ".pov");
  write_pov_scene(p.string(), f, {}, PovOptions{});
  const std::string scene = read_bytes(p.string());
  fs::remove(p);
  const std::string lines = pov_grain_lines(f);
  EXPECT_NE(scene.find(lines), std::string::npos);
  EXPECT_EQ(test::pov_grains(lines).size(), 3u);
}

// p lies inside the picture of the camera opt.
void expect_in_view(const PovOptions& opt, const Vec3& p) {
  const Vec3 fwd =
      (opt.camera_look_at - opt.camera_position) / norm(opt.camera_look_at - opt.camera_position);
  const Vec3 right = cross(fwd, Vec3{0, 0, 1}) / norm(cross(fwd, Vec3{0, 0, 1}));
  const Vec3 up = cross(right, fwd);
  const double tan_h = std::tan(deg_to_rad(opt.fov_deg) / 2);
  const double tan_v = tan_h * opt.height / opt.width;
  const Vec3 d = p - opt.camera_position;
  ASSERT_GT(dot(d, fwd), 0);
  EXPECT_LT(std::abs(dot(d, right)) / dot(d, fwd), tan_h) << p.x << " " << p.y << " " << p.z;
  EXPECT_LT(std::abs(dot(d, up)) / dot(d, fwd), tan_v) << p.x << " " << p.y << " " << p.z;
}

// The POV-Ray frames' fixed camera keeps in view the pour and the ground under it, with the width
// of the largest heap around it (a pour above a floor: the floor is infinite, so only the emitter
// and the ground found under it say where to look).
// A pour 0.45 m above a floor (its [[emitter]] table last, open to more keys).
const char* kPourAboveFloor = R"(
[material]
diameter = 0.01
[[geometry]]
type = "plane"
[[emitter]]
type = "pour"
count = 3000
center = [0.2, -0.1, 0.45]
radius = 0.06
rate = 1000
)";

TEST(PovCamera, FramesThePourAndTheGroundUnderIt) {
  const SceneConfig scene = load_scene_from_string(kPourAboveFloor, "pour.toml");
  const World world(scene);
  const PovOptions opt = fixed_pov_camera(world);
  EXPECT_FALSE(opt.auto_camera);
  const Real r = largest_heap(scene).radius;
  for (const Vec3 p : {Vec3{0.2, -0.1, 0.45}, Vec3{0.2, -0.1, 0}, Vec3{0.2 + r, -0.1, 0},
                       Vec3{0.2 - r, -0.1, 0}, Vec3{0.2, -0.1 + r, 0}, Vec3{0.2, -0.1 - r, 0}})
    expect_in_view(opt, p);
}

// A jet thrown level over open ground heaps where it comes down: the camera frames that too.
TEST(PovCamera, FramesWhereAJetComesDown) {
  const SceneConfig scene = load_scene_from_string(
      std::string(kPourAboveFloor) + "facing = \"velocity\"\nvelocity = [-6, 0, 0]\n", "jet.toml");
  const PovOptions opt = fixed_pov_camera(World(scene));
  const Real x = 0.2 - 6 * std::sqrt(2 * 0.45 / 9.81), r = largest_heap(scene).radius;
  for (const Vec3 p : {Vec3{x, -0.1, 0}, Vec3{x - r, -0.1, 0}, Vec3{x, -0.1 + r, 0},
                       Vec3{x, -0.1 - r, 0}, Vec3{0.2, -0.1, 0.45}})
    expect_in_view(opt, p);
}

// ---- Height fields ------------------------------------------------------------------------------

HeightFieldParams small_grid() {
  HeightFieldParams g;
  g.nx = 5;
  g.ny = 4;
  g.cell = 0.02;
  g.x0 = -0.05;
  g.y0 = 0.1;
  return g;
}

std::vector<Real> ramp(const HeightFieldParams& g) {
  std::vector<Real> z;
  for (int j = 0; j < g.ny; ++j)
    for (int i = 0; i < g.nx; ++i) z.push_back(0.01 * i + 0.1 * j + 0.0012345);
  return z;
}

TEST_F(ExportTest, HeightPngRecoversHeightsWithinOneStep) {
  const HeightFieldParams g = small_grid();
  std::vector<Real> z = ramp(g);
  const HeightRange range{-0.02, 0.5};
  EXPECT_EQ(write_height_png(path("H.png"), g, z, range), 0u);
  const GrayImage img = read_gray_png(path("H.png"), 1000);
  ASSERT_EQ(img.width, g.nx);
  ASSERT_EQ(img.height, g.ny);
  // 16 bits: a height comes back within half a level (plus rounding of the division)
  EXPECT_LT(range.step(), 1e-5);
  for (int j = 0; j < g.ny; ++j)
    for (int i = 0; i < g.nx; ++i) {
      const double grey =
          img.value[static_cast<std::size_t>(g.ny - 1 - j) * g.nx + i];  // row 0: top y
      const double back = range.z_min + grey * (range.z_max - range.z_min);
      EXPECT_NEAR(back, z[static_cast<std::size_t>(j) * g.nx + i], 0.5 * range.step() + 1e-12)
          << i << " " << j;
    }
  // outside the range: clamped and counted
  z[0] = 0.7;
  z[1] = -1;
  EXPECT_EQ(write_height_png(path("H2.png"), g, z, range), 2u);
  const GrayImage img2 = read_gray_png(path("H2.png"), 1000);
  EXPECT_EQ(img2.value[static_cast<std::size_t>(g.ny - 1) * g.nx + 0], 1.0);
  EXPECT_EQ(img2.value[static_cast<std::size_t>(g.ny - 1) * g.nx + 1], 0.0);
  EXPECT_FALSE(fs::exists(path("H2.png.tmp")));
}

// OBJ: vertices and triangles.
struct Obj {
  std::vector<Vec3> v;
  std::vector<std::array<int, 3>> f;
};

Obj read_obj(const std::string& path) {
  Obj o;
  std::istringstream in(read_bytes(path));
  for (std::string line; std::getline(in, line);) {
    std::istringstream l(line);
    std::string kw;
    l >> kw;
    if (kw == "v") {
      Vec3 p;
      l >> p.x >> p.y >> p.z;
      o.v.push_back(p);
    } else if (kw == "f") {
      std::array<int, 3> t{};
      l >> t[0] >> t[1] >> t[2];
      o.f.push_back(t);
    }
  }
  return o;
}

TEST_F(ExportTest, HeightObjHasAVertexPerColumnAndUpwardTriangles) {
  const HeightFieldParams g = small_grid();
  const std::vector<Real> z = ramp(g);
  for (const UpAxis up : {UpAxis::Z, UpAxis::Y}) {
    write_height_obj(path("H.obj"), g, z, up, "test");
    const Obj o = read_obj(path("H.obj"));
    ASSERT_EQ(o.v.size(), z.size());
    EXPECT_EQ(o.f.size(), static_cast<std::size_t>(2 * (g.nx - 1) * (g.ny - 1)));
    for (int j = 0; j < g.ny; ++j)
      for (int i = 0; i < g.nx; ++i) {
        const Vec3 c = from_up_axis(o.v[static_cast<std::size_t>(j) * g.nx + i], up);
        // 7 significant digits
        EXPECT_NEAR(c.x, g.x0 + (i + 0.5) * g.cell, 1e-7);
        EXPECT_NEAR(c.y, g.y0 + (j + 0.5) * g.cell, 1e-7);
        EXPECT_NEAR(c.z, z[static_cast<std::size_t>(j) * g.nx + i], 1e-7);
      }
    const Vec3 up_dir = to_up_axis({0, 0, 1}, up);
    for (const auto& t : o.f) {
      for (int k : t) ASSERT_TRUE(k >= 1 && k <= static_cast<int>(o.v.size()));
      const Vec3 a = o.v[t[0] - 1], b = o.v[t[1] - 1], c = o.v[t[2] - 1];
      EXPECT_GT(dot(cross(b - a, c - a), up_dir), 0);  // counter-clockwise seen from above
    }
  }
}

TEST(HeightSidecar, RecordsTheGridAndTheRange) {
  const HeightFieldParams g = small_grid();
  const nlohmann::json j = height_sidecar(g, {0.0, 0.65535}, UpAxis::Y);
  EXPECT_EQ(j["nx"], 5);
  EXPECT_EQ(j["ny"], 4);
  EXPECT_DOUBLE_EQ(j["cell_size"].get<double>(), 0.02);
  EXPECT_DOUBLE_EQ(j["extent"][0].get<double>(), -0.04);  // the first column's centre
  EXPECT_DOUBLE_EQ(j["extent"][3].get<double>(), 0.1 + 3.5 * 0.02);
  EXPECT_EQ(j["png"]["z_min"].get<double>(), 0.0);
  EXPECT_EQ(j["png"]["z_max"].get<double>(), 0.65535);
  EXPECT_DOUBLE_EQ(j["png"]["metres_per_level"].get<double>(), 1e-5);
  EXPECT_EQ(j["obj"]["up_axis"], "y");
}

// ---- Choosing exports ---------------------------------------------------------------------------

TEST(ExportList, ParsesNamesAndRefusesUnknownOnesListingTheKnown) {
  EXPECT_EQ(parse_export_list("ply,vtk, geo ,ply", "--export"),
            (std::vector<ExportFormat>{ExportFormat::Ply, ExportFormat::Vtk, ExportFormat::Geo}));
  EXPECT_EQ(parse_export_list("geo_gz,geo", "--export"),
            (std::vector<ExportFormat>{ExportFormat::GeoGz, ExportFormat::Geo}));
  EXPECT_TRUE(parse_export_list("none", "--export").empty());
  for (const char* bad : {"ply,vtkk", "ply,,csv", "none,ply", ""}) {
    try {
      parse_export_list(bad, "--export");
      ADD_FAILURE() << "accepted '" << bad << "'";
    } catch (const InputError& e) {
      const std::string msg = e.what();
      EXPECT_EQ(msg.rfind("--export", 0), 0u) << msg;
      if (std::string(bad) != "none,ply") {
        EXPECT_NE(msg.find("ply, vtk, geo, geo_gz, pov, csv, height, height_obj"),
                  std::string::npos)
            << msg;
      }
    }
  }
  OutputConfig o;
  EXPECT_EQ(run_exports(o, Mode::Surface),
            (std::vector<ExportFormat>{ExportFormat::Ply, ExportFormat::Height}));
  EXPECT_EQ(run_exports(o, Mode::Dem), (std::vector<ExportFormat>{ExportFormat::Ply}));
}

const char* kScene = R"(
[output]
fps = 30
export = ["vtk", "height_obj"]
up_axis = "y"
[[emitter]]
type = "block"
count = 10
)";

TEST(ExportKeys, SceneFileChoosesExportsAndUpAxis) {
  const SceneConfig s = load_scene_from_string(kScene, "x.toml");
  ASSERT_TRUE(s.output.exports.has_value());
  EXPECT_EQ(*s.output.exports,
            (std::vector<ExportFormat>{ExportFormat::Vtk, ExportFormat::HeightObj}));
  EXPECT_EQ(s.output.up_axis, UpAxis::Y);
  // unset: the default; an empty array: nothing
  const SceneConfig d = load_scene_from_string("[[emitter]]\ncount = 1\n", "d.toml");
  EXPECT_FALSE(d.output.exports.has_value());
  EXPECT_EQ(d.output.up_axis, UpAxis::Z);
  const SceneConfig e = load_scene_from_string(kScene, "x.toml", {{"output.export", "[]"}});
  EXPECT_TRUE(e.output.exports->empty());
}

TEST(ExportKeys, BadValuesNameThePlaceAndWhatWasExpected) {
  const auto error = [](const std::string& text, const std::vector<Override>& o = {}) {
    try {
      load_scene_from_string(text, "x.toml", o);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  std::string text = kScene;
  text.replace(text.find("\"height_obj\""), 12, "\"vtkk\"");
  EXPECT_NE(error(text).find("x.toml:4:18: output.export[1] = \"vtkk\" is not an export: expected "
                             "one of ply, vtk, geo, geo_gz, pov, csv, height, height_obj"),
            std::string::npos)
      << error(text);
  EXPECT_NE(error(kScene, {{"output.up_axis", "x"}})
                .find("--set output.up_axis: output.up_axis = \"x\" is not one of \"z\", \"y\""),
            std::string::npos)
      << error(kScene, {{"output.up_axis", "x"}});
  EXPECT_NE(error(kScene, {{"output.export", "\"ply\""}})
                .find("output.export: expected an array of strings, got a string"),
            std::string::npos);
  EXPECT_NE(error(kScene, {{"output.export", "[1]"}})
                .find("output.export[0]: expected a string, got an integer"),
            std::string::npos);
}

}  // namespace
}  // namespace sandflow
