// Emitters on the sizes a user may give: what they place, and that an absurd size is refused at
// once instead of making (or looping over) a pattern no machine holds.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "checkpoint/checkpoint.hpp"
#include "config/emitter_region.hpp"
#include "core/error.hpp"
#include "sim/emitters.hpp"
#include "sim/world.hpp"

namespace sandflow {
namespace {

MaterialConfig millimetre_grains() {
  MaterialConfig m;
  m.diameter = 0.001;
  m.diameter_spread = 0.0;
  return m;
}

EmitterConfig block(Vec3 center, Vec3 size, std::int64_t count) {
  EmitterConfig e;
  e.type = EmitterType::Block;
  e.center = center;
  e.size = size;
  e.count = count;
  e.jitter = 0;
  return e;
}

const Vec3 kGravity{0, 0, -9.81};

TEST(Emitters, ABlockFarLargerThanItsCountPlacesExactlyTheCountFromItsLowCorner) {
  // a 100 m box of 10 one-millimetre grains: 10^15 lattice points, of which the first 10 are used
  const EmitterConfig e = block({0, 0, 50}, {100, 100, 100}, 10);
  Emitter emitter(e, millimetre_grains(), kGravity, "test");
  Rng rng(1);
  std::vector<NewGrain> out;
  emitter.emit(0.0, rng, out);
  ASSERT_EQ(out.size(), 10u);
  EXPECT_TRUE(emitter.done());
  const Real s = e.spacing * 0.001;
  for (std::size_t i = 0; i < out.size(); ++i) {
    // one row along x at the box's low corner, a spacing apart (jitter 0)
    EXPECT_NEAR(out[i].x.x, -50 + 0.0005 + static_cast<Real>(i) * s, 1e-9) << i;
    EXPECT_NEAR(out[i].x.y, -50 + 0.0005, 1e-12);
    EXPECT_NEAR(out[i].x.z, 0.0005, 1e-12);
    EXPECT_DOUBLE_EQ(out[i].r, 0.0005);
  }
}

TEST(Emitters, ABlockStartedOverGrainsAlreadyThereLeavesOutTheTakenPlacesAndARestartKnowsIt) {
  // a lattice at rest (no gravity) fills the low half of a box; a block started later fills the
  // whole box: placed on the lattice's grains, its low half would be fired off
  SceneConfig s;
  s.path = "emitters";
  s.simulation.gravity = {0, 0, 0};
  EmitterConfig below;
  below.type = EmitterType::Lattice;
  below.center = {0, 0, 0.5};
  below.size = {0.1, 0.1, 0.05};
  below.count = static_cast<std::int64_t>(box_slots(below, s.material));
  EmitterConfig over = block({0, 0, 0.525}, {0.1, 0.1, 0.1}, 0);
  over.count = static_cast<std::int64_t>(box_slots(over, s.material));
  over.jitter = 0.25;
  over.start = 0.05;
  s.emitters = {below, over};
  World w(s);
  Checkpoint c;
  Real max_overlap = 0;
  for (int f = 0; f < 3; ++f) {
    c.frames.push_back(w.advance_frame());
    max_overlap = std::max(max_overlap, c.frames.back().max_overlap_rel);
  }
  const Emitter& e = w.emitters()[1];
  EXPECT_TRUE(e.done());
  EXPECT_GT(e.left_out(), 0);
  EXPECT_GT(e.emitted(), e.count() / 3);  // its upper half, and more
  EXPECT_EQ(e.emitted() + e.left_out(), e.count());
  EXPECT_EQ(w.total_grains(), below.count + e.emitted());
  EXPECT_EQ(max_overlap, 0.0);  // nothing placed touches anything

  // the count left out survives a checkpoint, and the block is not emitted again after it
  c.scene_hash = scene_hash(w, "start");
  c.world = w.save_state();
  World resumed(s);
  restore_checkpoint(resumed, parse_checkpoint(encode_checkpoint(c), "ck.bin"), c.scene_hash,
                     "ck.bin");
  EXPECT_EQ(resumed.emitters()[1].left_out(), e.left_out());
  resumed.advance_frame();
  EXPECT_EQ(resumed.total_grains(), w.total_grains());
}

TEST(Emitters, ALatePourBatchIsWhereAndAsFastAsFreeFallSinceItsTimeMakesIt) {
  // a batch may wait for the pair list's next rebuild; its grains must not notice
  EmitterConfig pour;
  pour.type = EmitterType::Pour;
  pour.center = {0, 0, 0.5};
  pour.radius = 0.01;
  pour.count = 1000;
  pour.rate = 50000;  // about 35 grains a batch
  pour.velocity = {0.2, 0, -1.5};
  pour.jitter = 0.5;
  Emitter on_time(pour, millimetre_grains(), kGravity, "test");
  Emitter late(pour, millimetre_grains(), kGravity, "test");
  ASSERT_GT(late.max_wait(), 0.0);
  const Real t0 = late.next_time(), tau = 0.9 * late.max_wait();
  Rng rng_a(7), rng_b(7);
  std::vector<NewGrain> a, b;
  on_time.emit(t0, rng_a, a);
  late.emit(t0 + tau, rng_b, b);
  ASSERT_EQ(a.size(), b.size());
  ASSERT_GT(a.size(), 0u);
  for (std::size_t i = 0; i < a.size(); ++i) {
    // the grain on time, carried on by its own free fall
    const Vec3 shift = a[i].v * tau + kGravity * (tau * tau / 2);
    EXPECT_LT(norm(b[i].x - (a[i].x + shift)), 1e-12) << i;
    EXPECT_LT(norm(b[i].v - (a[i].v + kGravity * tau)), 1e-12) << i;
    EXPECT_EQ(a[i].r, b[i].r);
    EXPECT_TRUE(late.near_slots(b[i].x, b[i].r));  // the slot check sees where it lands
  }
  EXPECT_EQ(on_time.next_time(), late.next_time());  // the schedule does not slip
}

// A pour straight down falls as a stream, not as a stack of discs: its grains leave the disk at
// heights spread over a batch's fall, yet every one is on free fall from rest at the disk (the
// speed it lands with is the pour's), none overlaps another, and the flow is the rate.
TEST(Emitters, AVerticalPourFallsAsAStreamOfFreeFallingGrainsNotAsDiscs) {
  EmitterConfig pour;
  pour.type = EmitterType::Pour;
  pour.center = {0, 0, 0.5};
  pour.radius = 0.006;
  pour.count = 4000;
  pour.rate = 5000;  // of the 6,698 grains/s its slots let through
  pour.jitter = 0.5;
  Emitter e(pour, millimetre_grains(), kGravity, "test");
  const Real g = 9.81;
  Rng rng(3);
  struct Born {
    NewGrain grain;
    Real t;
  };
  std::vector<Born> born;
  std::vector<Real> drops;
  for (int b = 0; b < 40 && !e.done(); ++b) {
    const Real t = e.next_time();
    std::vector<NewGrain> out;
    e.emit(t, rng, out);
    for (const NewGrain& n : out) {
      born.push_back({n, t});
      const Real drop = pour.center.z - n.x.z;
      drops.push_back(drop);
      // on free fall from rest at the disk, but for the jitter of its place (at most half the
      // free gap between slots, 0.5 * 0.05 mm): v^2 = 2 g (drop - jitter)
      const Real jit = pour.jitter * (pour.spacing - 1) * 0.001 / 2;
      EXPECT_NEAR(n.v.z * n.v.z, 2 * g * drop, 2 * g * jit + 1e-12);
      EXPECT_LE(n.v.z, 0.0);
      EXPECT_EQ(n.v.x, 0.0);
      EXPECT_EQ(n.v.y, 0.0);
    }
  }
  ASSERT_GT(born.size(), 1000u);
  // heights spread over (nearly) a whole batch's fall of one spacing, not a disc
  const auto [lo, hi] = std::minmax_element(drops.begin(), drops.end());
  EXPECT_LT(*lo, 0.0002);
  EXPECT_GT(*hi, 0.0008);
  // no two grains overlap at the latest birth: each moved on its free fall until then
  const Real t_end = born.back().t;
  std::vector<Vec3> at_end;
  for (const Born& b : born) {
    const Real dt = t_end - b.t;
    at_end.push_back(b.grain.x + b.grain.v * dt + kGravity * (dt * dt / 2));
  }
  Real closest = 1;
  for (std::size_t i = 0; i < at_end.size(); ++i)
    for (std::size_t j = i + 1; j < at_end.size(); ++j)
      closest = std::min(closest, norm(at_end[i] - at_end[j]) - born[i].grain.r - born[j].grain.r);
  EXPECT_GE(closest, -1e-12);
  // the rate: as many grains as the pour's rate over the batches' time
  const Real span = born.back().t - born.front().t;
  const auto first_batch = static_cast<Real>(std::count_if(
      born.begin(), born.end(), [&](const Born& b) { return b.t == born.front().t; }));
  EXPECT_NEAR((static_cast<Real>(born.size()) - first_batch) / span, pour.rate, 0.02 * pour.rate);
}

// A pour's grains from their births on, as free fall carries them.
struct PourFlight {
  std::vector<NewGrain> grains;
  std::vector<Real> born;  ///< [s]
  Real lead = 0;           ///< the emitter's stream_lead()
};

PourFlight pour_flight(const EmitterConfig& pour, int batches) {
  Emitter e(pour, millimetre_grains(), kGravity, "test");
  PourFlight f;
  f.lead = e.stream_lead();
  Rng rng(3);
  for (int b = 0; b < batches && !e.done(); ++b) {
    const Real t = e.next_time();
    std::vector<NewGrain> out;
    e.emit(t, rng, out);
    for (const NewGrain& n : out) {
      f.grains.push_back(n);
      f.born.push_back(t);
    }
  }
  return f;
}

// The smallest gap between two grains of a pour over their flights: each pair from the younger's
// birth, where the older has flown on its free fall, to where their constant relative velocity
// brings them closest [m] (negative: they overlap).
Real closest_gap_in_flight(const PourFlight& f) {
  Real closest = 1;
  for (std::size_t b = 0; b < f.grains.size(); ++b)
    for (std::size_t a = 0; a < f.grains.size(); ++a) {
      if (a == b || f.born[a] > f.born[b] || (f.born[a] == f.born[b] && a > b)) continue;
      const Real t = f.born[b] - f.born[a];
      const NewGrain& A = f.grains[a];
      const NewGrain& B = f.grains[b];
      const Vec3 s = A.x + A.v * t + kGravity * (t * t / 2) - B.x;
      const Vec3 w = A.v + kGravity * t - B.v;
      Real d2 = norm2(s);
      if (dot(s, w) < 0 && norm2(w) > 0) d2 -= dot(s, w) * dot(s, w) / norm2(w);
      closest = std::min(closest, std::sqrt(std::max(d2, 0.0)) - A.r - B.r);
    }
  return closest;
}

// rate: about half of what its slots let through at that speed down
EmitterConfig sideways_pour(Vec3 velocity, Real rate) {
  EmitterConfig pour;
  pour.type = EmitterType::Pour;
  pour.center = {0, 0, 0.5};
  pour.radius = 0.006;
  pour.count = 100000;
  pour.rate = rate;
  pour.velocity = velocity;
  pour.jitter = 0.5;
  return pour;
}

// sideways_pour at a slot spacing of its own (in diameters)
EmitterConfig stream_config(Vec3 velocity, Real rate, Real spacing) {
  EmitterConfig c = sideways_pour(velocity, rate);
  c.spacing = spacing;
  return c;
}

// Thrown a little sideways, a pour still falls as a stream (heights spread over a batch's fall,
// on free fall from the pour) and its grains never meet in flight; thrown more steeply, its leads
// shrink or go, as its spacing allows, and still no two grains meet.
TEST(Emitters, APourThrownSidewaysFallsAsAStreamWhoseGrainsNeverMeetInFlight) {
  const EmitterConfig slant = sideways_pour({0.2, 0, -1.5}, 80000);
  const PourFlight f = pour_flight(slant, 30);
  ASSERT_GT(f.grains.size(), 200u);
  EXPECT_EQ(f.lead, 1.0);
  Real low = 1, high = 0;
  const Real jit = slant.jitter * (slant.spacing - 1) * 0.001 / 2;
  for (const NewGrain& n : f.grains) {
    // on the throw's free fall: as far along the throw as its speed down says it has fallen
    const Real fall = (n.v.z - slant.velocity.z) / kGravity.z;
    EXPECT_NEAR(n.v.x, slant.velocity.x, 1e-12);
    EXPECT_NEAR(slant.center.z - n.x.z, -slant.velocity.z * fall - kGravity.z * fall * fall / 2,
                jit + 1e-12);
    low = std::min(low, slant.center.z - n.x.z);
    high = std::max(high, slant.center.z - n.x.z);
  }
  EXPECT_LT(low, 0.0002);
  EXPECT_GT(high, 0.0008);
  EXPECT_GE(closest_gap_in_flight(f), -1e-12);

  // steeper: a wider spacing leaves room for some lead (26.6 degrees off the vertical), or all
  struct Throw {
    Vec3 v;
    Real rate, spacing, lead;
  };
  const Throw throws[] = {{{0.5, 0, -1.0}, 15000, 1.05, 0.0},
                          {{0.5, 0, -1.0}, 15000, 1.2, 0.25},
                          {{0.5, 0, -1.0}, 15000, 1.5, 1.0},
                          {{1.5, 0, -0.5}, 30000, 1.05, 0.0},
                          {{1.0, 0.5, 0}, 4000, 1.05, 0.0}};
  for (const Throw& t : throws) {
    const PourFlight g = pour_flight(stream_config(t.v, t.rate, t.spacing), 30);
    const std::string what =
        fmt::format("velocity ({}, {}, {}), spacing {}", t.v.x, t.v.y, t.v.z, t.spacing);
    ASSERT_GT(g.grains.size(), 100u) << what;
    EXPECT_EQ(g.lead, t.lead) << what;
    EXPECT_GE(closest_gap_in_flight(g), -1e-12) << what;
  }
}

// The spacing a pour's warning suggests ("spacing = X lets it fall as a stream"), 0 for none.
Real suggested_spacing(const std::string& warning) {
  const std::string key = "; spacing = ";
  const std::size_t at = warning.find(key);
  return at == std::string::npos ? 0 : std::stod(warning.substr(at + key.size()));
}

// A pour that cannot fall as a whole stream says so, and names the smallest of the spacings it
// tries that would let it: at that spacing the pour streams whole (and its grains never meet in
// flight), at the one tried before it does not. Straight down, or slightly slanted, it says
// nothing; thrown up it says it falls as discs.
TEST(Emitters, APourThatCannotStreamNamesTheSpacingThatLetsIt) {
  const MaterialConfig grains = millimetre_grains();
  auto emitter = [&](Vec3 v, Real rate, Real spacing) {
    return Emitter(stream_config(v, rate, spacing), grains, kGravity, "s.toml: emitter[0]");
  };
  EXPECT_EQ(emitter({0, 0, -1.5}, 80000, 1.05).warning(), "");
  EXPECT_EQ(emitter({0.2, 0, -1.5}, 80000, 1.05).warning(), "");
  const Real tried[] = {1.05, 1.1, 1.2, 1.3, 1.4, 1.5, 1.75, 2.0, 2.5, 3.0};
  struct Throw {
    Vec3 v;
    Real rate;
  };
  for (const Throw& t :
       {Throw{{0.5, 0, -1.0}, 4000}, Throw{{1.0, 0, -1.0}, 1000}, Throw{{0.6, 0.6, -1.0}, 500}}) {
    const std::string what = fmt::format("velocity ({}, {}, {})", t.v.x, t.v.y, t.v.z);
    const Emitter discs = emitter(t.v, t.rate, 1.05);
    EXPECT_EQ(discs.stream_lead(), 0.0) << what;
    const std::string w = discs.warning();
    EXPECT_EQ(w.rfind("s.toml: emitter[0]: thrown ", 0), 0u) << w;
    EXPECT_NE(w.find("falls as discs"), std::string::npos) << w;
    const Real spacing = suggested_spacing(w);
    ASSERT_GT(spacing, 1.05) << w;
    EXPECT_EQ(w.find("times the area"), std::string::npos) << w;  // (these rates fit)
    const Emitter stream = emitter(t.v, t.rate, spacing);
    EXPECT_EQ(stream.stream_lead(), 1.0) << what << ", spacing " << spacing;
    EXPECT_EQ(stream.warning(), "") << what;
    EXPECT_GE(closest_gap_in_flight(pour_flight(stream_config(t.v, t.rate, spacing), 30)), -1e-12)
        << what;
    const Real* before = std::find(std::begin(tried), std::end(tried), spacing) - 1;
    ASSERT_GE(before, std::begin(tried)) << spacing;
    EXPECT_LT(emitter(t.v, t.rate, *before).stream_lead(), 1.0) << what << ", spacing " << *before;
  }
  // a rate the suggested spacing's slots cannot hold: the area it would take
  const std::string crowded = emitter({0.5, 0, -1.0}, 80000, 1.05).warning();
  EXPECT_GT(suggested_spacing(crowded), 1.05) << crowded;
  EXPECT_NE(crowded.find("times the area for its 80000 grains/s"), std::string::npos) << crowded;
  // thrown level: no spacing tried lets it stream
  const std::string flat = emitter({1.0, 0.5, 0}, 100, 1.05).warning();
  EXPECT_NE(flat.find("no spacing up to 3"), std::string::npos) << flat;
  // thrown up
  EXPECT_NE(emitter({0, 0, 0.5}, 100, 1.05).warning().find("falls as discs"), std::string::npos);
}

// A nozzle (facing = "velocity") lays its area across its throw, so its batches leave one
// behind the other along it, a spacing apart: thrown level or down at a slant, it holds as many
// grains a second as its slots times |v| / s allow (a level area thrown level holds only what
// falls a spacing in a batch's time), its grains never meet in flight, and it warns of nothing.
// Thrown up too slowly to clear its own slots it is refused.
TEST(Emitters, ANozzleStreamsAlongItsThrowAtAnyAngleAndItsGrainsNeverMeetInFlight) {
  const MaterialConfig grains = millimetre_grains();
  for (const Vec3 v : {Vec3{2.0, 0, 0}, Vec3{1.0, 1.0, -1.0}, Vec3{0, 0, -1.5}}) {
    const std::string what = fmt::format("velocity ({}, {}, {})", v.x, v.y, v.z);
    EmitterConfig nozzle = sideways_pour(v, 100);
    nozzle.facing = PourFacing::Velocity;
    const Emitter probe(nozzle, grains, kGravity, "s.toml: emitter[0]");
    EXPECT_EQ(probe.warning(), "") << what;
    const Real max_rate = probe.max_rate();
    EmitterConfig level = sideways_pour(v, 100);
    const Real level_rate = Emitter(level, grains, kGravity, "level").max_rate();
    if (v.z == 0) {
      // level: s / |v| against sqrt(2 s / g) between batches, 28 times the rate here
      const Real s = nozzle.spacing * 0.001;
      EXPECT_NEAR(max_rate / level_rate, std::sqrt(2 * s / 9.81) / (s / norm(v)), 1e-9) << what;
      level.rate = 0.9 * max_rate;
      EXPECT_THROW(Emitter(level, grains, kGravity, "level"), InputError) << what;
    }
    // at nine tenths of what it holds, 30 batches: every grain in flight a diameter clear of every
    // other; the first batch (no jitter) lies across the throw, within the disk
    nozzle.rate = 0.9 * max_rate;
    nozzle.jitter = 0;
    Emitter first(nozzle, grains, kGravity, "first");
    Rng rng(5);
    std::vector<NewGrain> out;
    first.emit(first.next_time(), rng, out);
    ASSERT_GT(out.size(), 50u) << what;
    for (const NewGrain& g : out) {
      EXPECT_NEAR(dot(g.x - nozzle.center, v / norm(v)), 0, 1e-12) << what;
      EXPECT_LE(norm(g.x - nozzle.center), nozzle.radius - 0.0005 + 1e-12) << what;
    }
    nozzle.jitter = 0.5;
    const PourFlight f = pour_flight(nozzle, 30);
    ASSERT_GT(f.grains.size(), 1500u) << what;
    EXPECT_GE(closest_gap_in_flight(f), -1e-12) << what;
  }
  // thrown up at 0.1 m/s, a grain stops within 0.5 mm: short of its own slot spacing
  EmitterConfig up = sideways_pour({0, 0, 0.1}, 100);
  up.facing = PourFacing::Velocity;
  try {
    Emitter(up, grains, kGravity, "s.toml: emitter[0]");
    ADD_FAILURE() << "a nozzle that cannot clear its slots was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("stop within one spacing"), std::string::npos) << e.what();
  }
  up.velocity = {0, 0, 0.5};  // clears them
  EXPECT_GT(Emitter(up, grains, kGravity, "s.toml: emitter[0]").max_rate(), 0);
}

// The box around a pour's area that the grid, the camera and the world's bounds use holds every
// slot of it, level or facing any throw, a disk or a rectangle, and is no larger than the area
// needs (within a slot of it along each axis).
TEST(Emitters, ThePourRegionBoundsItsSlotsAtAnyAim) {
  const MaterialConfig grains = millimetre_grains();
  const Vec3 none{0, 0, 0};  // (no gravity: no slot leads its batch, each grain is at its slot)
  for (const Vec3 v : {Vec3{0, 0, -1}, Vec3{2, 0, 0}, Vec3{1, 1, -1}, Vec3{0.3, -2, 1}})
    for (const PourShape shape : {PourShape::Disk, PourShape::Rect})
      for (const PourFacing facing : {PourFacing::Up, PourFacing::Velocity}) {
        EmitterConfig e = sideways_pour(v, 1);
        e.shape = shape;
        e.size = {0.02, 0.008, 0};
        e.facing = facing;
        e.jitter = 0;
        const std::string what = fmt::format("velocity ({}, {}, {}), {}, {}", v.x, v.y, v.z,
                                             shape == PourShape::Disk ? "disk" : "rect",
                                             facing == PourFacing::Up ? "up" : "velocity");
        e.rate = 0.999 * Emitter(e, grains, none, "probe").max_rate();  // every slot
        Emitter emitter(e, grains, none, "test");
        Rng rng(2);
        std::vector<NewGrain> out;
        emitter.emit(emitter.next_time(), rng, out);
        ASSERT_GT(out.size(), 10u) << what;
        const Vec3 half = emitter_half_extent(e);
        Vec3 lo = out[0].x, hi = out[0].x;
        for (const NewGrain& g : out) {
          lo = min(lo, g.x);
          hi = max(hi, g.x);
        }
        for (int k = 0; k < 3; ++k) {
          const Real c = k == 0 ? e.center.x : k == 1 ? e.center.y : e.center.z;
          const Real l = k == 0 ? lo.x : k == 1 ? lo.y : lo.z;
          const Real h = k == 0 ? hi.x : k == 1 ? hi.y : hi.z;
          const Real r = k == 0 ? half.x : k == 1 ? half.y : half.z;
          EXPECT_GE(l, c - r - 1e-12) << what << ", axis " << k;
          EXPECT_LE(h, c + r + 1e-12) << what << ", axis " << k;
          EXPECT_LE(r - std::max(c - l, h - c), 0.0005 + 0.00105 * 1.5) << what << ", axis " << k;
        }
      }
}

TEST(Emitters, ABoxTooSmallForItsCountIsRefusedWithWhatItHolds) {
  // 3 x 3 x 3 slots at 1.05 mm in a 3.2 mm box
  const EmitterConfig e = block({0, 0, 1}, {0.0032, 0.0032, 0.0032}, 28);
  try {
    Emitter emitter(e, millimetre_grains(), kGravity, "s.toml: emitter[0]");
    FAIL() << "no error";
  } catch (const InputError& err) {
    EXPECT_NE(std::string(err.what()).find("the box holds only 27 grains"), std::string::npos)
        << err.what();
  }
  EXPECT_NO_THROW(Emitter(block({0, 0, 1}, {0.0032, 0.0032, 0.0032}, 27), millimetre_grains(),
                          kGravity, "s.toml: emitter[0]"));
}

TEST(Emitters, ImpossibleSizesAreNamedByTheirKeyBeforeAnythingIsMade) {
  EmitterConfig pour;
  pour.type = EmitterType::Pour;
  pour.center = {0, 0, 0.5};
  pour.count = 10;
  pour.radius = 1000;  // a disk 2 km across of 1 mm grains: about 3.3e12 slots
  auto problem = emitter_problem(pour, millimetre_grains());
  ASSERT_TRUE(problem);
  EXPECT_STREQ(problem->key, "radius");
  EXPECT_NE(problem->what.find("more than the limit of 16777216"), std::string::npos)
      << problem->what;
  pour.radius = 1.0;  // 3.3 million slots: allowed
  EXPECT_FALSE(emitter_problem(pour, millimetre_grains()));

  // beyond 2^40 spacings from the origin, x += spacing stops moving x
  EmitterConfig far = block({1.7e308, 0, 1}, {0.01, 0.01, 0.01}, 10);
  problem = emitter_problem(far, millimetre_grains());
  ASSERT_TRUE(problem);
  EXPECT_STREQ(problem->key, "center");
  far.center = {1.0e10, 0, 1};  // 10^13 spacings out: refused
  EXPECT_TRUE(emitter_problem(far, millimetre_grains()));
  far.center = {1.0e6, 0, 1};  // 10^9 spacings out: placed exactly enough
  EXPECT_FALSE(emitter_problem(far, millimetre_grains()));

  // a box thinner than a grain on one side holds nothing, whatever its other sides
  problem = emitter_problem(block({0, 0, 50}, {0.0005, 100, 100}, 10), millimetre_grains());
  ASSERT_TRUE(problem);
  EXPECT_STREQ(problem->key, "size");
  EXPECT_THROW(Emitter(block({0, 0, 50}, {0.0005, 100, 100}, 10), millimetre_grains(), kGravity,
                       "test"),
               InputError);
}

TEST(Emitters, BoxSlotsCountsWhatTheBoxPlaces) {
  // box_slots counts without placing: the same number as placing them all, for cubic and
  // close-packed boxes of awkward sizes (rows that just fit, just miss, odd half offsets)
  const MaterialConfig m = millimetre_grains();
  for (EmitterType type : {EmitterType::Block, EmitterType::Lattice})
    for (Vec3 size : {Vec3{0.0105, 0.0105, 0.0105}, Vec3{0.0031, 0.0177, 0.0093},
                      Vec3{0.001, 0.0021, 0.0052}, Vec3{0.02, 0.0149, 0.0121}}) {
      EmitterConfig e = block({0, 0, 0}, size, 1);
      e.type = type;
      e.count = static_cast<std::int64_t>(box_slots(e, m));
      ASSERT_GT(e.count, 0);
      EXPECT_NO_THROW(Emitter(e, m, kGravity, "test"));  // it holds its count
      e.count += 1;                                      // and no more
      EXPECT_THROW(Emitter(e, m, kGravity, "test"), InputError)
          << (type == EmitterType::Block ? "block " : "lattice ") << size.x << " " << size.y << " "
          << size.z;
    }
}

SceneConfig scene_of(std::vector<EmitterConfig> emitters) {
  SceneConfig s;
  s.material = millimetre_grains();
  s.emitters = std::move(emitters);
  return s;
}

TEST(Scaling, APourKeepsItsStartAndDuration) {
  // --grains previews the same shot: a pour of a tenth of the grains pours for as long, thinner
  EmitterConfig pour;
  pour.center = {0, 0, 0.2};
  pour.radius = 0.01;
  pour.rate = 2000;
  pour.count = 4000;
  pour.start = 0.5;
  SceneConfig s = scene_of({pour});
  const Emitter before(s.emitters[0], s.material, kGravity, "test");
  scale_grain_count(s, 400);
  const Emitter after(s.emitters[0], s.material, kGravity, "test");
  EXPECT_EQ(s.emitters[0].count, 400);
  EXPECT_DOUBLE_EQ(s.emitters[0].rate, 200);
  EXPECT_DOUBLE_EQ(s.emitters[0].start, 0.5);
  // the same end within a batch (the batches are the same, fewer grains in each): a batch waits
  // for the last to fall one spacing, sqrt(2 * 1.05 mm / g) = 15 ms
  const Real batch = std::sqrt(2 * 1.05e-3 / 9.81);
  EXPECT_NEAR(after.end_time(), before.end_time(), batch);
  EXPECT_NEAR(before.end_time(), 0.5 + 2.0, batch);
}

TEST(Scaling, APourScaledPastWhatItCanEmitSaysSo) {
  EmitterConfig pour;
  pour.center = {0, 0, 0.2};
  pour.radius = 0.003;
  pour.rate = 1000;
  pour.count = 1000;
  SceneConfig s = scene_of({pour});
  scale_grain_count(s, 1'000'000);
  try {
    Emitter(s.emitters[0], s.material, kGravity, "emitter.0");
    FAIL() << "a million grains in a second from a 6 mm disk";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("scaled with the count by --grains"), std::string::npos) << what;
    EXPECT_NE(what.find("the scene's 1000"), std::string::npos) << what;
  }
}

TEST(Scaling, ABlockKeepsItsShapeAndItsBottom) {
  // a full 20 x 10 x 40 block at 1.05 d, scaled down eightfold and up eightfold
  const MaterialConfig m = millimetre_grains();
  const Real a = 1.05 * m.diameter;
  const Vec3 size{20 * a, 10 * a, 40 * a};
  const EmitterConfig full = block({0.1, -0.2, 0.3}, size, 8000);
  ASSERT_EQ(box_slots(full, m), 8000);
  for (std::int64_t n : {1000, 64000}) {
    SceneConfig s = scene_of({full});
    scale_grain_count(s, n);
    const EmitterConfig& e = s.emitters[0];
    const Real k = std::cbrt(static_cast<Real>(n) / 8000);
    // the proportions, within a row of the lattice on each side
    EXPECT_NEAR(e.size.x, size.x * k, 1.5 * a) << n;
    EXPECT_NEAR(e.size.y, size.y * k, 1.5 * a) << n;
    EXPECT_NEAR(e.size.z, size.z * k, 1.5 * a) << n;
    EXPECT_NEAR(e.size.z / e.size.x, 2.0, 0.25) << n;
    // the same bottom and the same centre across
    EXPECT_NEAR(e.center.z - e.size.z / 2, 0.3 - size.z / 2, 1e-12) << n;
    EXPECT_DOUBLE_EQ(e.center.x, 0.1);
    EXPECT_DOUBLE_EQ(e.center.y, -0.2);
    // it holds its count, and it is full: at most a layer of the box empty
    EXPECT_GE(box_slots(e, m), static_cast<Real>(n)) << n;
    EXPECT_NO_THROW(Emitter(e, m, kGravity, "test"));
    EXPECT_LT(box_slots(e, m), n * (1 + 2.5 * a / e.size.z)) << n;
  }
}

TEST(Scaling, ATinyCountStillGetsABoxThatHoldsIt) {
  const MaterialConfig m = millimetre_grains();
  SceneConfig s = scene_of({block({0, 0, 0.5}, {0.5, 0.02, 0.3}, 100000)});
  scale_grain_count(s, 3);
  EXPECT_EQ(s.emitters[0].count, 3);
  EXPECT_GE(box_slots(s.emitters[0], m), 3);
  EXPECT_NO_THROW(Emitter(s.emitters[0], m, kGravity, "test"));
}

}  // namespace
}  // namespace sandflow
