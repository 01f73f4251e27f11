#include "analysis/crater.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include "geometry/shapes.hpp"
#include "sim/emitters.hpp"
#include "support/test_scenes.hpp"

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

// A scene of a bed `size` wide and `height` deep in a sandbox and a block of 1 cm grains thrown
// from `centre` (its box 0.1 m a side) at `velocity`.
SceneConfig impact_scene(double size, double height, const Vec3& centre, const Vec3& velocity) {
  SceneConfig s = test::grains_on_floor("impact", Mode::Dem, kD);
  GeometryConfig box = test::box_entry({0, 0, 0.2}, {size, size, 0.4});
  box.container = true;
  s.geometry = {box};
  EmitterConfig bed;
  bed.type = EmitterType::Bed;
  bed.name = "bed";
  bed.size = {size, size, 0};
  bed.height = height;
  EmitterConfig block;
  block.type = EmitterType::Block;
  block.name = "clod";
  block.center = centre;
  block.size = {0.1, 0.1, 0.1};
  block.velocity = velocity;
  block.count = 100;
  s.emitters = {bed, block};
  return s;
}

TEST(CraterSite, TheCentreIsWhereTheBlockComesDownToTheBedsTop) {
  // dropped from rest: the block's bottom (z 0.3) falls 0.2 m to the bed's top in
  // t = sqrt(2 * 0.2 / g), carried 1.5 m/s * t sideways
  const double g = 9.81, t = std::sqrt(2 * 0.2 / g);
  const SceneConfig s = impact_scene(1.0, 0.1, {-0.2, 0.1, 0.35}, {1.5, 0, 0});
  const CraterSite site = crater_site(s);
  ASSERT_TRUE(site.bed);
  EXPECT_EQ(site.bed_index, 0u);
  EXPECT_DOUBLE_EQ(site.height, 0.1);
  EXPECT_NEAR(site.cx, -0.2 + 1.5 * t, 1e-12);
  EXPECT_NEAR(site.cy, 0.1, 1e-12);
  EXPECT_NE(site.centre_from.find("'clod' lands"), std::string::npos) << site.centre_from;
  EXPECT_DOUBLE_EQ(site.x0, -0.5);
  EXPECT_DOUBLE_EQ(site.y1, 0.5);
  // thrown down at 7 m/s: z(t) = 0.3 - 7 t - g t^2 / 2 = 0.1 at t = (-7 + sqrt(49 + 2 g 0.2)) / g
  const double t7 = (-7 + std::sqrt(49 + 2 * g * 0.2)) / g;
  const CraterSite down = crater_site(impact_scene(1.0, 0.1, {0, 0, 0.35}, {1, -2, -7}));
  EXPECT_NEAR(down.cx, 1 * t7, 1e-12);
  EXPECT_NEAR(down.cy, -2 * t7, 1e-12);
}

TEST(CraterSite, WithoutOneThrownEmitterOverTheBedTheCentreIsFoundFromTheGrains) {
  // thrown so far that it comes down beyond the bed
  const CraterSite off = crater_site(impact_scene(0.5, 0.1, {0, 0, 0.35}, {20, 0, 0}));
  EXPECT_TRUE(off.bed);
  EXPECT_TRUE(std::isnan(off.cx));
  EXPECT_NE(off.centre_from.find("no bed's top"), std::string::npos) << off.centre_from;
  // thrown up under a gravity that points up: it never comes down
  SceneConfig up = impact_scene(0.5, 0.1, {0, 0, 0.35}, {0, 0, 1});
  up.simulation.gravity = {0, 0, 9.81};
  EXPECT_TRUE(std::isnan(crater_site(up).cx));
  // two thrown emitters
  SceneConfig two = impact_scene(0.5, 0.1, {0, 0, 0.35}, {0, 0, -1});
  two.emitters.push_back(two.emitters[1]);
  const CraterSite site = crater_site(two);
  EXPECT_TRUE(std::isnan(site.cx));
  EXPECT_NE(site.centre_from.find("several"), std::string::npos) << site.centre_from;
  // no bed: no crater is sought, and none is measured
  SceneConfig none = impact_scene(0.5, 0.1, {0, 0, 0.35}, {0, 0, -1});
  none.emitters.erase(none.emitters.begin());
  const CraterSite no_bed = crater_site(none);
  EXPECT_FALSE(no_bed.bed);
  const CraterFit f = measure_crater(no_bed, kLevel, {{0, 0, 0}}, {0.005});
  EXPECT_FALSE(f.ok);
  EXPECT_NE(f.reason.find("no bed"), std::string::npos) << f.reason;
}

