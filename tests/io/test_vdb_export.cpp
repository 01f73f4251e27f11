// The OpenVDB frames (io/vdb_export.hpp), read back with OpenVDB's own reader (io::File): the two
// grids by name, class and voxel size; every grain in the points grid with its attributes; the
// level set's sign inside the grains and the static layer and outside them, and its value near
// the surface; the y-up frame; the metadata; a failed write.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>
#include <openvdb/points/PointCount.h>
#include <openvdb/points/PointDataGrid.h>
#include <openvdb/tools/Interpolation.h>

#include "core/error.hpp"
#include "io/export_formats.hpp"
#include "io/frame_exporter.hpp"
#include "io/vdb_export.hpp"
#include "scene/scene_loader.hpp"
#include "sim/world.hpp"
#include "support/scratch.hpp"

namespace sandflow {
namespace {

namespace fs = std::filesystem;
namespace vdb = openvdb;

using VdbTest = test::ScratchTest;

constexpr Real kDiameter = 0.01;

// Grains one diameter across, apart from each other, with distinct values in every field.
FrameData vdb_sample_frame() {
  FrameData f;
  f.position = {{0.0125, -0.02, 0.1}, {0.05, 0.031, 0.12}, {-0.04, 0.0, 0.105}};
  f.radius = {0.005, 0.0045, 0.0055};
  f.velocity = {{1, 2, 3}, {-0.25, 0.5, -9.81}, {0, 0, 0}};
  f.id = {7, 42, 4000000000u};
  f.state = {0, 1, 0};
  return f;
}

VdbFrameInfo sample_info(UpAxis up = UpAxis::Z) {
  VdbFrameInfo info;
  info.scene = "sample";
  info.frame = 12;
  info.time = 0.4;
  info.up = up;
  info.points_voxel = 2 * kDiameter;
  info.surface_voxel = 0.9 * kDiameter / 3;  // a third of the smallest diameter at spread 0.1
  return info;
}

// A 20 x 20 grid of 1 cm columns on flat ground (L = 0) with static sand in its middle: a ramp
// h = 0.03 + 0.2 x over the columns of x in [-0.05, 0.05), y in [-0.05, 0.05); no sand elsewhere.
HeightField ramp_field() {
  HeightFieldParams p;
  p.x0 = p.y0 = -0.1;
  p.cell = 0.01;
  p.nx = p.ny = 20;
  HeightField hf(p, std::vector<Real>(400, 0.0));
  std::vector<Real> h(400, 0.0);
  for (int j = 5; j < 15; ++j)
    for (int i = 5; i < 15; ++i) h[j * 20 + i] = 0.03 + 0.2 * hf.centre(j * 20 + i).x;
  std::vector<Real> H = h;
  for (Real& z : H) z += 0.01;
  hf.set_surface(H);
  hf.set_static_top(h);
  return hf;
}

struct ReadBack {
  vdb::MetaMap::Ptr meta;
  vdb::points::PointDataGrid::Ptr grains;
  vdb::FloatGrid::Ptr surface;
  std::vector<std::string> names;  // every grid, in the file's order
};

ReadBack read_vdb(const std::string& path) {
  vdb::initialize();
  vdb::io::File file(path);
  file.open();
  ReadBack r;
  r.meta = file.getMetadata();
  for (auto it = file.beginName(); it != file.endName(); ++it) r.names.push_back(it.gridName());
  r.grains = vdb::gridPtrCast<vdb::points::PointDataGrid>(file.readGrid("grains"));
  r.surface = vdb::gridPtrCast<vdb::FloatGrid>(file.readGrid("surface"));
  file.close();
  return r;
}

// One point of the points grid, decoded to world space.
struct Point {
  vdb::Vec3d x;
  float pscale;
  vdb::Vec3f v;
  std::int64_t id;
  int state;
};

std::map<std::int64_t, Point> points_by_id(const vdb::points::PointDataGrid& grid) {
  std::map<std::int64_t, Point> out;
  for (auto leaf = grid.tree().cbeginLeaf(); leaf; ++leaf) {
    const vdb::points::AttributeHandle<vdb::Vec3f> P(leaf->constAttributeArray("P"));
    const vdb::points::AttributeHandle<float> pscale(leaf->constAttributeArray("pscale"));
    const vdb::points::AttributeHandle<vdb::Vec3f> v(leaf->constAttributeArray("v"));
    const vdb::points::AttributeHandle<std::int64_t> id(leaf->constAttributeArray("id"));
    const vdb::points::AttributeHandle<std::int8_t> state(leaf->constAttributeArray("state"));
    for (auto i = leaf->beginIndexOn(); i; ++i) {
      const vdb::Vec3d index = i.getCoord().asVec3d() + vdb::Vec3d(P.get(*i));
      out[id.get(*i)] = {grid.transform().indexToWorld(index), pscale.get(*i), v.get(*i),
                         id.get(*i), state.get(*i)};
    }
  }
  return out;
}

// The level set at a world point, interpolated trilinearly between voxel centres.
double phi(const vdb::FloatGrid& grid, const Vec3& x) {
  return vdb::tools::BoxSampler::sample(grid.tree(),
                                        grid.transform().worldToIndex(vdb::Vec3d(x.x, x.y, x.z)));
}

TEST_F(VdbTest, GridsReadBackWithTheirNamesClassesAndVoxels) {
  const std::string path = this->path("0012.vdb");
  write_vdb(path, vdb_sample_frame(), nullptr, sample_info());
  const ReadBack r = read_vdb(path);
  EXPECT_EQ(r.names, (std::vector<std::string>{"grains", "surface"}));
  ASSERT_TRUE(r.grains);
  ASSERT_TRUE(r.surface);
  EXPECT_EQ(r.grains->voxelSize(), vdb::Vec3d(2 * kDiameter));
  EXPECT_EQ(r.surface->voxelSize(), vdb::Vec3d(sample_info().surface_voxel));
  EXPECT_EQ(r.surface->getGridClass(), vdb::GRID_LEVEL_SET);
  // the narrow band: 3 voxels each side (stored as a 16-bit float: to 2^-11)
  EXPECT_NEAR(r.surface->background(), 3 * sample_info().surface_voxel,
              3 * sample_info().surface_voxel / 2048);
  EXPECT_TRUE(r.surface->saveFloatAsHalf());
  // metadata, in the file and on each grid
  for (const vdb::MetaMap* m : {r.meta.get(), static_cast<vdb::MetaMap*>(r.grains.get()),
                                static_cast<vdb::MetaMap*>(r.surface.get())}) {
    EXPECT_DOUBLE_EQ(m->metaValue<double>("time"), 0.4);
    EXPECT_EQ(m->metaValue<std::int32_t>("frame"), 12);
    EXPECT_EQ(m->metaValue<std::string>("scene"), "sample");
    EXPECT_EQ(m->metaValue<std::string>("units"), "m");
    EXPECT_EQ(m->metaValue<std::string>("up_axis"), "z");
  }
}

TEST_F(VdbTest, PointsHoldEveryGrainWithItsAttributes) {
  const FrameData f = vdb_sample_frame();
  const VdbFrameInfo info = sample_info();
  const std::string path = this->path("0012.vdb");
  write_vdb(path, f, nullptr, info);
  const ReadBack r = read_vdb(path);
  ASSERT_TRUE(r.grains);
  EXPECT_EQ(vdb::points::pointCount(r.grains->tree()), f.size());
  const auto points = points_by_id(*r.grains);
  ASSERT_EQ(points.size(), f.size());
  // P is a 16-bit offset from the voxel's centre: within one step, 2^-16 of a voxel
  const double quantum = info.points_voxel / 65535;
  for (std::size_t i = 0; i < f.size(); ++i) {
    SCOPED_TRACE(i);
    ASSERT_EQ(points.count(f.id[i]), 1u);
    const Point& p = points.at(f.id[i]);
    EXPECT_NEAR(p.x.x(), f.position[i].x, quantum);
    EXPECT_NEAR(p.x.y(), f.position[i].y, quantum);
    EXPECT_NEAR(p.x.z(), f.position[i].z, quantum);
    EXPECT_EQ(p.pscale, static_cast<float>(f.radius[i]));
    EXPECT_EQ(p.v,
              vdb::Vec3f(static_cast<float>(f.velocity[i].x), static_cast<float>(f.velocity[i].y),
                         static_cast<float>(f.velocity[i].z)));
    EXPECT_EQ(p.state, f.state[i]);
  }
  // the largest uint32 id needs the int64
  EXPECT_EQ(points.rbegin()->first, 4000000000LL);
}

TEST_F(VdbTest, LevelSetIsNegativeInsideEachGrainAndPositiveAway) {
  const FrameData f = vdb_sample_frame();
  const VdbFrameInfo info = sample_info();
  const double vs = info.surface_voxel;
  write_vdb(path("0012.vdb"), f, nullptr, info);
  const ReadBack r = read_vdb(path("0012.vdb"));
  ASSERT_TRUE(r.surface);
  for (std::size_t i = 0; i < f.size(); ++i) {
    SCOPED_TRACE(i);
    const Vec3 c = f.position[i];
    const double radius = f.radius[i];
    // the voxel nearest the centre holds its distance to the sphere, to the precision of the
    // 16-bit floats the level set is stored as (2^-11 of the band's half width, 3 voxels)
    const vdb::Coord k = r.surface->transform().worldToIndexCellCentered({c.x, c.y, c.z});
    const vdb::Vec3d at = r.surface->transform().indexToWorld(k);
    EXPECT_NEAR(r.surface->tree().getValue(k), (at - vdb::Vec3d(c.x, c.y, c.z)).length() - radius,
                3 * vs / 2048);
    // interpolated at the centre, the cusp of the distance is blunted by up to the half diagonal
    // of a voxel (0.87); a voxel out of the sphere, where the distance is smooth, the trilinear
    // interpolation is within a few hundredths of a voxel at these radii (1.5 to 2 voxels)
    EXPECT_LT(phi(*r.surface, c), -(radius - 0.87 * vs));
    EXPECT_NEAR(phi(*r.surface, c + Vec3{0, 0, radius + vs}), vs, 0.25 * vs);
    EXPECT_NEAR(phi(*r.surface, c + Vec3{radius + vs, 0, 0}), vs, 0.25 * vs);
    // well away: outside the band, the background
    EXPECT_FLOAT_EQ(phi(*r.surface, c + Vec3{0, 0, radius + 10 * vs}), r.surface->background());
  }
  // between the grains, empty space
  EXPECT_GT(phi(*r.surface, {0.0, 0.0, 0.2}), 0.0);
}

TEST_F(VdbTest, StaticLayerIsInsideBetweenTheGroundAndItsTop) {
  const HeightField hf = ramp_field();
  const VdbFrameInfo info = sample_info();
  const double vs = info.surface_voxel;
  write_vdb(path("0001.vdb"), FrameData{}, &hf, info);
  const ReadBack r = read_vdb(path("0001.vdb"));
  ASSERT_TRUE(r.surface);
  EXPECT_EQ(vdb::points::pointCount(r.grains->tree()), 0u);
  const double cos_slope = 1 / std::sqrt(1 + 0.2 * 0.2);
  // inside a column, h as the height field interpolates it (a plane here)
  for (const auto& [x, y] : {std::pair{0.005, 0.005}, {-0.023, 0.011}, {0.031, -0.037}}) {
    SCOPED_TRACE(x);
    const double h = hf.static_top_at(x, y);
    EXPECT_NEAR(h, 0.03 + 0.2 * x, 1e-12);
    // the surface at h, the distance off it across the slope, inside below it
    EXPECT_NEAR(phi(*r.surface, {x, y, h}), 0.0, 0.1 * vs);
    EXPECT_NEAR(phi(*r.surface, {x, y, h + 2 * vs}), 2 * vs * cos_slope, 0.1 * vs);
    EXPECT_NEAR(phi(*r.surface, {x, y, h - 2 * vs}), -2 * vs * cos_slope, 0.1 * vs);
    // deep inside (further than the band from both faces): the flood fill's -background
    EXPECT_FLOAT_EQ(phi(*r.surface, {x, y, h / 2}), -r.surface->background());
    // the ground under the layer is not sand
    EXPECT_NEAR(phi(*r.surface, {x, y, -vs}), vs, 0.1 * vs);
    EXPECT_GT(phi(*r.surface, {x, y, -10 * vs}), 0.0);
    // well above the heap
    EXPECT_FLOAT_EQ(phi(*r.surface, {x, y, h + 10 * vs}), r.surface->background());
  }
  // no sand on the bare ground around the square, nor beyond the grid
  for (const auto& [x, y] : {std::pair{0.085, 0.0}, {0.0, -0.09}, {0.3, 0.0}})
    for (const double z : {-vs, 0.0, vs, 0.02})
      EXPECT_GT(phi(*r.surface, {x, y, z}), 0.0) << x << " " << y << " " << z;
}

TEST_F(VdbTest, AWallStepKeepsTheLayerInItsColumns) {
  // the ramp's grid with a wall along its last row of columns (L = h = 0.1), beside sand 3 cm
  // deep: interpolated, the layer would climb the wall; it stops at the column's edge instead
  HeightField hf = ramp_field();
  const HeightFieldParams& p = hf.params();
  std::vector<Real> L(400, 0.0), h(400, 0.0);
  for (int j = 0; j < 20; ++j) {
    for (int i = 10; i < 19; ++i) h[j * 20 + i] = 0.03;
    L[j * 20 + 19] = h[j * 20 + 19] = 0.1;
  }
  hf = HeightField(p, L);
  std::vector<Real> H = h;
  for (Real& z : H) z += 0.01;
  hf.set_surface(H);
  hf.set_static_top(h);
  const VdbFrameInfo info = sample_info();
  write_vdb(path("0001.vdb"), FrameData{}, &hf, info);
  const ReadBack r = read_vdb(path("0001.vdb"));
  // in the last sand column, right up to the wall's column: sand to 3 cm, none above
  EXPECT_LT(phi(*r.surface, {0.089, 0.0, 0.015}), 0.0);
  EXPECT_GT(phi(*r.surface, {0.089, 0.0, 0.045}), 0.0);
  // over the wall's column: the wall, not sand
  for (const double z : {0.015, 0.05, 0.09}) EXPECT_GT(phi(*r.surface, {0.095, 0.0, z}), 0.0) << z;
}

TEST_F(VdbTest, YUpRotatesThePointsAndTheLevelSet) {
  const FrameData f = vdb_sample_frame();
  const HeightField hf = ramp_field();
  const VdbFrameInfo info = sample_info(UpAxis::Y);
  const double vs = info.surface_voxel;
  write_vdb(path("0001.vdb"), f, &hf, info);
  const ReadBack r = read_vdb(path("0001.vdb"));
  EXPECT_EQ(r.meta->metaValue<std::string>("up_axis"), "y");
  const auto points = points_by_id(*r.grains);
  const double quantum = info.points_voxel / 65535;
  for (std::size_t i = 0; i < f.size(); ++i) {
    SCOPED_TRACE(i);
    const Vec3 x = to_up_axis(f.position[i], UpAxis::Y);  // (x, z, -y)
    const Vec3 v = to_up_axis(f.velocity[i], UpAxis::Y);
    const Point& p = points.at(f.id[i]);
    EXPECT_NEAR(p.x.x(), x.x, quantum);
    EXPECT_NEAR(p.x.y(), x.y, quantum);
    EXPECT_NEAR(p.x.z(), x.z, quantum);
    EXPECT_EQ(
        p.v, vdb::Vec3f(static_cast<float>(v.x), static_cast<float>(v.y), static_cast<float>(v.z)));
    EXPECT_LT(phi(*r.surface, x), -(f.radius[i] - 0.87 * vs));
    EXPECT_NEAR(phi(*r.surface, x + Vec3{0, f.radius[i] + vs, 0}), vs, 0.25 * vs);
  }
  // the static layer turned with them: inside below h along the exported y
  const double h = hf.static_top_at(0.005, 0.005);
  EXPECT_LT(phi(*r.surface, to_up_axis({0.005, 0.005, h - 2 * vs}, UpAxis::Y)), -vs);
  EXPECT_GT(phi(*r.surface, to_up_axis({0.005, 0.005, h + 2 * vs}, UpAxis::Y)), vs);
  EXPECT_GT(phi(*r.surface, to_up_axis({0.005, 0.005, -2 * vs}, UpAxis::Y)), vs);
}

TEST_F(VdbTest, AnUnwritablePathIsAnOutputErrorNamingIt) {
  const std::string path = this->path("no_such_folder/0001.vdb");
  try {
    write_vdb(path, vdb_sample_frame(), nullptr, sample_info());
    FAIL() << "no error";
  } catch (const OutputError& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(path + ".tmp"));
}

// A small world in surface mode (a lattice settling on the floor), its frames written by the
// FrameExporter as a run writes them: DIR/frames/NNNN.vdb holds exactly the visible grains, and
// where the height field holds static sand, the level set is inside it.
TEST_F(VdbTest, AWorldsFramesHoldItsVisibleGrainsAndItsStaticLayer) {
  const SceneConfig scene = load_scene_from_string(R"(
[scene]
name = "vdb"
[material]
diameter = 0.01
diameter_spread = 0.1
k_n = 1.0e4
[surface]
repose_angle = 32
max_angle = 38
flowing_hold = 0  # (the layer freezes as the lattice settles: this test reads it)
[output]
fps = 30
export = ["vdb"]
[[geometry]]
type = "plane"
[[emitter]]
type = "lattice"
count = 240
center = [0.0, 0.0, 0.03]
size = [0.08, 0.08, 0.06]
)",
                                                   "vdb.toml");
  World world(scene);
  fs::create_directories(dir_ / "frames");
  FrameExporter exporter(world, dir_.string());
  for (int k = 0; k < 10; ++k) {
    world.advance_frame();
    exporter.write(world);
  }
  const std::string file = (dir_ / "frames" / "0010.vdb").string();
  ASSERT_EQ(exporter.written(), std::vector<std::string>{file});
  const ReadBack r = read_vdb(file);
  EXPECT_EQ(r.meta->metaValue<std::int32_t>("frame"), 10);
  EXPECT_EQ(r.meta->metaValue<std::string>("scene"), "vdb");
  EXPECT_EQ(r.grains->voxelSize(), vdb::Vec3d(0.02));
  EXPECT_EQ(r.surface->voxelSize(), vdb::Vec3d(vdb_surface_voxel(scene)));
  EXPECT_NEAR(vdb_surface_voxel(scene), 0.003, 1e-15);  // d (1 - 0.1) / 3
  const FrameData visible = world.visible_frame();
  EXPECT_EQ(vdb::points::pointCount(r.grains->tree()), visible.size());
  for (std::size_t i = 0; i < visible.size(); i += 37)
    EXPECT_LT(phi(*r.surface, visible.position[i]), 0.0) << i;
  // inside the static layer: half way up every column with a centimetre of it (after 10 frames
  // the settled lattice has 1.7 cm in the middle)
  const HeightField& hf = world.surface()->height_field();
  int checked = 0;
  for (std::size_t c = 0; c < hf.columns(); ++c) {
    const Real depth = hf.static_top()[c] - hf.terrain()[c];
    if (depth < 0.01) continue;
    const Vec3 at = hf.centre(c) + Vec3{0, 0, hf.terrain()[c] + depth / 2};
    EXPECT_LT(phi(*r.surface, at), 0.0) << c;
    ++checked;
  }
  EXPECT_GT(checked, 0);
  EXPECT_GT(phi(*r.surface, {0.0, 0.0, 0.2}), 0.0);
}

TEST(VdbKeys, ExportNameAndVoxelSize) {
  EXPECT_EQ(parse_export_list("ply,vdb", "--export"),
            (std::vector<ExportFormat>{ExportFormat::Ply, ExportFormat::Vdb}));
  EXPECT_EQ(export_name(ExportFormat::Vdb), "vdb");
  const char* text = R"(
[material]
diameter = 0.004
diameter_spread = 0.25
[output]
export = ["vdb"]
[[emitter]]
count = 10
)";
  // unset: a third of the smallest diameter; set: as given
  const SceneConfig d = load_scene_from_string(text, "x.toml");
  EXPECT_EQ(*d.output.exports, std::vector<ExportFormat>{ExportFormat::Vdb});
  EXPECT_DOUBLE_EQ(vdb_surface_voxel(d), 0.004 * 0.75 / 3);
  EXPECT_DOUBLE_EQ(vdb_points_voxel(d.material), 0.008);
  const SceneConfig s =
      load_scene_from_string(text, "x.toml", {{"output.vdb_voxel_size", "0.002"}});
  EXPECT_DOUBLE_EQ(vdb_surface_voxel(s), 0.002);
  try {
    load_scene_from_string(text, "x.toml", {{"output.vdb_voxel_size", "0"}});
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("output.vdb_voxel_size"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace sandflow
