// The compact store of STATIC grains (dem/grains.hpp): what comes back is within the frame's bound
// of what went in, the store costs at most 16 bytes a grain at a million grains, each column's
// main body ascends in height through adds, removes and merges, and its compact form restores it
// slot for slot.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <stdexcept>
#include <vector>

#include "core/error.hpp"
#include "core/rng.hpp"
#include "dem/grains.hpp"

namespace sandflow {
namespace {

constexpr Real kD = 0.01;      // mean diameter [m]
constexpr Real kSpread = 0.1;  // radii in d (1 +- spread) / 2

// A frame as World makes one for a scene of 1 cm grains: `cell` wide columns, nx x ny of them from
// (-0.5, -0.4), the domain [-1, 3] m along z widened by its height on both sides.
StaticFrame scene_frame(std::uint32_t nx, std::uint32_t ny, Real cell = kD) {
  StaticFrame f;
  f.x0 = -0.5;
  f.y0 = -0.4;
  f.cell = cell;
  f.nx = nx;
  f.ny = ny;
  f.z_lo = -1.0 - 4.0;
  f.z_hi = 3.0 + 4.0;
  f.r_lo = 0.5 * kD * (1 - kSpread);
  f.r_hi = 0.5 * kD * (1 + kSpread);
  return f;
}

struct Placed {
  Vec3 x;
  Real r;
  std::uint32_t column;
};

// A grain somewhere in column c (u, v: where in its square, in cells), at height z.
Placed in_column(const StaticFrame& f, std::uint32_t c, Real u, Real v, Real z, Real r) {
  return {{f.x0 + f.cell * ((c % f.nx) + u), f.y0 + f.cell * ((c / f.nx) + v), z}, r, c};
}

Real random_radius(Rng& rng) {
  return 0.5 * kD * (1 + kSpread * rng.uniform(-1.0, 1.0));
}

// Every grain the store holds, by id.
std::map<GrainId, StaticGrain> by_id(const StaticStore& st) {
  std::map<GrainId, StaticGrain> m;
  st.for_each([&](const StaticGrain& g) { EXPECT_TRUE(m.emplace(g.id, g).second) << g.id; });
  return m;
}

TEST(StaticStore, PositionsAndRadiiComeBackWithinTheBound) {
  const StaticFrame f = scene_frame(40, 30);
  StaticStore st(f);
  Rng rng(11);
  std::vector<Placed> in;
  // anywhere in the grid, at any height of the domain
  for (int k = 0; k < 20000; ++k)
    in.push_back(in_column(f, static_cast<std::uint32_t>(rng.uniform(0.0, 1200.0 - 1e-9)),
                           rng.uniform(0.0, 1.0), rng.uniform(0.0, 1.0),
                           rng.uniform(f.z_lo, f.z_hi), random_radius(rng)));
  // on the edges of their column (and a hair beyond, where another's rounding may file them), at
  // the very top and bottom of the heights, with the smallest and largest radii
  for (Real u : {0.0, 1e-12, 0.5, 1 - 1e-12, 1.0, -0.05, 1.05})
    for (Real z : {f.z_lo, f.z_hi, 0.0, 2.5})
      for (Real r : {f.r_lo, f.r_hi})
        for (std::uint32_t c : {0u, 39u, 40u * 29, 1199u, 617u}) {
          in.push_back(in_column(f, c, u, 1 - u, z, r));
          in.push_back(in_column(f, c, 0.25, u, z, r));
        }
  for (std::size_t k = 0; k < in.size(); ++k)
    st.add(static_cast<GrainId>(k), in[k].x, in[k].r, in[k].column);
  ASSERT_EQ(st.check(), "");
  ASSERT_EQ(st.size(), in.size());

  Real worst_x = 0, worst_r = 0;
  for (const auto& [id, g] : by_id(st)) {
    const Placed& p = in[id];
    EXPECT_EQ(g.column, p.column);
    worst_x = std::max(worst_x, norm(g.x - p.x));
    worst_r = std::max(worst_r, std::abs(g.r - p.r));
    // decoding is the same arithmetic every time: the slot's accessors agree bit for bit
    EXPECT_EQ(st.position(g.slot), g.x);
    EXPECT_EQ(st.radius(g.slot), g.r);
  }
  // the frame's bounds hold (with the rounding of the doubles around them), and they are far
  // below the 0.1 % of a diameter the issue allows
  EXPECT_LE(worst_x, f.position_error() * (1 + 1e-9));
  EXPECT_LE(worst_r, f.radius_error() * (1 + 1e-9));
  EXPECT_LT(f.position_error(), 1e-4 * kD);
  EXPECT_LT(f.radius_error(), 1e-4 * kD);
  std::printf(
      "largest round-trip error: centre %.3g m = %.3g d (bound %.3g d), radius %.3g m = "
      "%.3g d (bound %.3g d)\n",
      worst_x, worst_x / kD, f.position_error() / kD, worst_r, worst_r / kD, f.radius_error() / kD);
}

TEST(StaticStore, AGrainComesBackTheSameWhateverTheLayout) {
  // the same grains added in two orders (other merges, other slots) decode bit for bit the same:
  // where a grain wakes depends on where it slept, never on the store's history
  const StaticFrame f = scene_frame(20, 20);
  Rng rng(5);
  std::vector<Placed> in;
  for (int k = 0; k < 3000; ++k)
    in.push_back(in_column(f, static_cast<std::uint32_t>(rng.uniform(0.0, 400.0 - 1e-9)),
                           rng.uniform(0.0, 1.0), rng.uniform(0.0, 1.0), rng.uniform(0.0, 0.3),
                           random_radius(rng)));
  StaticStore a(f), b(f);
  for (std::size_t k = 0; k < in.size(); ++k)
    a.add(static_cast<GrainId>(k), in[k].x, in[k].r, in[k].column);
  for (std::size_t k = in.size(); k-- > 0;) {
    b.add(static_cast<GrainId>(k), in[k].x, in[k].r, in[k].column);
    if (k % 7 == 0) {  // a few wake and sleep again on the way
      const std::uint32_t slot = by_id(b).at(static_cast<GrainId>(k)).slot;
      b.remove(std::vector<std::uint32_t>{slot});
      b.add(static_cast<GrainId>(k), in[k].x, in[k].r, in[k].column);
    }
  }
  const auto ga = by_id(a), gb = by_id(b);
  ASSERT_EQ(ga.size(), gb.size());
  for (const auto& [id, g] : ga) {
    EXPECT_EQ(g.x, gb.at(id).x) << id;
    EXPECT_EQ(g.r, gb.at(id).r) << id;
  }
}

// Fills a store with `n` grains over nx x nx columns of `cell`, in a random order of columns (the
// order a bed or a pour might bring them), a column's grains stacked a diameter apart.
void fill(StaticStore& st, std::size_t n, Rng& rng) {
  const StaticFrame& f = st.frame();
  const std::size_t nc = f.columns();
  std::vector<std::uint32_t> height(nc, 0);
  for (std::size_t k = 0; k < n; ++k) {
    const auto c = static_cast<std::uint32_t>(rng.uniform(0.0, static_cast<Real>(nc) - 1e-9));
    const Placed p = in_column(f, c, rng.uniform(0.0, 1.0), rng.uniform(0.0, 1.0),
                               (height[c]++ + 0.5) * kD, random_radius(rng));
    st.add(static_cast<GrainId>(k), p.x, p.r, p.column);
  }
}

Real bytes_per_grain(const StaticStore& st) {
  return static_cast<Real>(st.allocated_bytes()) / static_cast<Real>(st.size());
}

TEST(StaticStore, AMillionGrainsCostAtMostSixteenBytesEach) {
  // a million grains, 20 to a column of a diameter, then 50 to a column of 1.6 diameters: the
  // store's own accounting (the capacity of every array it holds), after the fill and through
  // rounds of waking and sleeping (the tail filling, merges, empty slots)
  struct Case {
    std::uint32_t nx;
    Real cell;
  };
  for (const Case cs : {Case{224, kD}, Case{141, 1.6 * kD}}) {
    StaticStore st(scene_frame(cs.nx, cs.nx, cs.cell));
    Rng rng(3);
    fill(st, 1'000'000, rng);
    ASSERT_EQ(st.size(), 1'000'000u);
    ASSERT_EQ(st.check(), "");
    Real worst = bytes_per_grain(st);
    const Real after_fill = worst;
    // rounds: a thousand grains wake (a random patch of slots), then sleep again
    std::vector<std::uint32_t> slots;
    std::vector<StaticGrain> woken;
    for (int round = 0; round < 60; ++round) {
      slots.clear();
      woken.clear();
      const std::uint32_t from =
          static_cast<std::uint32_t>(rng.uniform(0.0, static_cast<Real>(st.slot_count() - 2000)));
      for (std::uint32_t k = from; k < from + 2000 && woken.size() < 1000; ++k)
        if (st.holds(k)) {
          slots.push_back(k);
          woken.push_back(st.grain(k));
        }
      st.remove(slots);
      worst = std::max(worst, bytes_per_grain(st));
      for (const StaticGrain& g : woken) {
        st.add(g.id, g.x, g.r, g.column);
        worst = std::max(worst, bytes_per_grain(st));
      }
    }
    ASSERT_EQ(st.check(), "");
    EXPECT_EQ(st.size(), 1'000'000u);
    EXPECT_LE(worst, 16.0);
    std::printf(
        "1,000,000 grains in %zu columns (%.0f a column): %.2f bytes a grain after the "
        "fill, %.2f at most through 60 rounds of 1,000 woken and put back\n",
        st.columns(), 1e6 / static_cast<double>(st.columns()), after_fill, worst);
  }
}

TEST(StaticStore, ColumnsAscendInHeightThroughAddsRemovesAndMerges) {
  // a model of the store (a map by id) against the store, through random sleeps and wakes that
  // cross many merges; after each batch every column holds exactly its grains, its main body
  // ascending in height, and the height-band query finds what a filter finds
  const StaticFrame f = scene_frame(12, 10);
  StaticStore st(f);
  Rng rng(9);
  std::map<GrainId, Placed> model;
  GrainId next = 0;
  for (int batch = 0; batch < 200; ++batch) {
    const int adds = static_cast<int>(rng.uniform(0.0, 60.0));
    for (int k = 0; k < adds; ++k) {
      const auto c = static_cast<std::uint32_t>(rng.uniform(0.0, 120.0 - 1e-9));
      const Placed p = in_column(f, c, rng.uniform(0.0, 1.0), rng.uniform(0.0, 1.0),
                                 rng.uniform(0.0, 0.2), random_radius(rng));
      const std::uint32_t slot = st.add(next, p.x, p.r, p.column);
      ASSERT_EQ(st.id(slot), next);  // add() names the slot it filled
      model[next++] = p;
    }
    std::vector<std::uint32_t> wake;
    st.for_each([&](const StaticGrain& g) {
      if (rng.uniform(0.0, 1.0) < 0.1) wake.push_back(g.slot);
    });
    for (std::uint32_t k : wake) model.erase(st.id(k));
    st.remove(wake);
    ASSERT_EQ(st.check(), "") << "batch " << batch;
    ASSERT_EQ(st.size(), model.size());

    for (std::uint32_t c = 0; c < f.columns(); ++c) {
      std::vector<GrainId> ids;
      std::vector<Real> main_z;  // the main body comes first, ascending; then the tail
      st.for_each_in_column(c, [&](const StaticGrain& g) {
        EXPECT_EQ(g.column, c);
        ids.push_back(g.id);
        if (g.slot < st.main_slots()) {
          EXPECT_EQ(main_z.size() + 1, ids.size()) << "a tail grain came before the main body";
          main_z.push_back(g.x.z);
        }
      });
      EXPECT_TRUE(std::is_sorted(main_z.begin(), main_z.end())) << "column " << c;
      std::vector<GrainId> want;
      for (const auto& [id, p] : model)
        if (p.column == c) want.push_back(id);
      std::sort(ids.begin(), ids.end());
      EXPECT_EQ(ids, want) << "column " << c;
      // the band query against a filter
      const Real z_lo = rng.uniform(0.0, 0.2), z_hi = z_lo + rng.uniform(0.0, 0.1);
      std::vector<GrainId> band, filtered;
      st.for_each_in_column_between(c, z_lo, z_hi,
                                    [&](const StaticGrain& g) { band.push_back(g.id); });
      st.for_each_in_column(c, [&](const StaticGrain& g) {
        if (g.x.z > z_lo && g.x.z < z_hi) filtered.push_back(g.id);
      });
      std::sort(band.begin(), band.end());
      std::sort(filtered.begin(), filtered.end());
      EXPECT_EQ(band, filtered) << "column " << c;
    }
  }
  EXPECT_GT(next, 5000u);  // enough to cross many merges
}

TEST(StaticStore, TheMainBodyOfEachColumnAscendsAfterAMerge) {
  // grains put to sleep top first, in one column: the 256th fills the tail (kTailMin), so the
  // 255 before it are merged into the main body, bottom first, and the last 45 wait in the tail
  const StaticFrame f = scene_frame(2, 1);
  StaticStore st(f);
  for (GrainId k = 0; k < 300; ++k) {
    const Placed p = in_column(f, 1, 0.5, 0.5, 1.0 - 0.001 * k, 0.005);
    st.add(k, p.x, p.r, p.column);
  }
  ASSERT_EQ(st.check(), "");
  ASSERT_EQ(st.main_slots(), StaticStore::kTailMin - 1);
  std::vector<Real> z;
  std::vector<GrainId> ids;
  st.for_each_in_column(1, [&](const StaticGrain& g) {
    z.push_back(g.x.z);
    ids.push_back(g.id);
  });
  ASSERT_EQ(z.size(), 300u);
  EXPECT_TRUE(std::is_sorted(z.begin(), z.begin() + 255));
  EXPECT_EQ(ids.front(), 254u);  // the lowest of the merged grains first
  EXPECT_EQ(ids[254], 0u);
  st.for_each_in_column(0, [&](const StaticGrain& g) { ADD_FAILURE() << "grain " << g.id; });
}

TEST(StaticStore, ItsCompactFormRestoresItSlotForSlot) {
  const StaticFrame f = scene_frame(30, 30);
  StaticStore st(f);
  Rng rng(2);
  fill(st, 20000, rng);
  std::vector<std::uint32_t> wake;
  for (std::uint32_t k = 0; k < st.slot_count(); k += 97) wake.push_back(k);
  st.remove(wake);  // some empty slots in the main body, and a tail
  for (GrainId k = 0; k < 100; ++k) {
    const Placed p = in_column(f, k % 900, 0.3, 0.7, 2.0, 0.005);
    st.add(100000 + k, p.x, p.r, p.column);
  }
  ASSERT_EQ(st.check(), "");
  const StaticStore::State s = st.save_state();
  StaticStore back(f);
  EXPECT_EQ(back.state_error(s), "");
  back.restore(s);
  EXPECT_EQ(back.check(), "");
  EXPECT_EQ(back.size(), st.size());
  EXPECT_EQ(back.slot_count(), st.slot_count());
  EXPECT_EQ(back.allocated_bytes(), st.allocated_bytes());
  std::vector<StaticGrain> a, b;
  st.for_each([&](const StaticGrain& g) { a.push_back(g); });
  back.for_each([&](const StaticGrain& g) { b.push_back(g); });
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t k = 0; k < a.size(); ++k) {
    EXPECT_EQ(a[k].slot, b[k].slot);
    EXPECT_EQ(a[k].id, b[k].id);
    EXPECT_EQ(a[k].x, b[k].x);
    EXPECT_EQ(a[k].r, b[k].r);
  }
  // and the same changes give the same store after (the same merges come at the same time)
  for (StaticStore* x : {&st, &back}) {
    Rng again(8);
    for (GrainId k = 0; k < 3000; ++k) {
      const Placed p = in_column(f, k % 900, again.uniform(0.0, 1.0), 0.5, 2.5, 0.005);
      x->add(200000 + k, p.x, p.r, p.column);
    }
  }
  EXPECT_EQ(st.save_state().id, back.save_state().id);
  EXPECT_EQ(st.save_state().code, back.save_state().code);
  EXPECT_EQ(st.allocated_bytes(), back.allocated_bytes());
}

TEST(StaticStore, AStateThatDoesNotFitIsRefusedSayingWhy) {
  const StaticFrame f = scene_frame(10, 10);
  StaticStore st(f);
  Rng rng(4);
  fill(st, 3000, rng);
  const StaticStore::State good = st.save_state();
  ASSERT_EQ(st.state_error(good), "");
  auto refused = [&](StaticStore::State s, const std::string& what) {
    const std::string e = st.state_error(s);
    EXPECT_NE(e.find(what), std::string::npos) << "got: '" << e << "', wanted: " << what;
    StaticStore other(f);
    EXPECT_THROW(other.restore(std::move(s)), std::invalid_argument);
  };
  StaticStore::State s = good;
  s.column_slots.pop_back();
  refused(s, "columns of static grains");
  s = good;
  s.code.pop_back();
  refused(s, "ids and");
  s = good;
  s.column_slots[3] += 1;
  refused(s, "but 3000 ids");
  s = good;
  // two grains of a column swapped: its heights no longer ascend
  bool swapped = false;
  for (std::uint32_t c = 0, at = 0; c < 100 && !swapped; at += s.column_slots[c++])
    for (std::uint32_t k = at; k + 1 < at + s.column_slots[c] && !swapped; ++k)
      if ((s.code[k] >> 38) < (s.code[k + 1] >> 38)) {
        std::swap(s.code[k], s.code[k + 1]);
        swapped = true;
      }
  ASSERT_TRUE(swapped);
  refused(s, "do not ascend in height");
  s = good;
  ASSERT_FALSE(s.tail_column.empty());
  s.tail_column[0] = 100;
  refused(s, "column 100 of 100");
  s = good;
  s.capacity = 1ull << 40;  // a hostile file must not make it allocate a terabyte
  refused(s, "room for");
  // a store without a frame (plain DEM mode) takes no grains
  StaticStore dem;
  EXPECT_NE(dem.state_error(good), "");
  EXPECT_EQ(dem.state_error(StaticStore::State{}), "");
}

TEST(StaticStore, WhatTheFrameCannotHoldIsRefused) {
  const StaticFrame f = scene_frame(4, 4);
  StaticStore st(f);
  const Placed ok = in_column(f, 5, 0.5, 0.5, 0.1, 0.005);
  EXPECT_NO_THROW(st.add(0, ok.x, ok.r, ok.column));
  // filed in the wrong column, above the heights, a radius outside the material's, no column
  EXPECT_THROW(st.add(1, ok.x, ok.r, 7), std::invalid_argument);
  EXPECT_THROW(st.add(2, {ok.x.x, ok.x.y, f.z_hi + 0.01}, ok.r, ok.column), SimulationError);
  EXPECT_THROW(st.add(3, ok.x, 0.007, ok.column), std::invalid_argument);
  EXPECT_THROW(st.add(4, ok.x, ok.r, 16), std::invalid_argument);
  StaticStore none;
  EXPECT_THROW(none.add(5, ok.x, ok.r, 0), std::invalid_argument);
  EXPECT_EQ(st.size(), 1u);
  StaticFrame bad = f;
  bad.z_hi = bad.z_lo;
  EXPECT_THROW(StaticStore{bad}, std::invalid_argument);
}

}  // namespace
}  // namespace sandflow
