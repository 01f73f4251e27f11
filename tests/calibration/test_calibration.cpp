// The calibration rig (src/calibration): a small heap on a rough disk, tilted until it fails.
// Run here on a base of 7 diameters and a fast tilt, so a trial takes seconds; the command's
// own rig (10 diameters, 2 deg/s) is measured in docs/physics.md.
#include "calibration/calibration.hpp"

#include <gtest/gtest.h>

#include "core/error.hpp"
#include "support/sanitizers.hpp"

namespace sandflow {
namespace {

SceneConfig sand() {
  SceneConfig s;
  s.path = "test";
  s.material.diameter = 0.01;
  s.material.diameter_spread = 0.1;
  s.material.friction = 0.6;
  s.material.rolling_friction = 0.3;
  s.material.wall_friction = 0.6;
  s.material.wall_rolling_friction = 0.3;
  s.stiffness.from_load = true;
  s.stiffness.max_overlap = 0.01;
  s.stiffness.impact_overlap = 0.25;
  s.simulation.threads = 2;
  return s;
}

const RigSettings kSmallRig{7, 6};

TEST(Calibration, ATinyHeapGivesTheSameAnglesEveryTimeAndFailsAboveWhereItStood) {
  const Calibration a = calibrate(sand(), 1, {}, kSmallRig);
  ASSERT_EQ(a.trials.size(), 1u);
  const CalibrationTrial& t = a.trials[0];
  ASSERT_TRUE(t.poured.ok);
  ASSERT_TRUE(t.failed) << "still standing at a tilt of " << t.tilt_deg;
  // a sand-like material on a rough base: a heap, not a layer, and not a column
  EXPECT_GT(t.theta0_deg, 18.0);
  EXPECT_LT(t.theta0_deg, 50.0);
  // a static slope fails above the angle it was poured at: the tilt at failure is positive
  EXPECT_GT(t.tilt_deg, 1.0);
  EXPECT_DOUBLE_EQ(a.theta_max_deg, t.theta0_deg + t.tilt_deg);
  EXPECT_DOUBLE_EQ(a.theta0_deg, t.theta0_deg);
  // deterministic: the same seed gives the same angles to the last bit
  const Calibration b = calibrate(sand(), 1, {}, kSmallRig);
  EXPECT_EQ(b.theta0_deg, a.theta0_deg);
  EXPECT_EQ(b.theta_max_deg, a.theta_max_deg);
}

TEST(Calibration, LessFrictionGivesALowerHeap) {
  // (61 s under the sanitizers; ATinyHeapGivesTheSameAnglesEveryTime... runs the same rig)
  if constexpr (test::kSanitizers) GTEST_SKIP() << "two heaps, left to the Release suite";
  SceneConfig slippery = sand();
  slippery.material.friction = 0.2;
  slippery.material.rolling_friction = 0.02;
  const Calibration rough = calibrate(sand(), 1, {}, kSmallRig);
  const Calibration smooth = calibrate(slippery, 1, {}, kSmallRig);
  // a third of the friction lowers the heap by far more than a small heap's spread of a few
  // degrees (measured 2026-11-26 on this rig: 24.8 and 15.5 degrees)
  EXPECT_LT(smooth.theta0_deg, rough.theta0_deg - 5.0)
      << smooth.theta0_deg << " against " << rough.theta0_deg;
}

TEST(Calibration, TheKeyFollowsTheMaterialNotTheScene) {
  SceneConfig a = sand();
  SceneConfig b = sand();
  b.name = "another scene";
  b.emitters.resize(3);
  b.simulation.seed = 7;
  EXPECT_EQ(calibration_key(a), calibration_key(b));
  b.material.friction = 0.5;
  EXPECT_NE(calibration_key(a), calibration_key(b));
  SceneConfig c = sand();
  c.material.diameter_spread = 0.2;
  EXPECT_NE(calibration_key(a), calibration_key(c));
  SceneConfig e = sand();
  e.simulation.gravity = {0, 0, -1.62};
  EXPECT_NE(calibration_key(a), calibration_key(e));
}

TEST(Calibration, TheKeyHoldsTheDemFingerprintSoNoCacheOutlivesTheCode) {
  const SceneConfig a = sand();
  const std::uint64_t f = dem_fingerprint(a);
  EXPECT_EQ(dem_fingerprint(a), f);  // deterministic
  EXPECT_EQ(calibration_key(a), calibration_key(a, {}, f));
  // code that computes other results measures other angles: another key
  EXPECT_NE(calibration_key(a, {}, f), calibration_key(a, {}, f + 1));
}

TEST(Calibration, TheFingerprintsProbeExercisesEveryPartOfTheLaw) {
  // each part of the contact law that the calibration's heap depends on acts in the probe, so a
  // change of the code in any of them changes the fingerprint
  const std::uint64_t f = dem_fingerprint(sand());
  const auto changed = [&](auto set) {
    SceneConfig s = sand();
    set(s.material);
    return dem_fingerprint(s) != f;
  };
  EXPECT_TRUE(changed([](MaterialConfig& m) { m.friction = 0.59; }));
  EXPECT_TRUE(changed([](MaterialConfig& m) { m.rolling_friction = 0.29; }));
  EXPECT_TRUE(changed([](MaterialConfig& m) { m.wall_friction = 0.59; }));
  EXPECT_TRUE(changed([](MaterialConfig& m) { m.wall_rolling_friction = 0.29; }));
  EXPECT_TRUE(changed([](MaterialConfig& m) { m.restitution *= 0.99; }));
  EXPECT_TRUE(changed([](MaterialConfig& m) { m.tangential_damping_ratio *= 0.99; }));
  EXPECT_TRUE(changed([](MaterialConfig& m) { m.rolling_stiffness_ratio *= 0.99; }));
  EXPECT_TRUE(changed([](MaterialConfig& m) { m.twisting_friction = 0.05; }));
  EXPECT_TRUE(changed([](MaterialConfig& m) { m.wall_twisting_friction = 0.05; }));
  EXPECT_TRUE(changed([](MaterialConfig& m) { m.diameter_spread = 0.12; }));
}

TEST(Calibration, NoGravityIsRefused) {
  SceneConfig s = sand();
  s.simulation.gravity = {0, 0, 0};
  EXPECT_THROW(calibrate(s, 1, {}, kSmallRig), InputError);
}

}  // namespace
}  // namespace sandflow
