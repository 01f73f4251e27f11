// Analytic solids: signed distances and normals against hand-computed values, and containers
// that keep grains in.
#include <gtest/gtest.h>

#include <cmath>

#include "core/error.hpp"
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
  std::int64_t n = 1;
  while (fits(n + 1)) ++n;
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
