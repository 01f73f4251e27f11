// Analytic solids: signed distances and normals against hand-computed values, and containers
// that keep grains in.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <memory>
#include <utility>
#include <vector>

#include "core/error.hpp"
#include "core/rng.hpp"
#include "geometry/heightmap.hpp"
#include "geometry/shapes.hpp"
#include "sim/world.hpp"

namespace sandflow {
namespace {

TEST(Shapes, BoxDistancesFacesEdgesAndInside) {
  const SolidBox box({0, 0, 0}, {1, 2, 3}, Mat3{});
  auto sp = box.closest({3, 0, 0});  // off the +x face
  EXPECT_NEAR(sp.distance, 2, 1e-12);
  EXPECT_NEAR(sp.normal.x, 1, 1e-12);
  sp = box.closest({2, 3, 0});  // off the edge x = 1, y = 2
  EXPECT_NEAR(sp.distance, std::sqrt(2.0), 1e-12);
  EXPECT_NEAR(sp.normal.x, std::sqrt(0.5), 1e-12);
  EXPECT_NEAR(sp.normal.y, std::sqrt(0.5), 1e-12);
  sp = box.closest({0, 0, 2.5});  // inside, nearest the +z face
  EXPECT_NEAR(sp.distance, -0.5, 1e-12);
  EXPECT_NEAR(sp.normal.z, 1, 1e-12);
}

TEST(Shapes, RotatedBoxFollowsItsRotation) {
  // a thin slab rotated 90 degrees about x: its thin axis (local z) becomes world -y
  const SolidBox box({0, 0, 0}, {1, 1, 0.1}, rotation_xyz_deg({90, 0, 0}));
  const auto sp = box.closest({0, -1, 0});
  EXPECT_NEAR(sp.distance, 0.9, 1e-12);
  EXPECT_NEAR(sp.normal.y, -1, 1e-12);
}

TEST(Shapes, CylinderAndTube) {
  const SolidCylinder solid({0, 0, 0}, 1.0, 0.0, 2.0, Mat3{});
  EXPECT_NEAR(solid.closest({3, 0, 0}).distance, 2, 1e-12);
  EXPECT_NEAR(solid.closest({0, 0, 1.5}).distance, 0.5, 1e-12);
  EXPECT_NEAR(solid.closest({0, 0, 0}).distance, -1, 1e-12);
  // a tube of inner radius 0.8: its axis is free space, 0.8 from the wall
  const SolidCylinder tube({0, 0, 0}, 1.0, 0.8, 2.0, Mat3{});
  const auto sp = tube.closest({0.2, 0, 0});
  EXPECT_NEAR(sp.distance, 0.6, 1e-12);
  EXPECT_NEAR(sp.normal.x, -1, 1e-12);  // pointing inwards, to the free side
}

TEST(Shapes, SphereAndPlane) {
  const SolidSphere ball({1, 1, 1}, 0.5);
  EXPECT_NEAR(ball.closest({1, 1, 3}).distance, 1.5, 1e-12);
  const HalfSpace floor({0, 0, 0.2}, {0, 0, 1});
  EXPECT_NEAR(floor.closest({5, -3, 1}).distance, 0.8, 1e-12);
  EXPECT_NEAR(floor.closest({5, -3, 0}).distance, -0.2, 1e-12);
}

// A solid's vertical stretches are where its signed distance is negative: every shape, upright,
// turned and tilted, against the sign of closest() at 2,001 heights on each of 300 lines through
// and beside it. (The sign is exact for every shape, the heightmap's bound included; heights
// within 1e-9 m of an end are not asked.)
TEST(Shapes, VerticalStretchesAreWhereTheDistanceIsNegative) {
  HeightGrid g;
  g.nx = 5;
  g.ny = 4;
  for (int k = 0; k < g.nx * g.ny; ++k) g.z.push_back(0.1 + 0.05 * std::sin(1.7 * k));
  const Mat3 turned = rotation_xyz_deg({0, 0, 30}), tilted = rotation_xyz_deg({35, -20, 10});
  std::vector<std::unique_ptr<Solid>> solids;
  solids.push_back(std::make_unique<HalfSpace>(Vec3{0, 0, 0.1}, Vec3{0, 0, 1}));
  solids.push_back(std::make_unique<HalfSpace>(Vec3{0, 0, 0.1},
                                               Vec3{0.3, -0.2, -1} / norm(Vec3{0.3, -0.2, -1})));
  solids.push_back(std::make_unique<HalfSpace>(Vec3{0.1, 0, 0}, Vec3{1, 0, 0}));  // a vertical one
  solids.push_back(std::make_unique<SolidBox>(Vec3{0, 0, 0.1}, Vec3{0.3, 0.2, 0.1}, Mat3{}));
  solids.push_back(std::make_unique<SolidBox>(Vec3{0, 0, 0.1}, Vec3{0.3, 0.2, 0.1}, tilted));
  solids.push_back(std::make_unique<SolidSphere>(Vec3{0.1, -0.1, 0.2}, 0.35));
  for (const Mat3& rot : {Mat3{}, turned, tilted}) {
    solids.push_back(std::make_unique<SolidCylinder>(Vec3{0, 0, 0.1}, 0.3, 0.0, 0.4, rot));
    solids.push_back(std::make_unique<SolidCylinder>(Vec3{0, 0, 0.1}, 0.3, 0.2, 0.4, rot));
    solids.push_back(std::make_unique<SolidBowl>(Vec3{0, 0, 0.1}, 0.3, 0.05, 0.3, rot));
    solids.push_back(std::make_unique<SolidBowl>(Vec3{0, 0, 0.1}, 0.3, 0.05, 0.15, rot));
    solids.push_back(std::make_unique<SolidBowl>(Vec3{0, 0, 0.1}, 0.3, 0.05, 0.45, rot));
  }
  solids.push_back(
      std::make_unique<SolidHeightmap>(g, std::array<Real, 4>{-0.3, -0.2, 0.3, 0.25}, 0.04));
  Rng rng(7);
  for (std::size_t k = 0; k < solids.size(); ++k) {
    const Solid& solid = *solids[k];
    int inside = 0;
    for (int line = 0; line < 300; ++line) {
      const Real x = rng.uniform(-0.45, 0.45), y = rng.uniform(-0.45, 0.45);
      Stretches st;
      solid.vertical_stretches(x, y, st);
      for (std::size_t s = 0; s < st.size(); ++s) {
        ASSERT_LE(st[s].first, st[s].second) << "solid " << k;
        if (s > 0) {
          ASSERT_LT(st[s - 1].second, st[s].first) << "solid " << k << ": not ascending";
        }
      }
      for (int i = 0; i <= 2000; ++i) {
        const Real z = -0.5 + 1e-3 * i;
        bool near_end = false, in = false;
        for (const auto& [lo, hi] : st) {
          near_end |= std::abs(z - lo) < 1e-9 || std::abs(z - hi) < 1e-9;
          in |= z >= lo && z <= hi;
        }
        if (near_end) continue;
        const Real d = solid.closest({x, y, z}).distance;
        ASSERT_EQ(in, d < 0) << "solid " << k << " at (" << x << ", " << y << ", " << z
                             << "): distance " << d;
        inside += in;
      }
    }
    EXPECT_GT(inside, 1000) << "solid " << k << ": the lines hardly met it";
  }
}

// The least width across each shape: what the lines looking for walls between columns must not
// pass by (surface_params.cpp, wall_lines).
TEST(Shapes, LeastWidthIsTheThinnestWayAcross) {
  const Mat3 tilted = rotation_xyz_deg({35, -20, 10});
  EXPECT_DOUBLE_EQ(SolidBox({0, 0, 0}, {0.3, 0.0015, 0.2}, tilted).least_width(), 0.003);
  EXPECT_DOUBLE_EQ(SolidSphere({0, 0, 0}, 0.2).least_width(), 0.4);
  EXPECT_DOUBLE_EQ(SolidCylinder({0, 0, 0}, 0.3, 0.0, 0.4, Mat3{}).least_width(), 0.4);
  EXPECT_DOUBLE_EQ(SolidCylinder({0, 0, 0}, 0.3, 0.28, 0.4, Mat3{}).least_width(), 0.3 - 0.28);
  EXPECT_DOUBLE_EQ(SolidCylinder({0, 0, 0}, 0.3, 0.0, 0.01, Mat3{}).least_width(), 0.01);
  EXPECT_DOUBLE_EQ(SolidBowl({0, 0, 0}, 0.3, 0.004, 0.3, tilted).least_width(), 0.004);
  EXPECT_TRUE(std::isinf(HalfSpace({0, 0, 0}, {0, 0, 1}).least_width()));
}

// Grains dropped into an open box container and a cylindrical bucket stay inside them: none in a
// wall, none outside.
TEST(Shapes, ContainersHoldGrains) {
  for (GeometryType type : {GeometryType::Box, GeometryType::Cylinder}) {
    SceneConfig s;
    s.path = "containers";
    s.material.k_n = 1e4;
    GeometryConfig c;
    c.type = type;
    c.container = true;
    c.center = {0, 0, 0.1};
    c.size = {0.12, 0.12, 0.2};
    c.radius = 0.07;
    c.height = 0.2;
    s.geometry = {c};
    EmitterConfig e;
    e.type = EmitterType::Lattice;
    e.count = 800;
    e.center = {0, 0, 0.1};
    e.size = {0.09, 0.09, 0.18};
    e.velocity = {0.5, 0.3, 0};
    s.emitters = {e};
    s.output.frames = 12;
    World w(s);
    for (int f = 0; f < 12; ++f) w.advance_frame();
    EXPECT_EQ(w.geometry().count_inside(w.grains().x), 0u);
    for (const Vec3& p : w.grains().x) {
      EXPECT_GT(p.z, 0.0);
      EXPECT_LT(std::max(std::abs(p.x), std::abs(p.y)), 0.075);
    }
  }
}

TEST(Emitters, LatticeAndRectPourMakeTheirCountWithoutOverlaps) {
  SceneConfig s;
  s.path = "emitters";
  s.material.diameter_spread = 0.2;
  EmitterConfig lattice;
  lattice.type = EmitterType::Lattice;
  lattice.count = 500;
  lattice.center = {0, 0, 0.5};
  lattice.size = {0.1, 0.1, 0.1};
  EmitterConfig rect;
  rect.type = EmitterType::Pour;
  rect.shape = PourShape::Rect;
  rect.count = 300;
  rect.center = {1, 0, 0.5};
  rect.size = {0.1, 0.05, 0};
  rect.rate = 2000;
  rect.velocity = {0, 0, -1};
  s.emitters = {lattice, rect};
  s.simulation.gravity = {0, 0, -9.81};
  World w(s);
  const FrameStats st = w.advance_frame();
  EXPECT_EQ(st.max_overlap_rel, 0.0);  // nothing emitted overlaps anything
  EXPECT_GE(st.n_total, 500 + 50);
  for (int f = 0; f < 8; ++f) w.advance_frame();
  EXPECT_EQ(w.total_grains(), 800);
}

// A pour under a lattice at rest (no gravity) that covers its disk from x = x_lo to 0.06: the top
// of a heap grown up to the pour. Returns the pour's emitted and delayed grains and the largest
// overlap seen.
struct PourUnderHeap {
  std::int64_t emitted, delayed;
  Real max_overlap;
};
PourUnderHeap pour_under_heap(Real x_lo) {
  SceneConfig s;
  s.path = "emitters";
  s.simulation.gravity = {0, 0, 0};
  EmitterConfig heap_top;
  heap_top.type = EmitterType::Lattice;
  heap_top.center = {(x_lo + 0.06) / 2, 0, 0.5};
  heap_top.size = {0.06 - x_lo, 0.12, 0.03};
  EmitterConfig pour;
  pour.type = EmitterType::Pour;
  pour.count = 150;
  pour.center = {0, 0, 0.5};
  pour.radius = 0.05;
  pour.rate = 1000;
  pour.velocity = {0, 0, -1};
  s.emitters = {heap_top, pour};
  // fill the box: a lattice refuses a count larger than its box holds
  auto fits = [&](std::int64_t n) {
    s.emitters[0].count = n;
    try {
      World probe(s);
      return true;
    } catch (const InputError&) {
      return false;
    }
  };
  // (the largest count that fits, by doubling then bisection: a World per count tried, and a
  // walk up one by one built 498 of them, 42-67 s of the suite)
  std::int64_t n = 1, too_many = 2;
  while (fits(too_many)) n = std::exchange(too_many, 2 * too_many);
  while (too_many - n > 1) {
    const std::int64_t mid = n + (too_many - n) / 2;
    (fits(mid) ? n : too_many) = mid;
  }
  s.emitters[0].count = n;
  World w(s);
  Real max_overlap = 0;
  for (int f = 0; f < 10; ++f)
    max_overlap = std::max(max_overlap, w.advance_frame().max_overlap_rel);
  const Emitter& e = w.emitters()[1];
  EXPECT_EQ(w.total_grains(), n + e.emitted());
  return {e.emitted(), e.delayed(), max_overlap};
}

TEST(Emitters, PourSkipsSlotsTakenByGrainsAlreadyThere) {
  // half the disk covered: the pour uses the free half, and no new grain lands on an old one
  // (placed there, the two would be fired off)
  const PourUnderHeap half = pour_under_heap(0.0);
  EXPECT_GT(half.emitted, 0);
  EXPECT_EQ(half.max_overlap, 0.0);
  // all of it covered: nothing comes out, and every grain due is owed to a later batch
  const PourUnderHeap all = pour_under_heap(-0.06);
  EXPECT_EQ(all.emitted, 0);
  EXPECT_GT(all.delayed, 0);
  EXPECT_EQ(all.max_overlap, 0.0);
}

}  // namespace
}  // namespace sandflow
