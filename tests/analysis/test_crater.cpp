#include "analysis/crater.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <vector>

namespace sandflow {
namespace {

struct Bed {
  std::vector<Vec3> pos;
  std::vector<Real> radius;
};

// Columns of spheres of diameter d on a square lattice over [-half, half]^2, each stacked from
// z = 0 up to the surface top(x, y): the sand's top in a column is that surface to within d.
Bed lattice_bed(double d, double half, const std::function<double(double, double)>& top) {
  Bed b;
  const int n = static_cast<int>(half / d);
  for (int i = -n; i <= n; ++i)
    for (int j = -n; j <= n; ++j) {
      const double x = i * d + 0.013 * d, y = j * d - 0.021 * d;  // off the cells' edges
      for (double z = 0.5 * d; z + 0.5 * d <= top(x, y) + 0.5 * d; z += d) {
        b.pos.push_back({x, y, z});
        b.radius.push_back(0.5 * d);
      }
    }
  return b;
}

constexpr double kD = 0.01;      // grain diameter [m]
constexpr double kLevel = 0.10;  // the bed's top [m]

// A bowl of depth `depth` and radius `rc` at (cx, cy), with a rim of height `rim` at 1.3 rc.
std::function<double(double, double)> cratered(double depth, double rc, double rim, double cx,
                                               double cy) {
  return [=](double x, double y) {
    const double r = std::hypot(x - cx, y - cy);
    const double bowl = r < rc ? -depth * (1 - r * r / (rc * rc)) : 0.0;
    const double ring = rim * std::exp(-std::pow((r - 1.3 * rc) / (0.3 * rc), 2));
    return kLevel + bowl + ring;
  };
}

TEST(Crater, MeasuresDepthRimAndRadiusOfAKnownCrater) {
  const double depth = 0.05, rc = 0.12, rim = 0.02;
  const Bed b = lattice_bed(kD, 0.5, cratered(depth, rc, rim, 0.031, -0.017));
  const CraterFit f = measure_crater(b.pos, b.radius);
  ASSERT_TRUE(f.ok) << f.reason;
  // the map's heights are the stacks' tops, within a grain of the surface; the median of the
  // bed's cells is the untouched level (most of the bed is untouched)
  EXPECT_NEAR(f.centre.z, kLevel, 0.5 * kD);
  EXPECT_NEAR(f.depth, depth, kD);
  EXPECT_NEAR(f.rim_height, rim, kD);
  // the bowl meets the level at rc, but the rim's flank starts inside it: the profile crosses
  // the level a little before rc
  EXPECT_NEAR(f.radius, rc, 2 * kD);
  EXPECT_NEAR(f.rim_radius, 1.3 * rc, 2 * kD);
  EXPECT_NEAR(f.centre.x, 0.031, kD);
  EXPECT_NEAR(f.centre.y, -0.017, kD);
}

TEST(Crater, AGivenLevelAndCentreAreUsed) {
  const Bed b = lattice_bed(kD, 0.4, cratered(0.04, 0.1, 0.03, 0, 0));
  // a level one grain higher than the bed's makes the crater one grain deeper (the rim still
  // rises above it)
  const CraterFit f = measure_crater(b.pos, b.radius, kLevel + kD, 0.0, 0.0);
  ASSERT_TRUE(f.ok) << f.reason;
  EXPECT_NEAR(f.depth, 0.04 + kD, kD);
  EXPECT_DOUBLE_EQ(f.centre.x, 0.0);
  EXPECT_DOUBLE_EQ(f.centre.z, kLevel + kD);
  EXPECT_NEAR(f.rim_height, 0.03 - kD, kD);
}

TEST(Crater, NoRimWhenTheSurfaceNeverComesBackToTheLevel) {
  const Bed b = lattice_bed(kD, 0.4, cratered(0.04, 0.1, 0.0, 0, 0));
  const CraterFit f = measure_crater(b.pos, b.radius, kLevel + 2 * kD);
  EXPECT_FALSE(f.ok);
  EXPECT_NE(f.reason.find("no rim"), std::string::npos) << f.reason;
}

TEST(Crater, AFlatBedHasNoCraterEvenWithAHoleOfOneColumn) {
  Bed b = lattice_bed(kD, 0.2, [](double, double) { return kLevel; });
  // take out one whole column: the median over its neighbours fills it
  std::vector<Vec3> pos;
  std::vector<Real> radius;
  for (std::size_t k = 0; k < b.pos.size(); ++k)
    if (std::hypot(b.pos[k].x, b.pos[k].y) > 0.5 * kD) {
      pos.push_back(b.pos[k]);
      radius.push_back(b.radius[k]);
    }
  ASSERT_LT(pos.size(), b.pos.size());
  const CraterFit f = measure_crater(pos, radius);
  EXPECT_FALSE(f.ok);
  EXPECT_NE(f.reason.find("no crater"), std::string::npos) << f.reason;
}

TEST(Crater, RefusesNoGrainsAndMismatchedArrays) {
  EXPECT_FALSE(measure_crater({}, {}).ok);
  EXPECT_THROW(measure_crater({{0, 0, 0}}, {}), std::invalid_argument);
}

}  // namespace
}  // namespace sandflow