TEST(CraterSite, TheBedIsTheOneTheBlockComesDownOn) {
  // two beds side by side, the second (x > 0) higher; the block falls onto the second
  SceneConfig s = impact_scene(1.0, 0.1, {0.25, 0, 0.35}, {0, 0, 0});
  EmitterConfig left = s.emitters[0], right = s.emitters[0];
  left.center = {-0.25, 0, 0};
  left.size = {0.5, 1.0, 0};
  right.center = {0.25, 0, 0};
  right.size = {0.5, 1.0, 0};
  right.height = 0.15;
  s.emitters = {left, right, s.emitters[1]};
  const CraterSite site = crater_site(s);
  EXPECT_EQ(site.bed_index, 1u);
  EXPECT_DOUBLE_EQ(site.height, 0.15);
  EXPECT_DOUBLE_EQ(site.x0, 0.0);
  EXPECT_NEAR(site.cx, 0.25, 1e-12);
}

TEST(CraterSite, GrainsOutsideTheBedAreNotItsSurface) {
  // a crater at (0.1, 0) in a bed over [-0.3, 0.3]^2, and ejecta on the ground beyond its walls:
  // left in, the lowest cells would be the ejecta's, and the centre found among them
  Bed b = lattice_bed(kD, 0.3, cratered(0.04, 0.08, 0.01, 0.1, 0));
  for (double y = -0.1; y <= 0.1; y += kD) {
    b.pos.push_back({0.45, y, 0.5 * kD});
    b.radius.push_back(0.5 * kD);
  }
  SceneConfig s = impact_scene(0.6, kLevel, {0, 0, 0.35}, {0, 0, -1});
  s.emitters.push_back(s.emitters[1]);  // two thrown: the centre is found from the grains
  const CraterSite site = crater_site(s);
  ASSERT_TRUE(std::isnan(site.cx));
  const CraterFit f = measure_crater(site, kLevel, b.pos, b.radius);
  ASSERT_TRUE(f.ok) << f.reason;
  EXPECT_NEAR(f.centre.x, 0.1, kD);
  EXPECT_NEAR(f.depth, 0.04, kD);
}

TEST(BedLevel, IsTheTopOfAFlatBed) {
  // stacks up to kLevel: each column's top within half a grain below it (the lattice's stacks)
  const Bed flat = lattice_bed(kD, 0.2, [](double, double) { return kLevel; });
  EXPECT_LE(bed_level(flat.pos, flat.radius), kLevel + 1e-12);
  EXPECT_GT(bed_level(flat.pos, flat.radius), kLevel - kD);
  EXPECT_TRUE(std::isnan(bed_level({}, {})));
}

TEST(BedLevel, APackedBedsTopLiesWithinHalfAGrainBelowItsHeight) {
  // the bed emitter's drop-and-roll packing: no grain above `height`, its top full to within
  // about half a diameter (docs/scenes.md, "The bed"); the 3x3 median of the highest tops sits
  // between the two
  SceneConfig s = impact_scene(0.4, 0.06, {0, 0, 0.35}, {0, 0, -1});
  s.material.diameter_spread = 0.1;
  const Geometry g = Geometry::from_config(s.geometry, s.material, s.path);
  BedPacking bed;
  ASSERT_FALSE(pack_bed_emitter(s.emitters[0], s.material, g, bed_seed(1, 0), bed));
  const double level = bed_level(bed.x, bed.r);
  EXPECT_LT(level, 0.06);
  EXPECT_GT(level, 0.06 - 0.5 * kD);
}

}  // namespace
}  // namespace sandflow
