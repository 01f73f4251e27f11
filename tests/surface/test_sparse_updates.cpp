// Only what can change is updated (docs/design.md §4): a height field that skips the columns
// which cannot change ends bit for bit where one that updates every column ends, and a closed
// bed at rest costs no column's work; the index of the static grains near a point, kept up to
// date column by column, finds what brute force finds.
#include <gtest/gtest.h>

#include <set>
#include <vector>

#include "core/rng.hpp"
#include "surface/height_field.hpp"
#include "surface/interface_layer.hpp"
#include "surface/static_reach.hpp"

namespace sandflow {
namespace {

HeightFieldParams bed_params(int n) {
  HeightFieldParams p;
  p.cell = 0.01;
  p.nx = p.ny = n;
  p.theta0 = deg_to_rad(32);
  p.theta_max = deg_to_rad(38);
  p.rolling_min = 0.01;
  p.avalanche_depth = 0.01;
  p.close_after = 0.05;
  p.flowing_min = 0.02;  // (a stopped flow's layer held for a while: one more state to follow)
  p.flowing_hold = 0.03;
  return p;
}

// A flat bed 10 cm deep with a steep mound in one corner (which avalanches), every column closed.
HeightField closed_bed(int n, bool mound) {
  HeightField hf(bed_params(n), std::vector<Real>(static_cast<std::size_t>(n) * n, 0.0));
  std::vector<Real> h(hf.columns(), 0.1);
  if (mound)
    for (std::size_t c = 0; c < hf.columns(); ++c) {
      const Vec3 x = hf.centre(c);
      h[c] += std::max(0.0, 0.1 - norm(Vec3{x.x - 0.08, x.y - 0.08, 0}));  // 45 degrees
    }
  hf.set_surface(h);
  hf.set_static_top(h);
  for (std::size_t c = 0; c < hf.columns(); ++c) hf.close(c);
  return hf;
}

TEST(SparseUpdates, SkippingTheColumnsThatCannotChangeChangesNothing) {
  const int n = 40;
  HeightField sparse = closed_bed(n, true), full = closed_bed(n, true);
  std::vector<Real> tops = sparse.static_top();
  Rng rng(3);
  const Real dt = 0.005;
  std::size_t most = 0;
  for (int update = 0; update < 60; ++update) {
    // a few grains resting on the bed in one strip, some moving the pile; none after update 40
    Grains hot;
    ColumnSet flowing(sparse.columns());
    if (update < 40)
      for (GrainId id = 0; id < 6; ++id) {
        const Real x = rng.uniform(0.2, 0.3), y = rng.uniform(0.05, 0.35);
        hot.add(id, {x, y, sparse.static_top_at(x, y) + 0.004}, {}, 0.005, 2600);
        if (id % 2 == 0)
          sparse.for_each_ray_hit(hot.x.back(), 0.005, [&](std::size_t c, Real, Real) {
            flowing.add(static_cast<std::uint32_t>(c));
          });
      }
    // static grains woken in one column now and then: its static top falls
    std::vector<std::uint32_t> changed;
    if (update % 7 == 3) {
      const auto c = static_cast<std::uint32_t>(rng.uniform(0.0, 1.0) * sparse.columns()) %
                     static_cast<std::uint32_t>(sparse.columns());
      tops[c] -= 0.005;
      changed.push_back(c);
    }
    sparse.measure(hot, tops, {}, &changed);
    full.set_static_top(full.static_top());  // (every column, as if anything had changed)
    full.measure(hot, tops);
    sparse.exchange(dt, flowing);
    full.exchange(dt, flowing);
    // an impact lowers h under one grain
    if (update % 5 == 1 && !hot.x.empty()) {
      const std::int64_t c = sparse.column_of(hot.x[0].x, hot.x[0].y);
      sparse.limit_static_top(static_cast<std::size_t>(c), hot.x[0].z - 0.02);
      full.limit_static_top(static_cast<std::size_t>(c), hot.x[0].z - 0.02);
    }
    if (update > 0) most = std::max(most, sparse.evaluated_columns());
    ASSERT_EQ(sparse.surface(), full.surface()) << "update " << update;
    ASSERT_EQ(sparse.static_top(), full.static_top()) << "update " << update;
    ASSERT_EQ(sparse.rolling(), full.rolling()) << "update " << update;
    ASSERT_EQ(sparse.slope(), full.slope()) << "update " << update;
    ASSERT_EQ(sparse.exchange_rate(), full.exchange_rate()) << "update " << update;
    ASSERT_EQ(sparse.rest(), full.rest()) << "update " << update;
    ASSERT_EQ(sparse.hold_left(), full.hold_left()) << "update " << update;
  }
  // the work followed the grains, the mound and the woken columns, not the 1,600 columns
  EXPECT_LT(most, sparse.columns() / 2);
  EXPECT_GT(most, 0u);
}

TEST(SparseUpdates, AClosedBedAtRestCostsNoColumnsWork) {
  HeightField hf = closed_bed(100, false);
  const std::vector<Real> tops = hf.static_top();
  const std::vector<std::uint32_t> none;
  ColumnSet flowing(hf.columns());
  const Real dt = 0.005;
  hf.measure(Grains{}, tops, {}, &none);
  hf.exchange(dt, flowing);
  EXPECT_EQ(hf.evaluated_columns(), hf.columns());  // the first update sees everything
  hf.measure(Grains{}, tops, {}, &none);
  hf.exchange(dt, flowing);
  EXPECT_EQ(hf.evaluated_columns(), 0u);
  // one grain lands and moves the pile: its columns flow and open
  Grains hot;
  hot.add(0, {0.5, 0.5, 0.104}, {}, 0.005, 2600);
  hf.for_each_ray_hit(hot.x[0], 0.005, [&](std::size_t c, Real, Real) {
    flowing.add(static_cast<std::uint32_t>(c));
  });
  hf.measure(hot, tops, {}, &none);
  hf.exchange(dt, flowing);
  EXPECT_GT(hf.evaluated_columns(), 0u);
  EXPECT_LE(hf.evaluated_columns(), 30u);  // its columns and their neighbours
  // it leaves: its columns close again after close_after, and only they are evaluated while
  // their rolling layer settles (the exchange deposits a fraction of it at each update)
  flowing.clear();
  std::size_t most = 0;
  for (int update = 0; update < 20; ++update) {
    hf.measure(Grains{}, tops, {}, &none);
    hf.exchange(dt, flowing);
    most = std::max(most, hf.evaluated_columns());
  }
  EXPECT_LE(most, 30u);
  for (std::size_t c = 0; c < hf.columns(); ++c) EXPECT_TRUE(hf.closed(c)) << c;
}

TEST(SparseUpdates, TheReachIndexFollowsAStoreThatChanges) {
  HeightFieldParams p;
  p.cell = 0.01;
  p.nx = 20;
  p.ny = 15;
  HeightField hf(p, std::vector<Real>(static_cast<std::size_t>(p.nx * p.ny), 0.0));
  Rng rng(11);
  StaticStore st(static_frame(hf, -1.0, 1.0, 0.004, 0.006));
  std::vector<std::uint32_t> held;
  GrainId next = 0;
  auto add_some = [&](int count) {
    for (int k = 0; k < count; ++k) {
      const Vec3 x{rng.uniform(0.0, 0.2), rng.uniform(0.0, 0.15), rng.uniform(0.0, 0.08)};
      held.push_back(st.add(next++, x, rng.uniform(0.0045, 0.0055),
                            static_cast<std::uint32_t>(hf.column_of(x.x, x.y))));
    }
  };
  add_some(800);
  StaticReach reach;
  for (int round = 0; round < 6; ++round) {
    reach.prepare(hf, st, 0.004 + 0.003 * round);  // (a wider reach now and then)
    for (int q = 0; q < 150; ++q) {
      const Vec3 x{rng.uniform(-0.02, 0.22), rng.uniform(-0.02, 0.17), rng.uniform(-0.02, 0.11)};
      const Real extra = rng.uniform(0.0, 0.004 + 0.003 * round);
      std::set<std::uint32_t> fast, brute;
      reach.for_each_within(hf, st, x, extra, [&](std::uint32_t k) { fast.insert(k); });
      st.for_each([&](const StaticGrain& g) {
        if (norm(x - g.x) < extra + g.r) brute.insert(g.slot);
      });
      ASSERT_EQ(fast, brute) << "round " << round << ", query " << q;
    }
    // some grains leave (the highest of a column among them) and others come
    std::vector<std::uint32_t> gone;
    st.for_each([&](const StaticGrain& g) {
      if (rng.uniform(0.0, 1.0) < 0.1) gone.push_back(g.slot);
    });
    st.remove(gone);
    add_some(60);
  }
}

}  // namespace
}  // namespace sandflow
