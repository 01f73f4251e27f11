// Restart equality: a World saved at a frame boundary, encoded, parsed and restored into a fresh
// World of the same scene continues exactly as the World that never stopped — every frame's
// statistics and the final state hash bit for bit, in both modes, across thread counts.
#include <gtest/gtest.h>
#include <omp.h>

#include "checkpoint/checkpoint.hpp"
#include "core/error.hpp"
#include "io/run_output.hpp"
#include "sim/world.hpp"
#include "support/test_scenes.hpp"

namespace sandflow {
namespace {

/// A pile that exercises every piece of saved state: a prefilled lattice that settles (contacts,
/// tangential and rolling history, transitions to the interface and the static layer), a pour
/// on top (the emitter's progress and the random state), a container (wall contacts), frequent
/// sorts by cell (sort_every 2), and grains thrown out of the domain and counted (removals).
SceneConfig restart_scene(Mode mode) {
  SceneConfig s;
  s.path = "restart";
  s.name = "restart";
  s.simulation.mode = mode;
  s.simulation.dt_fraction = 0.2;  // few substeps: the test is about exactness, not accuracy
  s.simulation.sort_every = 2;
  s.simulation.on_leave = OnLeave::Count;
  s.simulation.domain = std::array<Real, 6>{-0.2, -0.2, -0.05, 0.2, 0.2, 0.4};
  s.material.diameter = 0.01;
  s.material.diameter_spread = 0.1;
  s.material.k_n = 1e4;
  s.material.rolling_friction = 0.3;
  // the block is four grains deep: under the pour a flowing layer of 4 d would leave no grain to
  // put to sleep in 14 frames, and the static layer's state would go untested
  s.surface.flowing_min = 0.01;
  s.output.fps = 60;
  GeometryConfig box = test::box_entry({0, 0, 0.1}, {0.12, 0.12, 0.2});
  box.container = true;
  s.geometry = {box};
  EmitterConfig pile;
  pile.type = EmitterType::Lattice;
  pile.center = {0, 0, 0.025};
  pile.size = {0.11, 0.11, 0.04};
  pile.count = 250;
  const EmitterConfig pour = test::disk_pour({0, 0, 0.12}, 0.03, 1000, 120, {0, 0, -1});
  // a few grains thrown over the wall and out of the domain
  EmitterConfig throw_out;
  throw_out.type = EmitterType::Block;
  throw_out.center = {0, 0, 0.15};
  throw_out.size = {0.035, 0.024, 0.012};
  throw_out.count = 6;
  throw_out.start = 0.02;
  throw_out.velocity = {3, 0, 1};
  s.emitters = {pile, pour, throw_out};
  return s;
}

/// The statistics that must match: all but the wall-clock time.
void expect_same(const FrameStats& a, const FrameStats& b) {
  EXPECT_EQ(a.frame, b.frame);
  EXPECT_EQ(a.time, b.time);
  EXPECT_EQ(a.n_total, b.n_total);
  EXPECT_EQ(a.n_active, b.n_active);
  EXPECT_EQ(a.n_interface, b.n_interface);
  EXPECT_EQ(a.n_static, b.n_static);
  EXPECT_EQ(a.contacts, b.contacts);
  EXPECT_EQ(a.wall_contacts, b.wall_contacts);
  EXPECT_EQ(a.max_overlap_rel, b.max_overlap_rel);
  EXPECT_EQ(a.kinetic_energy, b.kinetic_energy);
  EXPECT_EQ(a.rebuilds, b.rebuilds);
  EXPECT_EQ(a.transitions.total(), b.transitions.total());
  EXPECT_EQ(a.left_domain, b.left_domain);
}

/// Runs `frames` frames straight, and again stopping after `k` to go on in a new World from the
/// checkpoint bytes (with `threads_after` threads); compares frame by frame.
void check_restart(const SceneConfig& scene, int frames, int k, int threads_before,
                   int threads_after, TransitionCounts* seen = nullptr,
                   std::int64_t* left = nullptr) {
  omp_set_num_threads(1);
  World straight(scene);
  std::vector<FrameStats> want;
  for (int f = 0; f < frames; ++f) want.push_back(straight.advance_frame());

  omp_set_num_threads(threads_before);
  World first(scene);
  Checkpoint c;
  for (int f = 0; f < k; ++f) c.frames.push_back(first.advance_frame());
  c.scene_hash = scene_hash(first, "test");
  c.world = first.save_state();
  const std::string bytes = encode_checkpoint(c);

  omp_set_num_threads(threads_after);
  World resumed(scene);
  restore_checkpoint(resumed, parse_checkpoint(bytes, "test.bin"), scene_hash(resumed, "test"),
                     "test.bin");
  EXPECT_EQ(resumed.state_hash(), first.state_hash()) << "right after the restore";
  for (int f = k; f < frames; ++f) {
    SCOPED_TRACE("frame " + std::to_string(f + 1));
    expect_same(resumed.advance_frame(), want[static_cast<std::size_t>(f)]);
  }
  EXPECT_EQ(resumed.state_hash(), straight.state_hash());
  // saving does not disturb the run that saved
  for (int f = k; f < frames; ++f) first.advance_frame();
  EXPECT_EQ(first.state_hash(), straight.state_hash());
  omp_set_num_threads(1);
  for (const FrameStats& st : want) {
    if (seen) *seen += st.transitions;
    if (left) *left += st.left_domain;
  }
}

TEST(Restart, SurfaceModeContinuesBitForBit) {
  TransitionCounts seen;
  std::int64_t left = 0;
  check_restart(restart_scene(Mode::Surface), 14, 6, 1, 1, &seen, &left);
  // the run must exercise what the checkpoint holds, or the test proves nothing
  EXPECT_GT(seen.trapped, 0);
  EXPECT_GT(seen.slept, 0);
  EXPECT_GT(seen.woken, 0);
  EXPECT_GT(left, 0);
}

TEST(Restart, RestoreGivesBackEverySavedValue) {
  // saved, restored and saved again: the same bytes, so no field is dropped or altered on the
  // way back (a rebuild flag or an allowance that the continuation tests may not reach)
  for (Mode mode : {Mode::Surface, Mode::Dem}) {
    const SceneConfig scene = restart_scene(mode);
    World a(scene);
    Checkpoint c;
    for (int f = 0; f < 5; ++f) c.frames.push_back(a.advance_frame());
    c.scene_hash = scene_hash(a, "test");
    c.world = a.save_state();
    const std::string bytes = encode_checkpoint(c);
    World b(scene);
    restore_checkpoint(b, parse_checkpoint(bytes, "test.bin"), c.scene_hash, "test.bin");
    Checkpoint again;
    again.frames = c.frames;
    again.scene_hash = c.scene_hash;
    again.world = b.save_state();
    EXPECT_TRUE(encode_checkpoint(again) == bytes) << (mode == Mode::Dem ? "dem" : "surface");
  }
}

TEST(Restart, DemModeContinuesBitForBit) {
  std::int64_t left = 0;
  check_restart(restart_scene(Mode::Dem), 14, 6, 1, 1, nullptr, &left);
  EXPECT_GT(left, 0);
}

// Twisting friction without rolling friction: the law's rolling part still runs (the twisting
// torque rides on it), with its history saved and checked on restore in both modes.
TEST(Restart, ARunWithTwistingButNoRollingFrictionContinuesBitForBit) {
  for (Mode mode : {Mode::Surface, Mode::Dem}) {
    SceneConfig scene = restart_scene(mode);
    scene.material.rolling_friction = 0;
    scene.material.twisting_friction = 0.1;
    scene.material.wall_twisting_friction = 0.1;
    check_restart(scene, 10, 5, 1, 1);
    World w(scene);
    for (int f = 0; f < 3; ++f) w.advance_frame();
    EXPECT_TRUE(w.dem().resists_turning());
    EXPECT_EQ(w.dem().pairs().psi.size(), w.dem().pairs().j.size());
  }
}

TEST(Restart, EveryFrameBoundaryOfASurfaceRunIsARestartPoint) {
  // checkpoints at successive frames each continue exactly (a state missed at one boundary, such
  // as a timer due at the next step, shows up at some k)
  const SceneConfig scene = restart_scene(Mode::Surface);
  for (int k = 1; k <= 4; ++k) {
    SCOPED_TRACE("k = " + std::to_string(k));
    check_restart(scene, k + 2, k, 1, 1);
  }
}

/// A settling block of more grains than kParallelMinGrains: the lists are built and swept by two
/// threads.
SceneConfig parallel_scene(Mode mode) {
  SceneConfig s;
  s.path = "threads";
  s.simulation.mode = mode;
  s.simulation.dt_fraction = 0.2;
  s.simulation.sort_every = 2;
  s.material.diameter = 0.01;
  s.material.k_n = 1e4;
  s.output.fps = 600;  // a frame of a few steps: the test is about exactness
  s.geometry = {test::floor_plane()};
  EmitterConfig pile;
  pile.type = EmitterType::Lattice;
  pile.center = {0, 0, 0.1};
  pile.size = {0.2, 0.2, 0.2};
  pile.count = static_cast<std::int64_t>(kParallelMinGrains) + 500;
  s.emitters = {pile};
  return s;
}

TEST(Restart, TwoThreadsBeforeAndOneAfterGiveTheSameState) {
  check_restart(parallel_scene(Mode::Dem), 4, 2, 2, 1);
  check_restart(parallel_scene(Mode::Dem), 4, 2, 1, 2);
}

TEST(Restart, TwoThreadsBeforeAndOneAfterGiveTheSameStateInSurfaceMode) {
  check_restart(parallel_scene(Mode::Surface), 4, 2, 2, 1);
  // (still enough hot grains for two threads when the checkpoint is taken)
  World w(parallel_scene(Mode::Surface));
  for (int f = 0; f < 2; ++f) w.advance_frame();
  EXPECT_GT(w.grains().size(), kParallelMinGrains);
}

TEST(Restart, ARunWhoseContainerIsRemovedResumesBitForBitBeforeAndAfterTheRemoval) {
  // the container goes at frame 8 (of 60 a second); checkpoints at frame 6 (before: the resumed
  // run removes it as the straight one did) and at frame 10 (after: it must be gone at once, and
  // the height field's terrain traced again, before the saved state is put back)
  for (Mode mode : {Mode::Surface, Mode::Dem}) {
    SCOPED_TRACE(mode == Mode::Dem ? "dem" : "surface");
    SceneConfig scene = restart_scene(mode);
    scene.geometry.push_back(test::floor_plane());
    scene.geometry[0].remove_at = 8.0 / 60;
    check_restart(scene, 14, 6, 1, 1);
    check_restart(scene, 14, 10, 1, 1);
    check_restart(scene, 9, 8, 1, 1);  // at the removal's own frame boundary
  }
}

}  // namespace
}  // namespace sandflow
