// The blow rule (surface.blows; SurfaceFlow::apply_impacts): a clod striking a bed born static
// opens it as far as its whole momentum reaches, shared with the bed at the flow speed
// (blow_radius), not only under its grains; without the rule only the columns under the clod
// open. The blow's record is what the grains brought, and a run with a blow under way restarts
// bit for bit.
#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <filesystem>

#include "checkpoint/checkpoint.hpp"
#include "scene/scene_loader.hpp"
#include "sim/world.hpp"
#include "surface/seat.hpp"

namespace sandflow {
namespace {

namespace fs = std::filesystem;
const fs::path kScene = fs::path(SANDFLOW_SOURCE_DIR) / "tests/data/scenes/impact_small.toml";
constexpr Real kD = 0.01, kTop = 0.05;  // the scene's grain and its bed's top

// A clod of 125 grains thrown down at 6 m/s onto a bed 26 cm wide and 5 cm deep, born static;
// frames of 5 ms, so that a frame ends while the blow is under way.
SceneConfig impact(bool blows) {
  SceneConfig s = load_scene(kScene.string());
  s.surface.blows = blows;
  s.output.fps = 200;
  return s;
}

// The farthest column centre from the impact's axis whose static top lies 2 d or more under the
// bed's top [m], over the bed's inside (the columns along the sandbox's walls are not the bed's:
// docs/known-issues.md).
Real farthest_opened(const HeightField& hf) {
  Real far = 0;
  for (std::size_t c = 0; c < hf.columns(); ++c) {
    const Vec3 x = hf.centre(c);
    if (std::max(std::abs(x.x), std::abs(x.y)) > 0.13 - 3 * kD) continue;
    if (hf.static_top()[c] < kTop - 2 * kD) far = std::max(far, std::hypot(x.x, x.y));
  }
  return far;
}

TEST(Blows, AClodOpensTheBedAsFarAsItsMomentumReachesAndOnlyWithTheRule) {
  omp_set_num_threads(1);
  Real opened[2] = {0, 0};
  for (int with = 0; with < 2; ++with) {
    World w(impact(with == 1));
    Real widest = 0, widest_now = 0;
    std::size_t most_blows = 0;
    for (int f = 0; f < 8; ++f) {  // 40 ms: the clod lands at about 11 ms
      w.advance_frame();
      if (f < 4)  // (later, the ejecta open the columns where they land)
        opened[with] = std::max(opened[with], farthest_opened(w.surface()->height_field()));
      const SurfaceState st = w.surface()->save_state();
      most_blows = std::max(most_blows, st.blows.size());
      widest_now = 0;
      for (const Blow& b : st.blows) {
        // what it received is what the clod's grains brought down, at most their momentum
        // when thrown (125 grains of 1 cm at 6 m/s, and what gravity adds over 7 cm: 6.1 m/s)
        const Real m1 = 2600 * kPi / 6 * kD * kD * kD;
        EXPECT_LE(b.p0, 125 * 1.1 * 1.331 * m1 * 6.2);  // (radii up to 1.1 r: mass 1.331 m1)
        EXPECT_LE(b.p, b.p0);
        // its radius is the one its momentum sets moving
        const Real n = static_cast<Real>(b.n), d = b.d / n;
        const SeatParams& seat = w.surface()->params().interface.seat;
        EXPECT_NEAR(b.rho, blow_radius(b.p / (b.m / n), seat.move_speed(d / 2), d),
                    1e-12);
        widest = std::max(widest, b.rho);
        widest_now = std::max(widest_now, b.rho);
      }
    }
    if (with == 1) {
      EXPECT_GE(most_blows, 1u);
      // 125 grains at 6 m/s against v_flow = 0.099 m/s: about 14 d undecayed, less as the first
      // grains' share decays (over sqrt(rho / g)) before the last arrive
      EXPECT_GT(widest, 6 * kD);
      EXPECT_LT(widest, 15 * kD);
      // 30 ms after the landing the crater is still growing (its time, sqrt(rho / g), is 0.11 s
      // at 13 d): the blow holds most of its widest radius (0.95 of it), where friction's 17 ms
      // alone shrank it to 0.68
      EXPECT_GT(widest_now, 0.8 * widest) << widest_now << " " << widest;
    } else {
      EXPECT_EQ(most_blows, 0u);
    }
  }
  // in the first 20 ms: the clod is 6 cm wide, and its own grains open the columns within a
  // grain or two of it (3 d about the axis, and 2 d); the blow as far as its radius
  EXPECT_LT(opened[0], 6 * kD) << opened[0] << " " << opened[1];
  EXPECT_GT(opened[1], 10 * kD) << opened[0] << " " << opened[1];
}

TEST(Blows, ARunWithABlowUnderWayRestartsBitForBit) {
  omp_set_num_threads(1);
  const SceneConfig s = impact(true);
  World straight(s);
  std::vector<FrameStats> want;
  for (int f = 0; f < 8; ++f) want.push_back(straight.advance_frame());

  World first(s);
  Checkpoint c;
  for (int f = 0; f < 4; ++f) c.frames.push_back(first.advance_frame());  // 20 ms
  ASSERT_FALSE(first.surface()->save_state().blows.empty()) << "no blow under way to save";
  ASSERT_FALSE(first.surface()->save_state().counted.empty());
  c.scene_hash = scene_hash(first, "test");
  c.world = first.save_state();
  const std::string bytes = encode_checkpoint(c);
  World resumed(s);
  restore_checkpoint(resumed, parse_checkpoint(bytes, "test.bin"), scene_hash(resumed, "test"),
                     "test.bin");
  // what was saved comes back, and the run goes on as if it had never stopped
  Checkpoint again = c;
  again.world = resumed.save_state();
  EXPECT_TRUE(encode_checkpoint(again) == bytes) << "the restored state saves differently";
  for (int f = 4; f < 8; ++f) {
    const FrameStats a = resumed.advance_frame(), &b = want[static_cast<std::size_t>(f)];
    EXPECT_EQ(a.n_active, b.n_active) << "frame " << f + 1;
    EXPECT_EQ(a.n_static, b.n_static) << "frame " << f + 1;
    EXPECT_EQ(a.kinetic_energy, b.kinetic_energy) << "frame " << f + 1;
  }
  EXPECT_EQ(resumed.state_hash(), straight.state_hash());
}

}  // namespace
}  // namespace sandflow
