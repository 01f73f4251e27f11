// The bowl: its exact signed distance against a dense sampling of its surface, its normals,
// inside/outside, bounds, sphere tracing through it, and grains poured into it.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "geometry/shapes.hpp"
#include "sdf_check.hpp"
#include "sim/world.hpp"

namespace sandflow {
namespace {

using testing::expect_tracing_never_crosses;
using testing::nearest_sample;
using testing::random_points;

struct BowlCase {
  Vec3 center;
  Real radius, thickness, depth;
  Vec3 rotation_deg;
};

// The solid, written independently of SolidBowl: the shell below the rim plane.
bool bowl_contains(const BowlCase& b, const Vec3& p) {
  const Vec3 q = rotation_xyz_deg(b.rotation_deg).transposed() * (p - b.center);
  const Real r = norm(q);
  return r >= b.radius && r <= b.radius + b.thickness && q.z <= b.depth - b.radius;
}

// Samples of the surface about `spacing` apart: the inner and outer caps (rings of constant
// polar angle) and the flat rim, in world coordinates.
std::vector<Vec3> bowl_surface(const BowlCase& b, Real spacing) {
  const Mat3 rot = rotation_xyz_deg(b.rotation_deg);
  const Real h = b.depth - b.radius;
  std::vector<Vec3> out;
  const auto ring = [&](Real rho, Real z) {
    const int n = std::max(1, static_cast<int>(std::ceil(2 * kPi * rho / spacing)));
    for (int k = 0; k < n; ++k) {
      const Real phi = 2 * kPi * k / n;
      out.push_back(b.center + rot * Vec3{rho * std::cos(phi), rho * std::sin(phi), z});
    }
  };
  for (Real a : {b.radius, b.radius + b.thickness}) {
    const Real theta_max = std::acos(-h / a);  // polar angle from the bottom pole to the rim
    const int n = static_cast<int>(std::ceil(a * theta_max / spacing));
    for (int k = 0; k <= n; ++k) {
      const Real theta = theta_max * k / n;
      ring(a * std::sin(theta), -a * std::cos(theta));
    }
  }
  const Real rim_in = std::sqrt(b.radius * b.radius - h * h);
  const Real rim_out = std::sqrt((b.radius + b.thickness) * (b.radius + b.thickness) - h * h);
  const int n = std::max(1, static_cast<int>(std::ceil((rim_out - rim_in) / spacing)));
  for (int k = 0; k <= n; ++k) ring(rim_in + (rim_out - rim_in) * k / n, h);
  return out;
}

const BowlCase kCases[] = {
    {{0, 0, 0}, 0.2, 0.03, 0.2, {0, 0, 0}},       // a hemisphere
    {{0.1, -0.2, 0.3}, 0.15, 0.02, 0.08, {20, -35, 10}},  // a shallow dish, tilted
    {{0, 0, 0}, 0.1, 0.04, 0.17, {0, 0, 0}},      // a deep bowl, its rim above the centre
};

TEST(Bowl, DistanceMatchesBruteForceAndClassifiesInside) {
  // Samples about s = 2 mm apart: every surface point is within s of a sample (rings s apart,
  // samples at most s apart along a ring), so the brute-force distance exceeds the true one by at
  // most s. The bowl's distance is exact, so it must lie in [brute - s, brute] (+ rounding).
  constexpr Real s = 2e-3;
  for (const BowlCase& b : kCases) {
    const SolidBowl bowl(b.center, b.radius, b.thickness, b.depth, rotation_xyz_deg(b.rotation_deg));
    const std::vector<Vec3> surface = bowl_surface(b, s);
    Vec3 lo, hi;
    bowl.bounds(lo, hi);
    for (const Vec3& p : random_points(lo, hi, 0.05, 300, 7)) {
      const SurfacePoint sp = bowl.closest(p);
      const auto bf = nearest_sample(surface, p);
      EXPECT_LE(std::abs(sp.distance), bf.distance + 1e-12) << "overestimates at " << p.x;
      EXPECT_GE(std::abs(sp.distance), bf.distance - s);
      EXPECT_EQ(sp.distance < 0, bowl_contains(b, p));
      EXPECT_NEAR(norm(sp.normal), 1.0, 1e-12);
      // the normal points away from the surface outside, towards it inside (the nearest sample is
      // within s of the nearest point, so the angle is small once the point is 10 s away)
      if (bf.distance > 10 * s) {
        const Vec3 away = (p - bf.point) / bf.distance;
        EXPECT_GT(dot(sp.normal, sp.distance > 0 ? away : -away), 0.9);
      }
    }
  }
}

TEST(Bowl, NormalIsTheGradientOfTheDistance) {
  // a step of 1e-6 along the normal changes the distance by the step (away from the medial
  // surfaces, which random points miss at this scale)
  for (const BowlCase& b : kCases) {
    const SolidBowl bowl(b.center, b.radius, b.thickness, b.depth, rotation_xyz_deg(b.rotation_deg));
    Vec3 lo, hi;
    bowl.bounds(lo, hi);
    for (const Vec3& p : random_points(lo, hi, 0.05, 300, 11)) {
      const SurfacePoint sp = bowl.closest(p);
      EXPECT_NEAR(bowl.closest(p + sp.normal * 1e-6).distance - sp.distance, 1e-6, 1e-9);
    }
  }
}

TEST(Bowl, HandValuesOfTheHemisphere) {
  // inner radius 1, thickness 0.1, rim plane through the centre
  const SolidBowl bowl({0, 0, 0}, 1.0, 0.1, 1.0, Mat3{});
  auto sp = bowl.closest({0, 0, 0});  // the centre: 1 above the inner bottom
  EXPECT_NEAR(sp.distance, 1.0, 1e-12);
  sp = bowl.closest({0, 0, -0.5});
  EXPECT_NEAR(sp.distance, 0.5, 1e-12);
  EXPECT_NEAR(sp.normal.z, 1.0, 1e-12);  // the inside of the bowl faces up at its bottom
  sp = bowl.closest({0, 0, -1.3});  // under the bowl
  EXPECT_NEAR(sp.distance, 0.2, 1e-12);
  EXPECT_NEAR(sp.normal.z, -1.0, 1e-12);
  sp = bowl.closest({0, 0, -1.04});  // in the wall, nearer the inside
  EXPECT_NEAR(sp.distance, -0.04, 1e-12);
  sp = bowl.closest({1.05, 0, 0.3});  // above the rim
  EXPECT_NEAR(sp.distance, 0.3, 1e-12);
  EXPECT_NEAR(sp.normal.z, 1.0, 1e-12);
  sp = bowl.closest({1.3, 0, 0.3});  // above and beyond the outer corner of the rim
  EXPECT_NEAR(sp.distance, std::hypot(0.2, 0.3), 1e-12);
  sp = bowl.closest({1.05, 0, -0.01});  // in the wall just under the rim
  EXPECT_NEAR(sp.distance, -0.01, 1e-12);
}

TEST(Bowl, BoundsHoldTheSurface) {
  for (const BowlCase& b : kCases) {
    const SolidBowl bowl(b.center, b.radius, b.thickness, b.depth, rotation_xyz_deg(b.rotation_deg));
    Vec3 lo, hi;
    bowl.bounds(lo, hi);
    for (const Vec3& q : bowl_surface(b, 5e-3))
      for (int i = 0; i < 3; ++i) {
        EXPECT_GE(q[i], lo[i] - 1e-12);
        EXPECT_LE(q[i], hi[i] + 1e-12);
      }
  }
  // unrotated, the bounds are tight: the outer radius around, the rim plane on top
  const SolidBowl dish({0, 0, 0}, 1.0, 0.1, 0.5, Mat3{});
  Vec3 lo, hi;
  dish.bounds(lo, hi);
  EXPECT_NEAR(hi.z, -0.5, 1e-12);
  EXPECT_NEAR(lo.z, -1.1, 1e-12);
  EXPECT_NEAR(hi.x, std::sqrt(1.1 * 1.1 - 0.25), 1e-12);
}

TEST(Bowl, SphereTracingNeverStepsAcrossTheSurface) {
  for (const BowlCase& b : kCases) {
    const SolidBowl bowl(b.center, b.radius, b.thickness, b.depth, rotation_xyz_deg(b.rotation_deg));
    Vec3 lo, hi;
    bowl.bounds(lo, hi);
    const auto inside = [&b](const Vec3& p) { return bowl_contains(b, p); };
    for (const Vec3& p : random_points(lo, hi, 0.02, 60, 3))
      expect_tracing_never_crosses(bowl, inside, p.x, p.y, hi.z + 0.1, lo.z - 0.1);
  }
}

// 200 grains dropped into a hemispherical bowl settle in it: above its inner surface, below its
// rim, and none inside the shell.
TEST(Bowl, HoldsPouredGrains) {
  SceneConfig s;
  s.path = "bowl";
  s.simulation.mode = Mode::Dem;
  GeometryConfig g;
  g.type = GeometryType::Bowl;
  g.center = {0, 0, 0.15};
  g.radius = 0.1;
  g.wall_thickness = 0.02;
  s.geometry = {g};
  EmitterConfig e;
  e.type = EmitterType::Lattice;
  e.count = 200;
  e.center = {0, 0, 0.19};
  e.size = {0.09, 0.09, 0.05};
  e.velocity = {0.3, 0.2, 0};
  s.emitters = {e};
  s.output.frames = 24;
  World w(s);
  for (int f = 0; f < 24; ++f) w.advance_frame();
  ASSERT_EQ(w.grains().x.size(), 200u);
  EXPECT_EQ(w.geometry().count_inside(w.grains().x), 0u);
  for (std::size_t i = 0; i < w.grains().x.size(); ++i) {
    const Vec3& p = w.grains().x[i];
    // inside the inner sphere by most of a radius (contacts overlap by ~1 % of d) and below the rim
    EXPECT_LT(norm(p - g.center), g.radius - 0.9 * w.grains().r[i]);
    EXPECT_LT(p.z, g.center.z);
  }
}

}  // namespace
}  // namespace sandflow
