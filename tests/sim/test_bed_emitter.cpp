// The bed emitter (sim/emitters.hpp): a bed's count is its packing's, in both modes; in plain DEM
// the bed stays at rest; in surface mode it is born in the static layer, closed, and stays there
// a second, and a disturbance wakes only the bed near it; --grains keeps a bed;
// the state does not depend on the thread count, and a restart continues it exactly.
#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/error.hpp"
#include "sim/world.hpp"
#include "support/test_scenes.hpp"

namespace sandflow {
namespace {

constexpr Real kD = 0.02;  // 2 cm grains (dt ~ 1.2e-4 s) keep these runs short

// A bed 8 x 8 grains wide, 4 deep, in a box container whose inside is its footprint (a bed's
// sides are vertical walls: free-standing, its edges would slump).
SceneConfig bed_scene(Mode mode, Real width = 8, Real depth = 4) {
  SceneConfig s = test::grains_on_floor("bed", mode, kD);
  GeometryConfig box = test::box_entry({0, 0, 0.1}, {width * kD, width * kD, 0.2});
  box.container = true;
  s.geometry = {box};
  EmitterConfig e;
  e.type = EmitterType::Bed;
  e.center = {0, 0, 0};
  e.size = {width * kD, width * kD, 0};
  e.height = depth * kD;
  s.emitters = {e};
  s.output.frames = 6;  // 0.2 s
  resolve_beds(s);
  return s;
}

// The bed's grains as packed, by id (ids follow the packing's order).
BedPacking packed(const SceneConfig& s) {
  BedPacking b;
  const Geometry g = Geometry::from_config(s.geometry, s.material, s.path);
  EXPECT_FALSE(pack_bed_emitter(s.emitters[0], s.material, g, bed_seed(s.simulation.seed, 0), b));
  return b;
}

TEST(BedEmitter, TheCountIsThePackingsInBothModes) {
  for (Mode mode : {Mode::Dem, Mode::Surface}) {
    const SceneConfig s = bed_scene(mode);
    const std::int64_t n = s.emitters[0].count;
    EXPECT_EQ(n, static_cast<std::int64_t>(packed(s).size()));
    // about 8 x 8 x 4 d^3 at a packing fraction of 0.5 (walls and top loosen the edges)
    EXPECT_GT(n, 200);
    EXPECT_LT(n, 300);
    EXPECT_EQ(s.total_grains(), n);
    // the box of its grains, for the domain and the height field's extent
    EXPECT_NEAR(s.emitters[0].center.z - s.emitters[0].size.z / 2, 0, 1e-9);
    EXPECT_LE(s.emitters[0].center.z + s.emitters[0].size.z / 2, 4 * kD + 1e-12);
    World w(s);
    const FrameStats st = w.advance_frame();
    EXPECT_EQ(st.n_total, n);
    EXPECT_EQ(w.total_grains(), n);
    if (mode == Mode::Dem) {
      EXPECT_EQ(st.n_active, n);
    }
  }
}

TEST(BedEmitter, StaysAtRestInPlainDem) {
  const SceneConfig s = bed_scene(Mode::Dem);
  const BedPacking b = packed(s);
  World w(s);
  FrameStats st;
  for (int f = 0; f < *s.output.frames; ++f) st = w.advance_frame();
  // Born touching without overlap, the grains sink into their contacts under the bed's weight:
  // m g / k_n = 1.1e-5 m (5e-4 d) a contact, a few contacts deep, so a few thousandths of d. The
  // packing's stability is geometric (frictionless): a small grain wedged on three floor grains
  // whose centres lie a tenth of d below its own pushes them apart until friction holds them,
  // and a grain held at the edge of its cone of support (one contact pushing barely) tips. Over
  // 20 seeds, with the generator of 2026-11-26 and that of 2026-11-27 alike, 0 to 4 grains of
  // about 227 moved more than 0.05 d (the largest 0.45 d, a grain of the top layer), the rest
  // a few thousandths: the bed stays, grains at its surface may settle. A bed that came apart
  // would move a good part of its grains by half a diameter, to the next hollow.
  const Real m = s.material.density * kPi / 6 * kD * kD * kD;
  std::size_t moved = 0;
  const Grains& g = w.grains();
  for (std::size_t i = 0; i < g.size(); ++i) moved += norm(g.x[i] - b.x[g.id[i]]) > 0.05 * kD;
  EXPECT_LE(moved, b.size() / 33);  // (3 %: 6 of 200)
  // and the oscillation of that sinking has died out: the kinetic energy per grain is below a
  // millionth of m g d (the weight's work over a diameter)
  EXPECT_LT(st.kinetic_energy / static_cast<Real>(b.size()), 1e-6 * m * 9.81 * kD);
  EXPECT_LT(st.max_overlap_rel, 0.01);
}

TEST(BedEmitter, IsBornInTheStaticLayerInSurfaceModeAndStaysThereASecond) {
  SceneConfig s = bed_scene(Mode::Surface);
  s.output.frames = 30;  // 1 s
  const std::int64_t n = s.emitters[0].count;
  World w(s);
  TransitionCounts total;
  FrameStats first;
  std::int64_t fewest_static = n;
  for (int f = 0; f < *s.output.frames; ++f) {
    const FrameStats st = w.advance_frame();
    if (f == 0) first = st;
    EXPECT_EQ(st.n_total, n);
    fewest_static = std::min(fewest_static, st.n_static);
    total += st.transitions;
  }
  // the bed is born closed: every grain static, in every frame of a second (a bed at rest costs
  // nothing)
  EXPECT_EQ(first.n_static, n);
  EXPECT_EQ(fewest_static, n);
  const Real H = s.emitters[0].center.z + s.emitters[0].size.z / 2;
  const Grains& g = w.grains();
  for (std::size_t i = 0; i < g.size(); ++i)
    if (g.state[i] == GrainState::Active) {
      EXPECT_GT(g.x[i].z, H - 2 * kD) << "grain " << g.id[i];
    }
  EXPECT_LT(w.kinetic_energy(), 1e-9);
  // the updates neither erode the bed nor wake it
  EXPECT_EQ(total.dislodged, 0);
  EXPECT_EQ(total.woken, 0);
  EXPECT_EQ(total.trapped, 0);
}

TEST(BedEmitter, ABedWhoseFootprintIsNotWholeColumnsWideIsBornStaticToo) {
  // 8.3 to 8.8 grains (and columns) wide: the container's walls cross columns. A column
  // whose centre lay on a wall would take the wall's top as its level and keep the bed's grains
  // beside the wall simulated (a grid from the footprint's low edge did so at 8.5: 65 of 261)
  for (const Real width : {8.3, 8.45, 8.5, 8.55, 8.8}) {
    SceneConfig s = bed_scene(Mode::Surface, width, 4);
    s.output.frames = 6;
    const std::int64_t n = s.emitters[0].count;
    World w(s);
    std::int64_t fewest_static = n;
    for (int f = 0; f < *s.output.frames; ++f)
      fewest_static = std::min(fewest_static, w.advance_frame().n_static);
    EXPECT_EQ(fewest_static, n) << "width " << width << " grains";
  }
}

TEST(BedEmitter, AContainersWallThinnerThanAGrainHoldsTheStaticLayer) {
  // walls of 0.05 to 0.6 d: the column centres beyond a wall lie outside it, on the floor. Unless
  // the height field knows the wall between, it sees a step down there, erodes the bed's static
  // layer through the wall and wakes it (without the walls between columns, 0.6 d at 8.3 grains
  // kept 23 of 244 static, 0.3 d at 8.8 grains 21 of 275; with three lines on each edge every case
  // of 0.05 and 0.1 d failed: the middle line lies on the wall's inner face, and rounding put it
  // outside)
  for (const Real wall : {0.05, 0.1, 0.3, 0.6})
    for (const Real width : {8.0, 8.3, 8.5, 8.8}) {
      SceneConfig s = bed_scene(Mode::Surface, width, 4);
      s.geometry[0].wall_thickness = wall * kD;
      resolve_beds(s);
      s.output.frames = 15;  // 0.5 s
      const std::int64_t n = s.emitters[0].count;
      World w(s);
      std::int64_t fewest_static = n;
      for (int f = 0; f < *s.output.frames; ++f)
        fewest_static = std::min(fewest_static, w.advance_frame().n_static);
      EXPECT_EQ(fewest_static, n) << "wall " << wall << " d, width " << width << " grains";
    }
}

TEST(BedEmitter, ADisturbanceWakesOnlyTheBedNearIt) {
  // a bed 20 x 20 grains wide, 3 deep; a block of 8 grains dropped on one corner of it at 2 m/s,
  // against the same bed left alone
  SceneConfig alone = bed_scene(Mode::Surface, 20, 3);
  alone.output.frames = 9;  // 0.3 s
  const std::int64_t n_bed = alone.emitters[0].count;
  const Vec3 hit{5 * kD, 5 * kD, 0};
  SceneConfig s = alone;
  EmitterConfig block;
  block.type = EmitterType::Block;
  block.name = "block";
  block.count = 8;
  block.center = {hit.x, hit.y, 5 * kD};
  block.size = {3 * kD, 3 * kD, 3 * kD};
  block.velocity = {0, 0, -2};
  s.emitters.push_back(block);
  World w(s), w0(alone);
  std::int64_t woken = 0;
  Real farthest = 0;  // the farthest bed grain from the hit that left the static layer for it
  for (int f = 0; f < *s.output.frames; ++f) {
    w.advance_frame();
    w0.advance_frame();
    std::vector<std::uint8_t> hot0(static_cast<std::size_t>(n_bed), 0);
    for (GrainId id : w0.grains().id) hot0[id] = 1;
    const Grains& g = w.grains();
    for (std::size_t i = 0; i < g.size(); ++i)
      if (static_cast<std::int64_t>(g.id[i]) < n_bed && !hot0[g.id[i]]) {
        ++woken;
        farthest = std::max(farthest, std::hypot(g.x[i].x - hit.x, g.x[i].y - hit.y));
      }
  }
  // the hit opened the bed, but only near it: within 10 diameters of the hit (the block's grains
  // splash up to 8 here), where the far corner of the bed lies 21 diameters away
  EXPECT_GT(woken, 0);
  EXPECT_LT(farthest, 10 * kD);
}

TEST(BedEmitter, ARelievedTopFollowsItsRelief) {
  // a bed 24 grains wide and 6 deep whose top falls up to 2 grains below `height`, in hills about
  // 16 grains apart (gentler than the material's theta_max: a steeper relief slumps)
  SceneConfig flat = bed_scene(Mode::Surface, 24, 6);
  SceneConfig hilly = flat;
  hilly.emitters[0].relief = 2 * kD;
  hilly.emitters[0].relief_wavelength = 16 * kD;
  resolve_beds(hilly);
  const BedPacking b = packed(hilly);
  // the highest grain top of each 2 d x 2 d patch of the footprint
  std::vector<Real> patch(144, -1);
  for (std::size_t k = 0; k < b.size(); ++k) {
    EXPECT_LE(b.x[k].z + b.r[k], 6 * kD + 1e-9);  // never above `height`
    const int i = std::clamp(static_cast<int>((b.x[k].x + 12 * kD) / (2 * kD)), 0, 11);
    const int j = std::clamp(static_cast<int>((b.x[k].y + 12 * kD) / (2 * kD)), 0, 11);
    Real& top = patch[static_cast<std::size_t>(j * 12 + i)];
    top = std::max(top, b.x[k].z + b.r[k]);
  }
  const auto [low, high] = std::minmax_element(patch.begin(), patch.end());
  // hills reach the top within a grain; hollows lie at least half the relief below it
  EXPECT_GT(*high, 5 * kD);
  EXPECT_LT(*low, 6 * kD - 1.0 * kD);
  // the relief takes grains away: a noise of mean depth about half the relief, less than the
  // flat bed by a twentieth to a third of its 6-grain depth
  EXPECT_LT(hilly.emitters[0].count, flat.emitters[0].count * 19 / 20);
  EXPECT_GT(hilly.emitters[0].count, flat.emitters[0].count * 2 / 3);
  // born at rest in the static layer like a flat bed, but for a few grains where the top is
  // steepest: their centre lies above h interpolated between the column centres (3 of 2,828)
  World w(hilly);
  const FrameStats st = w.advance_frame();
  EXPECT_GE(st.n_static, hilly.emitters[0].count * 99 / 100);
}

TEST(BedEmitter, GrainsScalingKeepsTheBed) {
  SceneConfig s = bed_scene(Mode::Surface);
  const std::int64_t bed = s.emitters[0].count;
  s.emitters.push_back(test::disk_pour({0, 0, 0.3}, 0.05, 1000, 500, {0, 0, 0}));
  scale_grain_count(s, bed + 100);
  EXPECT_EQ(s.emitters[0].count, bed);
  EXPECT_EQ(s.emitters[1].count, 100);
  EXPECT_EQ(s.total_grains(), bed + 100);
  EXPECT_THROW(scale_grain_count(s, bed), InputError);  // nothing left for the pour
  SceneConfig only = bed_scene(Mode::Surface);
  scale_grain_count(only, bed);  // (the beds' own count: nothing to do)
  EXPECT_EQ(only.emitters[0].count, bed);
  EXPECT_THROW(scale_grain_count(only, 2 * bed), InputError);
}

std::uint64_t hash_after(const SceneConfig& s, int threads, int frames) {
  omp_set_num_threads(threads);
  World w(s);
  for (int f = 0; f < frames; ++f) w.advance_frame();
  omp_set_num_threads(omp_get_num_procs());
  return w.state_hash();
}

TEST(BedEmitter, OneAndTwoThreadsAndARestartGiveTheSameState) {
  for (Mode mode : {Mode::Surface, Mode::Dem}) {
    SceneConfig s = bed_scene(mode);
    // a block dropped onto the bed, so that the state moves
    EmitterConfig block;
    block.type = EmitterType::Block;
    block.center = {0, 0, 0.14};
    block.size = {3 * kD, 3 * kD, 3 * kD};
    block.count = 8;
    block.velocity = {0, 0, -1};
    s.emitters.push_back(block);
    const std::uint64_t h1 = hash_after(s, 1, 4);
    EXPECT_EQ(hash_after(s, 2, 4), h1);
    // a restart after 2 frames continues exactly
    World a(s);
    for (int f = 0; f < 2; ++f) a.advance_frame();
    World b(s);
    b.restore_state(a.save_state());
    for (int f = 0; f < 2; ++f) b.advance_frame();
    EXPECT_EQ(b.state_hash(), h1);
  }
}

TEST(BedEmitter, ABedStartedOverGrainsAlreadyThereLeavesOutTheTakenPlaces) {
  // a lattice at rest fills the low-y half of the container two grains deep; the bed comes a
  // tenth of a second later: its grains there would sit in the lattice's, fired apart
  for (Mode mode : {Mode::Dem, Mode::Surface}) {
    SceneConfig s = bed_scene(mode);
    EmitterConfig lattice;
    lattice.type = EmitterType::Lattice;
    lattice.center = {0, -2 * kD, kD};
    lattice.size = {8 * kD, 4 * kD, 2 * kD};
    lattice.count = static_cast<std::int64_t>(box_slots(lattice, s.material));
    s.emitters[0].start = 0.1;
    s.emitters.push_back(lattice);  // (after the bed: a bed's packing is seeded by its index)
    World w(s);
    Real max_overlap = 0;
    for (int f = 0; f < 6; ++f)
      max_overlap = std::max(max_overlap, w.advance_frame().max_overlap_rel);
    const Emitter& bed = w.emitters()[0];
    EXPECT_TRUE(bed.done()) << static_cast<int>(mode);
    EXPECT_GT(bed.left_out(), 0) << static_cast<int>(mode);
    EXPECT_GT(bed.emitted(), bed.left_out()) << static_cast<int>(mode);  // the free half is placed
    EXPECT_EQ(bed.emitted() + bed.left_out(), bed.count());
    EXPECT_EQ(w.total_grains(), lattice.count + bed.emitted());
    // grains that settled under gravity, not grains placed in each other (a diameter's worth then)
    EXPECT_LT(max_overlap, 0.05) << static_cast<int>(mode);
  }
}

}  // namespace
}  // namespace sandflow
