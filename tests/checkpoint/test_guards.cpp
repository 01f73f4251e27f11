// Guards (docs/scenes.md, [simulation]): a run that leaves its valid range stops with the step and
// the grain — an overlap past max_overlap_stop, a non-finite grain, a grain leaving the domain —
// or, with on_leave = "count", removes leaving grains and counts them. And the scene keys that
// set them are validated like every other key.
#include <gtest/gtest.h>

#include <cctype>
#include <limits>
#include <string>

#include "core/error.hpp"
#include "scene/scene_loader.hpp"
#include "sim/world.hpp"
#include "support/test_scenes.hpp"

namespace sandflow {
namespace {

EmitterConfig one_grain(const Vec3& at, const Vec3& v) {
  EmitterConfig e;
  e.type = EmitterType::Block;
  e.center = at;
  e.size = {0.011, 0.011, 0.011};
  e.count = 1;
  e.jitter = 0;
  e.velocity = v;
  return e;
}

SceneConfig bare_scene() {
  SceneConfig s;
  s.path = "guards";
  s.simulation.mode = Mode::Dem;
  s.material.diameter = 0.01;
  s.material.k_n = 1e4;
  s.output.fps = 30;
  return s;
}

/// Runs up to `frames` frames; returns the SimulationError's message ("" when none).
std::string run_until_stopped(World& w, int frames) {
  try {
    for (int f = 0; f < frames; ++f) w.advance_frame();
  } catch (const SimulationError& e) {
    return e.what();
  }
  return "";
}

/// N of a message that starts "step N (frame F, t = ..." (-1 otherwise).
long long step_of(const std::string& msg) {
  if (msg.rfind("step ", 0) != 0) return -1;
  std::size_t end = 5;
  while (end < msg.size() && std::isdigit(static_cast<unsigned char>(msg[end]))) ++end;
  if (end == 5 || msg.compare(end, 8, " (frame ") != 0) return -1;
  return std::stoll(msg.substr(5, end - 5));
}

TEST(Guards, ARunawayOverlapWithAWallNamesTheStepTheGrainAndTheWall) {
  // a grain thrown at 20 m/s on a floor of soft springs: it sinks ~20 diameters deep
  SceneConfig s = bare_scene();
  s.material.k_n = 10;
  s.geometry = {test::floor_plane()};
  s.geometry[0].name = "floor";
  s.emitters = {one_grain({0, 0, 0.05}, {0, 0, -20})};
  World w(s);
  const std::string msg = run_until_stopped(w, 2);
  EXPECT_NE(msg.find("grain 0 overlaps geometry[0] ('floor')"), std::string::npos) << msg;
  EXPECT_NE(msg.find("above simulation.max_overlap_stop = 60 %"), std::string::npos) << msg;
  // it reaches the floor (4.5 cm below its bottom) after 2.25 ms at 20 m/s, and 0.6 of a
  // diameter deeper 0.3 ms later (gravity and the soft springs change that by well under a step)
  const long long step = step_of(msg);
  const Real dt = w.time_step().dt;
  EXPECT_GE(step * dt, 0.045 / 20) << msg;
  EXPECT_LE(step * dt, (0.045 + 0.006) / 20 + 2 * dt) << msg;
}

// Each step's guard sees the state the step starts from: the state the frame's last step leaves
// (the one written, and restarted from) is measured at the frame's end. One step a frame, and a
// grain a millimetre above the floor moving so fast that this one step takes it 80 % of a
// diameter into it: without the frame's check the run ends cleanly with the grain in the floor.
TEST(Guards, TheStateTheFramesLastStepLeavesIsChecked) {
  SceneConfig s = bare_scene();
  s.geometry = {test::floor_plane()};
  s.geometry[0].name = "floor";
  s.emitters = {one_grain({0, 0, 0.006}, {0, 0, 0})};
  const Real dt = World(s).time_step().dt;
  s.output.fps = 1 / dt;  // one step a frame
  s.simulation.gravity = {0, 0, 0};
  s.emitters = {one_grain({0, 0, 0.006}, {0, 0, -0.009 / dt})};
  World w(s);
  ASSERT_EQ(w.time_step().substeps, 1);
  const std::string msg = run_until_stopped(w, 1);
  // (about 80 %: the block sets its one grain down half a millimetre lower)
  EXPECT_NE(msg.find("grain 0 overlaps geometry[0] ('floor') by 8"), std::string::npos) << msg;
  EXPECT_EQ(step_of(msg), 1) << msg;
}

TEST(Guards, ARunawayOverlapBetweenGrainsNamesBoth) {
  SceneConfig s = bare_scene();
  s.simulation.gravity = {0, 0, 0};
  s.material.k_n = 10;
  s.emitters = {one_grain({-0.02, 0, 0}, {2, 0, 0}), one_grain({0.02, 0, 0}, {-2, 0, 0})};
  World w(s);
  const std::string msg = run_until_stopped(w, 2);
  EXPECT_NE(msg.find("grains 0 and 1 overlap by"), std::string::npos) << msg;
  EXPECT_GT(step_of(msg), 0) << msg;
}

TEST(Guards, ANonFiniteGrainStopsTheRunWithItsId) {
  // a velocity gone NaN after the first frame (two grains on one spot would do it: no contact
  // normal; the emitters no longer place a grain on another, so it is put there by hand)
  SceneConfig s = bare_scene();
  s.simulation.gravity = {0, 0, 0};
  s.emitters = {one_grain({0, 0, 0}, {}), one_grain({0.1, 0, 0}, {})};
  World w(s);
  w.advance_frame();
  WorldState state = w.save_state();
  const std::int64_t at = state.step;
  ASSERT_EQ(state.grains.size(), 2u);
  state.grains.v[0].x = std::numeric_limits<Real>::quiet_NaN();
  w.restore_state(std::move(state));
  const std::string msg = run_until_stopped(w, 1);
  EXPECT_NE(msg.find("non-finite position or velocity"), std::string::npos) << msg;
  EXPECT_NE(msg.find("grain 0 "), std::string::npos) << msg;
  EXPECT_EQ(step_of(msg), at) << msg;  // found in the state it was put into, before a step
}

/// Five grains thrown sideways into the void, with the default domain.
SceneConfig thrown_out(OnLeave on_leave) {
  SceneConfig s = bare_scene();
  EmitterConfig e = one_grain({0, 0, 0.5}, {5, 0, 0});
  e.size = {0.06, 0.012, 0.012};
  e.count = 5;
  s.emitters = {e};
  s.simulation.on_leave = on_leave;
  return s;
}

TEST(Guards, TheDefaultDomainIsTheScenesBoxWidenedByItsExtentAtLeastAMetre) {
  World w(thrown_out(OnLeave::Stop));
  // the block's box, 6 x 1.2 x 1.2 cm around (0, 0, 0.5), widened by 1 m
  EXPECT_NEAR(w.domain_lo().x, -0.03 - 1, 1e-12);
  EXPECT_NEAR(w.domain_hi().x, 0.03 + 1, 1e-12);
  EXPECT_NEAR(w.domain_lo().z, 0.494 - 1, 1e-12);
  EXPECT_NEAR(w.domain_hi().z, 0.506 + 1, 1e-12);
  // a larger scene widens by its own extent: a 3 m box
  SceneConfig big = thrown_out(OnLeave::Stop);
  big.geometry = {test::box_entry({0, 0, -0.1}, {3, 2, 0.2})};
  World wb(big);
  EXPECT_NEAR(wb.domain_lo().x, -1.5 - 3, 1e-12);
  EXPECT_NEAR(wb.domain_hi().y, 1 + 3, 1e-12);
  // a floor has no end: grains may roll on it as far as they go, but not fall through
  SceneConfig floored = thrown_out(OnLeave::Stop);
  floored.geometry = {test::floor_plane()};
  World wf(floored);
  EXPECT_EQ(wf.domain_lo().x, -std::numeric_limits<Real>::infinity());
  EXPECT_EQ(wf.domain_hi().y, std::numeric_limits<Real>::infinity());
  EXPECT_NEAR(wf.domain_lo().z, 0 - 1, 1e-12);
  EXPECT_NEAR(wf.domain_hi().z, 0.506 + 1, 1e-12);
}

TEST(Guards, LeavingGrainsStopTheRunOrAreCountedAsTheSceneChooses) {
  // counted: the run goes on, the grains are removed and counted, none is lost otherwise
  World counted(thrown_out(OnLeave::Count));
  int first_frame = 0;
  std::int64_t left = 0;
  for (int f = 1; f <= 15; ++f) {
    const FrameStats st = counted.advance_frame();
    if (st.left_domain > 0 && first_frame == 0) first_frame = f;
    left += st.left_domain;
    EXPECT_EQ(st.n_total + left, 5);
  }
  EXPECT_EQ(left, 5);
  EXPECT_EQ(counted.left_domain(), 5);
  EXPECT_EQ(counted.total_grains(), 0);
  // x = 0.03 + 5 t leaves 1.03 m at t = 0.2 s: frame 7 at 30 fps (1.06 m, falling 0.2 m)
  EXPECT_EQ(first_frame, 7);
  // stopped: in the same frame, naming the grain and the way to count instead
  World stopped(thrown_out(OnLeave::Stop));
  const std::string msg = run_until_stopped(stopped, 15);
  EXPECT_NE(msg.find("(frame 7, "), std::string::npos) << msg;
  const std::size_t at = msg.find(" left the domain [-1.03, 1.03] x ");
  ASSERT_NE(at, std::string::npos) << msg;
  EXPECT_GE(at, 7u);
  EXPECT_EQ(msg.substr(at - 7, 6), "grain ") << msg;
  EXPECT_TRUE(msg[at - 1] >= '0' && msg[at - 1] <= '4') << msg;
  EXPECT_NE(msg.find("simulation.on_leave = \"count\""), std::string::npos) << msg;
}

TEST(Guards, TheirSceneKeysAreValidated) {
  const std::string base = R"(
[simulation]
KEY
[[emitter]]
type = "block"
count = 1
)";
  auto error = [&](const std::string& line) {
    std::string text = base;
    text.replace(text.find("KEY"), 3, line);
    try {
      load_scene_from_string(text, "g.toml");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_EQ(error("max_overlap_stop = 0.3"), "");
  EXPECT_NE(error("max_overlap_stop = 1.5").find("g.toml:3:1: simulation.max_overlap_stop = 1.5 is outside (0, 1]"),
            std::string::npos)
      << error("max_overlap_stop = 1.5");
  EXPECT_NE(error("on_leave = \"drop\"").find("simulation.on_leave = \"drop\" is not one of \"stop\", \"count\""),
            std::string::npos)
      << error("on_leave = \"drop\"");
  EXPECT_NE(error("domain = [0, 0, 0, 1, 1]").find("simulation.domain: expected an array of 6 numbers"),
            std::string::npos);
  EXPECT_NE(error("domain = [0, 0, 0, 1, -1, 1]").find("with x1 > x0, y1 > y0, z1 > z0"),
            std::string::npos)
      << error("domain = [0, 0, 0, 1, -1, 1]");
  const SceneConfig ok =
      load_scene_from_string(base.substr(0, base.find("KEY")) +
                                 "domain = [-1, -2, -3, 1, 2, 3]\non_leave = \"count\"" +
                                 base.substr(base.find("KEY") + 3),
                             "g.toml");
  EXPECT_EQ(ok.simulation.on_leave, OnLeave::Count);
  EXPECT_EQ((*ok.simulation.domain)[5], 3);
}

}  // namespace
}  // namespace sandflow
