// The multi-valued terrain (docs/design.md §4): the solids under each column, the level a column's
// sand rests on, and a pour onto a shelf that overhangs a floor.
#include <gtest/gtest.h>

#include <omp.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "core/error.hpp"
#include "geometry/shapes.hpp"
#include "sim/world.hpp"
#include "support/test_scenes.hpp"
#include "surface/height_field.hpp"
#include "surface/surface_params.hpp"

namespace sandflow {
namespace {

constexpr Real kInf = std::numeric_limits<Real>::infinity();
// solid_intervals finds tops and bottoms in closed form: to rounding
constexpr Real kTraceTol = 1e-12;

using test::box_entry;
using test::floor_plane;

TEST(TerrainIntervals, FloorAndAShelfAboveIt) {
  const Geometry geo = Geometry::from_config(
      {floor_plane(0), box_entry({0, 0, 0.3}, {0.2, 0.2, 0.1})}, MaterialConfig{});
  const auto under = geo.solid_intervals(0.05, 0.0, 1.0, -1.0);
  ASSERT_EQ(under.size(), 2u);
  EXPECT_EQ(under[0].first, -kInf);  // the floor goes on down
  EXPECT_NEAR(under[0].second, 0.0, kTraceTol);
  EXPECT_NEAR(under[1].first, 0.25, kTraceTol);
  EXPECT_NEAR(under[1].second, 0.35, kTraceTol);
  const auto beside = geo.solid_intervals(0.15, 0.0, 1.0, -1.0);
  ASSERT_EQ(beside.size(), 1u);
  EXPECT_NEAR(beside[0].second, 0.0, kTraceTol);
}

TEST(TerrainIntervals, OpenContainerHoldsItsFloorAboveTheGround) {
  GeometryConfig cup;
  cup.type = GeometryType::Cylinder;
  cup.container = true;
  cup.center = {0, 0, 0.2};
  cup.radius = 0.1;
  cup.height = 0.1;
  cup.wall_thickness = 0.02;
  const Geometry geo = Geometry::from_config({floor_plane(0), cup}, MaterialConfig{});
  const auto inside = geo.solid_intervals(0, 0, 1.0, -1.0);
  ASSERT_EQ(inside.size(), 2u);
  EXPECT_NEAR(inside[1].first, 0.13, kTraceTol);   // the cup's bottom plate, 2 cm thick
  EXPECT_NEAR(inside[1].second, 0.15, kTraceTol);
  const auto wall = geo.solid_intervals(0.11, 0, 1.0, -1.0);  // through the tube and its plate
  ASSERT_EQ(wall.size(), 2u);
  EXPECT_NEAR(wall[1].first, 0.13, kTraceTol);
  EXPECT_NEAR(wall[1].second, 0.25, kTraceTol);
  EXPECT_TRUE(geo.solid_intervals(0, 0, 1.0, 0.5).empty());  // nothing between 0.5 and 1
}

TEST(TerrainIntervals, AContainersWallAndItsFloorAreOneSolid) {
  // the box's floor slab ends at the wall's foot within rounding (its top here is -0.0 minus a
  // hair): a line through the wall meets one solid, as the grains do, not a wall floating above
  // a seam
  GeometryConfig box = box_entry({0, 0, 0.1}, {0.083, 0.083, 0.2});
  box.container = true;
  box.wall_thickness = 0.003;
  const Geometry geo = Geometry::from_config({box}, MaterialConfig{});
  for (const Real x : {-0.0444, -0.043, -0.0416}) {
    const auto wall = geo.solid_intervals(x, 0.0, 1.0, -1.0);
    ASSERT_EQ(wall.size(), 1u) << "at x = " << x;
    EXPECT_NEAR(wall[0].first, -0.003, kTraceTol);
    EXPECT_NEAR(wall[0].second, 0.2, kTraceTol);
  }
}

// One column with the floor at 0 and a shelf from 0.10 to 0.12.
HeightField shelf_column() {
  HeightFieldParams p;
  p.cell = 0.01;
  p.nx = p.ny = 1;
  p.gap = 0.01;
  TerrainColumns t;
  t.add_column({{-kInf, 0.0}, {0.10, 0.12}});
  return HeightField(p, t);
}

const std::vector<Real> kNoStatic{-kInf};

// Tracing the columns is bounded by a budget of questions to the solids, counted row by row in
// order: the least budget that passes is the same at 1 and 2 threads, and one query less is refused
// naming the keys that make the field.
TEST(TerrainIntervals, TracingStopsAtItsBudgetWhateverTheThreads) {
  const Geometry geo = Geometry::from_config(
      {floor_plane(0), box_entry({0, 0, 0.3}, {0.2, 0.2, 0.1})}, MaterialConfig{});
  SurfaceParams p;
  p.grid.nx = 40;
  p.grid.ny = 30;
  p.grid.cell = 0.02;
  p.grid.x0 = -0.4;
  p.grid.y0 = -0.3;
  const auto passes = [&](std::uint64_t budget) {
    try {
      terrain_columns(p, geo, budget);
      return true;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("40 x 30 columns of 0.02 m"), std::string::npos);
      EXPECT_NE(std::string(e.what()).find("surface.cell_size"), std::string::npos);
      return false;
    }
  };
  std::uint64_t least[2] = {};
  for (const int threads : {1, 2}) {
    omp_set_num_threads(threads);
    std::uint64_t lo = 0, hi = 1;  // passes(hi), not passes(lo)
    while (!passes(hi)) lo = hi, hi *= 2;
    while (hi - lo > 1) {
      const std::uint64_t mid = lo + (hi - lo) / 2;
      (passes(mid) ? hi : lo) = mid;
    }
    least[threads - 1] = hi;
  }
  omp_set_num_threads(omp_get_num_procs());
  EXPECT_EQ(least[0], least[1]);
  // every column asks both solids once, and the lines between columns near the box ask them again
  EXPECT_GT(least[0], 2u * 40u * 30u);
}

TEST(TerrainIntervals, AWallBetweenColumnCentresIsFoundAndAFloorMakesNone) {
  // columns of 2 cm along x, centres at 1, 3, 5, 7 cm; a wall 6 mm thick and 5 cm high between the
  // centres of columns 1 and 2, at several places along the way
  SurfaceParams p;
  p.grid.nx = 4;
  p.grid.ny = 2;
  p.grid.cell = 0.02;
  p.z_top = 1;
  p.z_floor = -1;
  const TerrainColumns bare =
      terrain_columns(p, Geometry::from_config({floor_plane(0)}, MaterialConfig{}));
  EXPECT_TRUE(bare.walls.empty());
  for (const Real at : {0.036, 0.04, 0.044}) {
    const Geometry geo = Geometry::from_config(
        {floor_plane(0), box_entry({at, 0.02, 0.025}, {0.006, 0.04, 0.05})}, MaterialConfig{});
    const TerrainColumns t = terrain_columns(p, geo);
    ASSERT_EQ(t.wall_start.size(), 9u) << at;
    // on the +x edge of column 1 in both rows, nowhere else
    for (std::size_t c = 0; c < 8; ++c) {
      const std::size_t walls = t.wall_start[c + 1] - t.wall_start[c];
      ASSERT_EQ(walls, c % 4 == 1 ? 1u : 0u) << at << " column " << c;
      if (walls == 0) continue;
      const TerrainColumns::Wall& w = t.walls[t.wall_start[c]];
      EXPECT_EQ(w.axis, 0);
      EXPECT_EQ(w.bottom, -kInf);  // standing on the floor, which goes on down
      EXPECT_NEAR(w.top, 0.05, kTraceTol);
    }
  }
}

TEST(TerrainIntervals, ABoxContainersInsideIsCentredOnWholeColumns) {
  // a pour off the centre of a box 15.3, 15.5 and 15.8 columns wide inside: every column
  // holding part of the inside has its centre inside, so none takes a wall's top as its level
  // under the grains beside the wall
  for (const Real inside : {0.153, 0.155, 0.158}) {
    SceneConfig s = test::grains_on_floor("bin", Mode::Surface, 0.01);
    GeometryConfig box = box_entry({0.0123, -0.0071, 0.06}, {inside, inside, 0.12});
    box.container = true;
    box.wall_thickness = 0.01;
    s.geometry.push_back(box);
    s.emitters = {test::disk_pour({0.0337, 0.0191, 0.3}, 0.03, 1000, 500, {0, 0, -1})};
    const Geometry geo = Geometry::from_config(s.geometry, s.material);
    const HeightFieldParams g = surface_params(s, geo, 1e-4).grid;
    auto check = [&](Real origin, int n, Real low) {
      const Real high = low + inside;
      for (int i = 0; i < n; ++i) {
        const Real a = origin + i * g.cell, b = a + g.cell, centre = a + 0.5 * g.cell;
        if (b > low && a < high) {
          EXPECT_TRUE(centre > low && centre < high) << inside << " column " << i;
        }
      }
      EXPECT_LE(origin, low - 0.01);  // the walls are on the grid
      EXPECT_GE(origin + n * g.cell, high + 0.01);
    };
    check(g.x0, g.nx, 0.0123 - inside / 2);
    check(g.y0, g.ny, -0.0071 - inside / 2);
  }
}

// A jet or a block thrown sideways over open ground heaps where it comes down and its grains roll
// on: the grid reaches there and along their run with room for the heap (without it every grain
// there stayed simulated); a pour straight down keeps its grid around the pour.
TEST(TerrainIntervals, TheGridReachesWhereAThrowComesDown) {
  SceneConfig s = test::grains_on_floor("jet", Mode::Surface, 0.01);
  EmitterConfig jet = test::disk_pour({0.3, 0.2, 0.3}, 0.03, 2000, 2000, {-2.5, 1.0, 0.5});
  jet.facing = PourFacing::Velocity;
  EmitterConfig block;
  block.type = EmitterType::Block;
  block.center = {0.3, 0.2, 0.3};
  block.size = {0.1, 0.1, 0.1};
  block.count = 500;
  block.velocity = {-2.5, 1.0, 0.5};
  const Geometry geo = Geometry::from_config(s.geometry, s.material);
  const Real t = (0.5 + std::sqrt(0.25 + 2 * 9.81 * 0.3)) / 9.81;  // up 0.5 m/s, down 0.3 m
  const Real land_x = 0.3 - 2.5 * t, land_y = 0.2 + 1.0 * t;
  for (const Real mu_r : {0.1, 2.0}) {
    s.material.wall_rolling_friction = mu_r;
    for (const EmitterConfig& e : {jet, block}) {
      s.emitters = {e};
      const Real heap = largest_heap(s).radius;
      const HeightFieldParams g = surface_params(s, geo, 1e-4).grid;
      // and on from there, as far as a grain rolls at 2.7 m/s (ten heaps' radii at the most)
      const Real run = std::min(7.25 / (2 * mu_r * 9.81), 10 * heap);
      const std::string what = fmt::format("mu_r {}, run {:.3f} m", mu_r, run);
      EXPECT_LE(g.x0, land_x - 2.5 / std::sqrt(7.25) * run - heap) << what;
      EXPECT_GE(g.y0 + g.ny * g.cell, land_y + 1.0 / std::sqrt(7.25) * run + heap) << what;
      EXPECT_LT(g.x0, land_x - 2.5 / std::sqrt(7.25) * run - heap + 0.1) << what;  // not farther
      EXPECT_GE(g.x0 + g.nx * g.cell, 0.3 + heap) << what;  // and the emitter still
    }
  }
  s.emitters = {test::disk_pour({0.3, 0.2, 0.3}, 0.03, 2000, 2000, {0, 0, -1})};
  const HeightFieldParams g = surface_params(s, geo, 1e-4).grid;
  EXPECT_GT(g.x0, land_x);
}

TEST(TerrainLevels, EmptyColumnRestsOnTheHighestSolid) {
  HeightField hf = shelf_column();
  hf.measure(Grains{}, kNoStatic);
  EXPECT_DOUBLE_EQ(hf.terrain()[0], 0.12);
  EXPECT_DOUBLE_EQ(hf.surface()[0], 0.12);
}

TEST(TerrainLevels, SandUnderTheShelfMovesTheLevelDownAndStopsAtTheShelf) {
  HeightField hf = shelf_column();
  Grains g;
  g.add(0, {0.005, 0.005, 0.005}, {}, 0.005, 2600);  // on the floor, under the shelf
  hf.measure(g, kNoStatic);
  EXPECT_DOUBLE_EQ(hf.terrain()[0], 0.0);
  EXPECT_NEAR(hf.surface()[0], 0.01, 1e-12);
  // a stack up to the shelf's underside: H stops there, it does not climb through the shelf
  for (int k = 1; k < 12; ++k) g.add(k, {0.005, 0.005, 0.005 + 0.0095 * k}, {}, 0.005, 2600);
  hf.measure(g, kNoStatic);
  EXPECT_DOUBLE_EQ(hf.terrain()[0], 0.0);
  EXPECT_DOUBLE_EQ(hf.surface()[0], 0.10);
}

TEST(TerrainLevels, SandOnTheShelfWinsAndItsStaticLayerStartsThere) {
  HeightField hf = shelf_column();
  Grains g;
  g.add(0, {0.005, 0.005, 0.005}, {}, 0.005, 2600);  // under the shelf
  hf.measure(g, kNoStatic);
  hf.set_static_top({0.004});  // a static layer under the shelf
  ASSERT_DOUBLE_EQ(hf.static_top()[0], 0.004);
  g.add(1, {0.005, 0.005, 0.125}, {}, 0.005, 2600);  // on the shelf
  hf.measure(g, kNoStatic);
  EXPECT_DOUBLE_EQ(hf.terrain()[0], 0.12);
  EXPECT_NEAR(hf.surface()[0], 0.13, 1e-12);
  EXPECT_DOUBLE_EQ(hf.static_top()[0], 0.12);  // the new level's static layer is empty
  // static grains under the shelf do not count as sand on it
  hf.measure(Grains{}, {0.009});
  EXPECT_DOUBLE_EQ(hf.terrain()[0], 0.0);
  EXPECT_DOUBLE_EQ(hf.surface()[0], 0.009);
}

// A pour onto the edge of a shelf above the floor: sand heaps on the shelf and spills onto the
// floor, some of it under the shelf. The height field must keep every grain under the shelf moving
// (it cannot see them), no grain may end inside the shelf, and none may be lost.
TEST(TerrainLevels, PourOverAShelfEdgeKeepsTheGrainsUnderItActive) {
  SceneConfig s = test::grains_on_floor("shelf", Mode::Surface, 0.02);
  s.material.rolling_friction = 0.3;
  s.geometry.push_back(box_entry({-0.15, 0, 0.15}, {0.3, 0.3, 0.04}));  // shelf x in [-0.3, 0]
  s.emitters = {test::disk_pour({0.0, 0, 0.45}, 0.08, 1000, 900, {0, 0, -1})};
  World w(s);
  const HeightField& hf = w.surface()->height_field();
  bool shelf_held_sand = false, floor_held_sand = false;
  for (int f = 0; f < 60; ++f) {
    w.advance_frame();
    const Grains& g = w.grains();
    for (std::size_t i = 0; i < g.size(); ++i) {
      const std::int64_t c = hf.column_of(g.x[i].x, g.x[i].y);
      if (c >= 0 && g.x[i].z < hf.terrain()[static_cast<std::size_t>(c)]) {
        ASSERT_EQ(g.state[i], GrainState::Active) << "frame " << f << ": a grain under its level";
      }
    }
  }
  // a static layer at least half a grain deep on each level (the shelf's top is at 0.17 m)
  for (std::size_t c = 0; c < hf.columns(); ++c) {
    const Real depth = hf.static_top()[c] - hf.terrain()[c];
    if (std::abs(hf.terrain()[c] - 0.17) < kTraceTol) shelf_held_sand |= depth > 0.01;
    if (std::abs(hf.terrain()[c]) < kTraceTol) floor_held_sand |= depth > 0.01;
  }
  EXPECT_TRUE(shelf_held_sand) << "no static layer formed on the shelf";
  EXPECT_TRUE(floor_held_sand) << "no static layer formed on the floor";
  std::vector<Vec3> x;
  std::vector<Real> r;
  w.all_grains(x, r);
  EXPECT_EQ(x.size(), 900u);
  EXPECT_EQ(w.geometry().count_inside(x), 0u);
}

}  // namespace
}  // namespace sandflow
