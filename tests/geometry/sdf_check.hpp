// Brute-force checks of a Solid's signed distance, shared by the tests of the shapes: the surface
// is sampled densely (the caller supplies the samples and their spacing) and compared with
// closest() at random points.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <vector>

#include "core/rng.hpp"
#include "geometry/shapes.hpp"

namespace sandflow::testing {

/// Nearest sample of the surface to p: its distance and the sample.
struct Nearest {
  Real distance;
  Vec3 point;
};

inline Nearest nearest_sample(const std::vector<Vec3>& surface, const Vec3& p) {
  Nearest best{std::numeric_limits<Real>::infinity(), {}};
  for (const Vec3& s : surface) {
    const Real d2 = norm2(p - s);
    if (d2 < best.distance) best = {d2, s};
  }
  best.distance = std::sqrt(best.distance);
  return best;
}

/// Random points in the box [lo - margin, hi + margin].
inline std::vector<Vec3> random_points(const Vec3& lo, const Vec3& hi, Real margin, int n,
                                       std::uint64_t seed) {
  Rng rng(seed);
  std::vector<Vec3> out;
  for (int k = 0; k < n; ++k)
    out.push_back({rng.uniform(lo.x - margin, hi.x + margin), rng.uniform(lo.y - margin, hi.y + margin),
                   rng.uniform(lo.z - margin, hi.z + margin)});
  return out;
}

/// Sphere tracing down the vertical line through (x, y) by closest() from z_top to z_bottom never
/// steps across the surface: between two consecutive points of the trace, finely subsampled,
/// the exact classification `inside` does not change unless the step ended on the surface (a hit).
/// The trace continues through the solid (by |d|), as a tracer of all solid intervals does.
inline void expect_tracing_never_crosses(const Solid& solid, const std::function<bool(const Vec3&)>& inside,
                                         Real x, Real y, Real z_top, Real z_bottom) {
  constexpr Real kHit = 1e-7, kStepPastHit = 2e-7;
  Vec3 p{x, y, z_top};
  for (int it = 0; it < 100000 && p.z > z_bottom; ++it) {
    const Real d = solid.closest(p).distance;
    const Real step = std::abs(d) < kHit ? kStepPastHit : std::abs(d);
    if (std::abs(d) >= kHit) {
      // every point strictly within the step keeps the classification of its start
      const bool start = inside(p);
      for (int k = 1; k < 16; ++k) {
        const Vec3 q{x, y, p.z - step * k / 16.0 * (1 - 1e-9)};
        ASSERT_EQ(inside(q), start) << "a step of " << step << " from z = " << p.z << " at (" << x
                                    << ", " << y << ") crosses the surface near z = " << q.z;
      }
    }
    p.z -= step;
  }
}

}  // namespace sandflow::testing
