// Mesh obstacles in a scene: found, placed, sampled into boundary particles that hold grains up,
// seen by the terrain and by the inside count; a missing file is an error or its fallback box.
#include <gtest/gtest.h>

#include <filesystem>

#include "core/error.hpp"
#include "geometry/shapes.hpp"
#include "io/height_export.hpp"
#include "sim/world.hpp"
#include "support/scratch.hpp"
#include "support/test_scenes.hpp"

namespace sandflow {
namespace {

namespace fs = std::filesystem;

// A 0.2 m cube as an OBJ file in the test's scratch folder (removed when the test ends); returns
// the folder.
fs::path cube_folder(const test::ScratchFolder& scratch) {
  scratch.write("cube.obj",
                "v 0 0 0\nv 2 0 0\nv 2 2 0\nv 0 2 0\nv 0 0 2\nv 2 0 2\nv 2 2 2\nv 0 2 2\n"
                "f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n");
  return scratch.dir();
}

GeometryConfig cube_entry() {
  GeometryConfig g;
  g.type = GeometryType::Mesh;
  g.name = "cube";
  g.mesh_file = "cube.obj";
  g.mesh_size = 0.2;  // the file's cube is 2 units wide
  g.position = {0, 0, 0};
  return g;
}

// A frame's static top h tells sand from bare solid by the solid under each column, a mesh's
// too (render draws the sand, measure stands it in for the sleeping grains): h at a mesh's top is
// bare. Asking the primitive solids alone (Geometry::top_below) took the floor under the mesh for
// the ground, and every column over a mesh for sand.
TEST(MeshObstacle, StaticSandIsToldFromTheBareTopOfAMesh) {
  const test::ScratchFolder scratch;
  const fs::path dir = cube_folder(scratch);
  MaterialConfig mat;
  mat.diameter = 0.02;
  const Geometry geo = Geometry::from_config({test::floor_plane(), cube_entry()}, mat,
                                             (dir / "scene.toml").string());
  const Real d = mat.diameter, top = 0.2 + geo.meshes()[0].particle_radius;
  HeightImages grid;  // 4 x 4 columns of 0.1 m: the middle four over the cube (|x|, |y| < 0.1)
  grid.origin_x = grid.origin_y = -0.2;
  grid.cell = 0.1;
  grid.nx = grid.ny = 4;
  std::vector<Real> h(16, 0.0);       // the floor's columns bare ...
  h[0] = 0.5 * d;                     // ... but one, half a grain of sand on the floor
  h[1 * 4 + 1] = top;                 // over the cube: bare
  h[1 * 4 + 2] = top + d;             // a grain of sand on it
  h[2 * 4 + 1] = h[2 * 4 + 2] = top;  // bare
  std::vector<Real> ground;
  const std::vector<std::uint8_t> sand = static_sand_columns(h, grid, geo, d, &ground);
  for (std::size_t k = 0; k < h.size(); ++k) {
    const bool over_cube = (k / 4 == 1 || k / 4 == 2) && (k % 4 == 1 || k % 4 == 2);
    EXPECT_NEAR(ground[k], over_cube ? top : 0.0, 1e-12) << k;
    EXPECT_EQ(sand[k], k == 0 || k == 1 * 4 + 2 ? 1 : 0) << k;
  }
}

TEST(MeshObstacle, IsScaledAndSetDownOnItsPosition) {
  const test::ScratchFolder scratch;
  const fs::path dir = cube_folder(scratch);
  MaterialConfig mat;
  mat.diameter = 0.02;
  const Geometry geo =
      Geometry::from_config({test::floor_plane(), cube_entry()}, mat, (dir / "scene.toml").string());
  ASSERT_EQ(geo.meshes().size(), 1u);
  const Aabb box = mesh_bounds(geo.meshes()[0].mesh);
  EXPECT_NEAR(box.lo.x, -0.1, 1e-12);
  EXPECT_NEAR(box.hi.y, 0.1, 1e-12);
  EXPECT_NEAR(box.lo.z, 0.0, 1e-12);
  EXPECT_NEAR(box.hi.z, 0.2, 1e-12);
  EXPECT_DOUBLE_EQ(geo.meshes()[0].particle_radius, 0.01);  // half the smallest diameter
  // the terrain sees the cube, grown by the particles the grains rest on, merged with the floor
  const auto col = geo.solid_intervals(0.0, 0.0, 1.0, -1.0);
  ASSERT_EQ(col.size(), 1u);
  EXPECT_NEAR(col[0].second, 0.21, 1e-9);
  // inside: the cube's centre; outside: beside it
  EXPECT_EQ(geo.count_inside({{0, 0, 0.1}, {0.3, 0, 0.1}, {0, 0, 0.25}}), 1u);
  EXPECT_TRUE(geo.warnings().empty());
}

TEST(MeshObstacle, MissingFileIsAnErrorOrItsFallbackBox) {
  const test::ScratchFolder scratch;
  const fs::path dir = cube_folder(scratch);
  GeometryConfig g = cube_entry();
  g.mesh_file = "no_such_mesh.ply";
  try {
    (void)Geometry::from_config({g}, MaterialConfig{}, (dir / "scene.toml").string());
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("no_such_mesh.ply"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("fetch_meshes.sh"), std::string::npos) << e.what();
  }
  g.fallback_box = true;
  g.fallback_size = {0.3, 0.2, 0.1};
  const Geometry geo = Geometry::from_config({g}, MaterialConfig{}, (dir / "scene.toml").string());
  ASSERT_EQ(geo.warnings().size(), 1u);
  EXPECT_NE(geo.warnings()[0].find("stands in"), std::string::npos);
  const Aabb box = mesh_bounds(geo.meshes()[0].mesh);
  EXPECT_NEAR(box.hi.x - box.lo.x, 0.3, 1e-12);
  EXPECT_NEAR(box.hi.z - box.lo.z, 0.1, 1e-12);
}

// Grains poured onto the cube in plain DEM: its boundary particles must hold a heap on its top,
// and none may get inside it or through the floor.
TEST(MeshObstacle, BoundaryParticlesHoldAPourAndNoGrainGetsIn) {
  const test::ScratchFolder scratch;
  const fs::path dir = cube_folder(scratch);
  SceneConfig s = test::grains_on_floor("cube", Mode::Dem, 0.02);
  s.path = (dir / "scene.toml").string();  // the mesh file is looked for beside it
  s.material.rolling_friction = 0.3;
  s.geometry.push_back(cube_entry());
  s.emitters = {test::disk_pour({0, 0, 0.5}, 0.06, 400, 300, {0, 0, -1})};
  World w(s);
  ASSERT_GT(w.dem().boundary().size(), 100u);
  for (int f = 0; f < 45; ++f) w.advance_frame();
  std::vector<Vec3> x;
  std::vector<Real> r;
  w.all_grains(x, r);
  ASSERT_EQ(x.size(), 300u);
  EXPECT_EQ(w.geometry().count_inside(x), 0u);
  int on_top = 0;
  for (const Vec3& p : x) on_top += p.z > 0.2 && std::abs(p.x) < 0.1 && std::abs(p.y) < 0.1;
  EXPECT_GT(on_top, 20) << "the cube's top held no heap";
}

}  // namespace
}  // namespace sandflow
