// The index of the static grains near a point (surface/static_reach.hpp) against brute force.
#include <gtest/gtest.h>

#include <algorithm>
#include <set>
#include <vector>

#include "core/rng.hpp"
#include "surface/interface_layer.hpp"
#include "surface/static_reach.hpp"

namespace sandflow {
namespace {

TEST(StaticReach, FindsWhatBruteForceFinds) {
  HeightFieldParams p;
  p.cell = 0.01;
  p.nx = 12;
  p.ny = 9;
  p.x0 = -0.06;
  p.y0 = -0.04;
  HeightField hf(p, std::vector<Real>(static_cast<std::size_t>(p.nx * p.ny), 0.0));
  Rng rng(7);
  StaticStore st(static_frame(hf, -1.0, 1.0, 0.004, 0.006));
  // a rough pile: grains in the grid, their heights spread over 8 cm
  for (GrainId id = 0; id < 600; ++id) {
    const Vec3 x{rng.uniform(-0.06, 0.06), rng.uniform(-0.04, 0.05), rng.uniform(0.0, 0.08)};
    st.add(id, x, rng.uniform(0.0045, 0.0055), static_cast<std::uint32_t>(hf.column_of(x.x, x.y)));
  }
  StaticReach reach;
  const Real extra_max = 0.012;
  reach.prepare(hf, st, extra_max);
  std::size_t found_any = 0;
  for (int q = 0; q < 400; ++q) {
    // points in and around the grid (some outside it: grains beside the height field)
    const Vec3 x{rng.uniform(-0.08, 0.08), rng.uniform(-0.06, 0.07), rng.uniform(-0.02, 0.11)};
    const Real extra = rng.uniform(0.0, extra_max);
    std::set<std::uint32_t> fast, brute;
    reach.for_each_within(hf, st, x, extra, [&](std::uint32_t k) {
      EXPECT_TRUE(fast.insert(k).second) << "grain " << k << " found twice";
    });
    st.for_each([&](const StaticGrain& g) {
      if (norm(x - g.x) < extra + g.r) brute.insert(g.slot);
    });
    EXPECT_EQ(fast, brute) << "query " << q;
    found_any += !brute.empty();
  }
  EXPECT_GT(found_any, 50u);  // the queries did meet grains
}

TEST(StaticReach, FollowsTheStoreAsItChanges) {
  HeightFieldParams p;
  p.cell = 0.01;
  p.nx = p.ny = 5;
  HeightField hf(p, std::vector<Real>(25, 0.0));
  StaticStore st(static_frame(hf, -1.0, 1.0, 0.004, 0.006));
  st.add(0, {0.025, 0.025, 0.005}, 0.005, 12);
  StaticReach reach;
  reach.prepare(hf, st, 0.01);
  int n = 0;
  const Vec3 above{0.025, 0.025, 0.03};  // 2.5 cm above the grain: out of reach
  reach.for_each_within(hf, st, above, 0.01, [&](std::uint32_t) { ++n; });
  EXPECT_EQ(n, 0);
  // a grain higher in the same column: the index must see it (a stale top would hide it)
  const std::uint32_t higher = st.add(1, {0.025, 0.025, 0.02}, 0.005, 12);
  reach.prepare(hf, st, 0.01);
  reach.for_each_within(hf, st, above, 0.01, [&](std::uint32_t k) { n += k == higher; });
  EXPECT_EQ(n, 1);
}

}  // namespace
}  // namespace sandflow
