#include "analysis/heap.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "core/rng.hpp"

namespace sandflow {
namespace {

struct Spheres {
  std::vector<Vec3> pos;
  std::vector<Real> radius;
};

// Spheres of radius r on a cubic lattice of spacing 2r, resting on z = 0, filling the cone
// z <= h - rho * tan(angle) around the apex (ax, ay). The lattice is anchored at the origin, not
// at the apex, so the apex falls between lattice columns as in a real pile.
Spheres lattice_cone(double angle_deg, double ax, double ay, double r, double h) {
  const double d = 2 * r, t = std::tan(deg_to_rad(angle_deg));
  const double base = h / t;
  Spheres g;
  const int n = static_cast<int>(std::ceil(base / d)) + 1;
  const int ix0 = static_cast<int>(std::floor(ax / d)), iy0 = static_cast<int>(std::floor(ay / d));
  for (int i = ix0 - n; i <= ix0 + n; ++i) {
    for (int j = iy0 - n; j <= iy0 + n; ++j) {
      const double x = i * d, y = j * d;
      const double top = h - std::hypot(x - ax, y - ay) * t;
      for (double z = r; z <= top; z += d) {
        g.pos.push_back({x, y, z});
        g.radius.push_back(r);
      }
    }
  }
  return g;
}

TEST(Heap, LatticeCone30Degrees) {
  // Apex away from the origin and between lattice columns: the apex search must find it.
  const double r = 0.005, d = 2 * r, h = 16 * d;
  const double ax = 0.3725, ay = -0.2135;
  const Spheres g = lattice_cone(30.0, ax, ay, r, h);
  const HeapFit fit = measure_heap(g.pos, g.radius);
  ASSERT_TRUE(fit.ok) << fit.reason;
  // 2 degrees: the lattice turns the flank into a staircase of one-diameter steps.
  EXPECT_NEAR(fit.repose_angle_deg, 30.0, 2.0);
  // The summit lies within a diameter or two of the true apex (lattice columns are d apart).
  // The lattice columns are d apart: the summit is found within half a column spacing.
  EXPECT_NEAR(fit.apex.x, ax, 0.5 * d);
  EXPECT_NEAR(fit.apex.y, ay, 0.5 * d);
  // Hh is the median grain top of the cells within d of the apex: the cone surface there lies
  // between h - d tan(30) and h, and a lattice grain's top lies within r of the surface.
  EXPECT_GT(fit.height, h - d * std::tan(deg_to_rad(30.0)) - r);
  EXPECT_LE(fit.height, h + r);
  // The fitted line meets the floor near the cone's base: a diameter for the staircase.
  EXPECT_NEAR(fit.base_radius, h / std::tan(deg_to_rad(30.0)), d);
  EXPECT_GE(fit.points_used, 4);
  // Staircase residuals: steps of one diameter give an RMS well under d / 2.
  EXPECT_LT(fit.fit_rms, 0.5 * d);
}

TEST(Heap, LatticeCone35Degrees) {
  const double r = 0.005, h = 16 * 2 * r;
  const Spheres g = lattice_cone(35.0, -1.1337, 0.5861, r, h);
  const HeapFit fit = measure_heap(g.pos, g.radius);
  ASSERT_TRUE(fit.ok) << fit.reason;
  EXPECT_NEAR(fit.repose_angle_deg, 35.0, 2.0);
  EXPECT_NEAR(fit.apex.x, -1.1337, r);
  EXPECT_NEAR(fit.apex.y, 0.5861, r);
}

TEST(Heap, StrayGrainOnTopDoesNotMoveApex) {
  const double r = 0.005, h = 16 * 2 * r;
  Spheres g = lattice_cone(30.0, 0.3725, -0.2135, r, h);
  // A loose grain high above the flank, far from the apex.
  g.pos.push_back({0.3725 + 0.2, -0.2135, h + 0.1});
  g.radius.push_back(r);
  const HeapFit fit = measure_heap(g.pos, g.radius, 0.0);
  ASSERT_TRUE(fit.ok) << fit.reason;
  EXPECT_NEAR(fit.apex.x, 0.3725, r);
  EXPECT_NEAR(fit.repose_angle_deg, 30.0, 2.0);
}

TEST(Heap, JitteredConeOnFloorHeight) {
  // Random offsets of a tenth of a diameter and an explicit floor below the lowest grain.
  const double r = 0.005, h = 16 * 2 * r;
  Spheres g = lattice_cone(32.0, 0.0, 0.0, r, h);
  Rng rng(7);
  auto u = [&rng] { return static_cast<double>(rng.next() >> 11) * 0x1.0p-53 - 0.5; };
  for (Vec3& p : g.pos) p += Vec3{u(), u(), u()} * (0.2 * r);
  for (Vec3& p : g.pos) p.z += 0.5;  // heap standing on a table at z = 0.5
  const HeapFit fit = measure_heap(g.pos, g.radius, 0.5);
  ASSERT_TRUE(fit.ok) << fit.reason;
  EXPECT_NEAR(fit.repose_angle_deg, 32.0, 2.0);
  // Same bound as the lattice cone's height, widened by the jitter of a tenth of a diameter.
  EXPECT_NEAR(fit.apex.z, 0.5 + h, 2 * r);
}

TEST(Heap, FlatLayerHasNoAngle) {
  Spheres g;
  const double r = 0.005;
  for (int i = 0; i < 60; ++i) {
    for (int j = 0; j < 60; ++j) {
      for (int k = 0; k < 2; ++k) {
        g.pos.push_back({i * 2 * r, j * 2 * r, r + k * 2 * r});
        g.radius.push_back(r);
      }
    }
  }
  const HeapFit fit = measure_heap(g.pos, g.radius);
  EXPECT_FALSE(fit.ok);
  EXPECT_NE(fit.reason.find("no flank"), std::string::npos) << fit.reason;
}

TEST(Heap, ASpreadOutLayerIsNotAHeap) {
  // What 3,000 grains poured too fast made: a layer 3.5 diameters high at its centre, thinning
  // over 40 diameters. A line fits it well (3 degrees), but its flank band spans under two grain
  // layers: reported as no flank, not as an angle.
  const double r = 0.005, h = 3.5 * 2 * r;
  const Spheres g = lattice_cone(3.0, 0.0, 0.0, r, h);
  const HeapFit fit = measure_heap(g.pos, g.radius, 0.0);
  EXPECT_FALSE(fit.ok);
  EXPECT_TRUE(std::isnan(fit.repose_angle_deg));
  EXPECT_NE(fit.reason.find("no flank"), std::string::npos) << fit.reason;
  // four diameters high, the same cone is a heap (its band spans two layers)
  const HeapFit taller = measure_heap(lattice_cone(3.0, 0.0, 0.0, r, 4.5 * 2 * r).pos,
                                      lattice_cone(3.0, 0.0, 0.0, r, 4.5 * 2 * r).radius, 0.0);
  EXPECT_TRUE(taller.ok) << taller.reason;
}

TEST(Heap, StandardErrorFallsAsTheFlankGrows) {
  // The same staircase of single grains along a longer flank: more rings, a surer slope. The
  // standard error is the slope's, sqrt(SSE / (n - 2) / Srr), carried through atan.
  const double r = 0.005;
  const Spheres small = lattice_cone(32.0, 0.0, 0.0, r, 8 * 2 * r);
  const Spheres large = lattice_cone(32.0, 0.0, 0.0, r, 32 * 2 * r);
  const HeapFit a = measure_heap(small.pos, small.radius, 0.0);
  const HeapFit b = measure_heap(large.pos, large.radius, 0.0);
  ASSERT_TRUE(a.ok && b.ok);
  EXPECT_GT(b.repose_angle_se_deg, 0.0);
  EXPECT_LT(b.repose_angle_se_deg, 0.5 * a.repose_angle_se_deg);
  // the true angle lies within a few standard errors plus the staircase's bias
  EXPECT_LT(std::abs(b.repose_angle_deg - 32.0), 2.0);
}

TEST(Heap, EmptyAndBadInput) {
  const HeapFit none = measure_heap({}, {});
  EXPECT_FALSE(none.ok);
  EXPECT_FALSE(none.reason.empty());
  EXPECT_TRUE(std::isnan(none.repose_angle_deg));

  // Only non-finite grains: nothing usable, no crash.
  const double nan = std::nan("");
  const HeapFit bad = measure_heap({{nan, 0, 0}, {0, 0, 0}}, {0.01, -1.0});
  EXPECT_FALSE(bad.ok);

  EXPECT_THROW(measure_heap({{0, 0, 0}}, {}), std::invalid_argument);
  EXPECT_THROW(measure_heap({{0, 0, 0}}, {0.01}, 0.0, 0.8, 0.2), std::invalid_argument);
}

TEST(Heap, NarrowBandCanRefuse) {
  // A band that spans under two grain layers: refused with a reason, not a wrong angle.
  const double r = 0.005, h = 8 * 2 * r;
  const Spheres g = lattice_cone(30.0, 0.0, 0.0, r, h);
  const HeapFit fit = measure_heap(g.pos, g.radius, 0.0, 0.45, 0.55);
  EXPECT_FALSE(fit.ok);
  EXPECT_NE(fit.reason.find("no flank"), std::string::npos) << fit.reason;
}

TEST(Heap, ASteepShortFlankHasTooFewPoints) {
  // 60 degrees over 8 diameters: the band's four diameters of rise lie within 2.3 diameters
  // of radius, fewer than four rings.
  const double r = 0.005, h = 8 * 2 * r;
  const Spheres g = lattice_cone(60.0, 0.0, 0.0, r, h);
  const HeapFit fit = measure_heap(g.pos, g.radius, 0.0);
  EXPECT_FALSE(fit.ok);
  EXPECT_NE(fit.reason.find("profile points"), std::string::npos) << fit.reason;
}

}  // namespace
}  // namespace sandflow
