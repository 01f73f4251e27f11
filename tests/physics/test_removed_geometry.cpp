// A solid removed during a run (`remove_at`: a gate opened, a tube lifted): it pushes until its
// time and nothing after, in both modes; in surface mode the height field's terrain follows and
// the static sand it held wakes.
#include <gtest/gtest.h>

#include <cmath>

#include "sim/world.hpp"
#include "support/test_scenes.hpp"

namespace sandflow {
namespace {

SceneConfig grain_on_a_box(Real remove_at) {
  SceneConfig s = test::grains_on_floor("removed box", Mode::Dem, 0.01);
  GeometryConfig box = test::box_entry({0, 0, 0.05}, {0.1, 0.1, 0.1});
  box.remove_at = remove_at;
  s.geometry.push_back(box);
  EmitterConfig one;
  one.type = EmitterType::Lattice;
  one.center = {0, 0, 0.106};
  one.size = {0.0111, 0.0111, 0.0111};
  one.count = 1;
  s.emitters = {one};
  s.output.fps = 30;
  return s;
}

TEST(RemovedGeometry, AGrainOnABoxRestsUntilTheBoxGoesThenFallsToTheFloor) {
  World w(grain_on_a_box(0.2));
  for (int f = 0; f < 5; ++f) w.advance_frame();  // 0.167 s: the box still holds it
  ASSERT_EQ(w.grains().size(), 1u);
  EXPECT_NEAR(w.grains().x[0].z, 0.105, 0.002);
  for (int f = 0; f < 15; ++f) w.advance_frame();  // 0.667 s: it has fallen 0.1 m and rests
  EXPECT_NEAR(w.grains().x[0].z, 0.005, 0.002);
  EXPECT_LT(norm(w.grains().v[0]), 0.05);
  // the box stays in the list of obstacles, reaching nothing
  EXPECT_EQ(w.geometry().count_inside({{0, 0, 0.05}}), 0u);
}

// A tube holding a settled column (about five radii high), lifted at 0.4 s.
SceneConfig tube_column(Mode mode) {
  SceneConfig s = test::grains_on_floor("tube", mode, 0.01);
  s.material.rolling_friction = 0.3;
  s.material.wall_rolling_friction = 0.3;
  s.surface.extent = std::array<Real, 4>{-0.3, -0.3, 0.3, 0.3};
  GeometryConfig tube;
  tube.type = GeometryType::Cylinder;
  tube.container = true;
  tube.center = {0, 0, 0.175};
  tube.radius = 0.04;
  tube.height = 0.35;
  tube.remove_at = 0.4;
  s.geometry.push_back(tube);
  EmitterConfig fill;
  fill.type = EmitterType::Block;
  fill.center = {0, 0, 0.15};
  fill.size = {0.056, 0.056, 0.29};  // 4 x 4 x 25 grains, loose: they settle in the tube
  fill.count = 400;
  fill.jitter = 0.5;
  s.emitters = {fill};
  s.output.fps = 30;
  return s;
}

TEST(RemovedGeometry, ALiftedTubeLetsItsColumnSpreadInBothModes) {
  for (Mode mode : {Mode::Dem, Mode::Surface}) {
    SCOPED_TRACE(mode == Mode::Dem ? "dem" : "surface");
    World w(tube_column(mode));
    for (int f = 0; f < 12; ++f) w.advance_frame();  // 0.4 s: settled in the tube
    std::vector<Vec3> x;
    std::vector<Real> r;
    w.all_grains(x, r);
    Real reach = 0;
    for (const Vec3& p : x) reach = std::max(reach, std::hypot(p.x, p.y));
    EXPECT_LT(reach, 0.04);
    const std::int64_t static_before = static_cast<std::int64_t>(w.static_grains().size());
    if (mode == Mode::Surface) {
      EXPECT_GT(static_before, 0) << "nothing to wake: the test is void";
    }
    for (int f = 0; f < 30; ++f) w.advance_frame();  // 1 s of collapse
    w.all_grains(x, r);
    ASSERT_EQ(x.size(), 400u);
    int outside = 0;
    for (const Vec3& p : x) outside += std::hypot(p.x, p.y) > 0.05;
    // a column five radii high spreads to several times its radius: most grains leave the tube
    EXPECT_GT(outside, 100);
    EXPECT_EQ(w.geometry().count_inside(x), 0u);
    if (mode == Mode::Surface) {
      // the static sand in the tube woke and moved: no grain static where the column stood high
      const SurfaceFlow& sf = *w.surface();
      const std::int64_t c = sf.height_field().column_of(0, 0);
      ASSERT_GE(c, 0);
      EXPECT_LT(sf.height_field().static_top()[static_cast<std::size_t>(c)], 0.09);
    }
  }
}

}  // namespace
}  // namespace sandflow
