// The invariant of the two stores (store_error): every grain once, in the store of its state.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "dem/grains.hpp"

namespace sandflow {
namespace {

// one column of 1 cm, heights [-1, 1] m, radii [4, 6] mm
StaticFrame frame() {
  StaticFrame f;
  f.cell = 0.01;
  f.nx = f.ny = 1;
  f.z_lo = -1;
  f.z_hi = 1;
  f.r_lo = 0.004;
  f.r_hi = 0.006;
  return f;
}

// grains 0-3 hot (1 INTERFACE), 4-5 static: six of the seven ids given, one left the domain
void fill(Grains& hot, StaticStore& statics) {
  for (GrainId id : {0u, 3u, 1u, 2u}) hot.add(id, {0, 0, 0.01 * id}, {}, 0.005, 2600);
  hot.state[2] = GrainState::Interface;
  statics.add(5, {0.005, 0.005, -0.01}, 0.005, 0);
  statics.add(4, {0.005, 0.005, -0.02}, 0.005, 0);
}

bool says(const std::string& error, const std::string& what) {
  return error.find(what) != std::string::npos;
}

TEST(Stores, EveryGrainOnceInTheStoreOfItsState) {
  Grains hot;
  StaticStore statics(frame());
  fill(hot, statics);
  EXPECT_EQ(store_error(hot, statics, 7, 6), "");
  EXPECT_TRUE(says(store_error(hot, statics, 7, 7), "are 6, not 7"));
}

TEST(Stores, AGrainInBothStoresIsNamed) {
  Grains hot;
  StaticStore statics(frame());
  fill(hot, statics);
  statics.add(3, {0.005, 0.005, -0.03}, 0.005, 0);  // a sleeping grain that stayed hot
  const std::string e = store_error(hot, statics, 7, 7);
  EXPECT_TRUE(says(e, "grain 3 is in the static store and in the hot store")) << e;
}

TEST(Stores, AStaticGrainInTheHotStoreOrATwiceHeldOneIsNamed) {
  Grains hot;
  StaticStore statics(frame());
  fill(hot, statics);
  hot.state[1] = GrainState::Static;
  EXPECT_TRUE(says(store_error(hot, statics, 7, 6), "grain 3 is STATIC but in the hot store"));
  hot.state[1] = GrainState::Active;
  hot.id[1] = 0;
  EXPECT_TRUE(says(store_error(hot, statics, 7, 6), "grain 0 is twice in the hot store"));
  hot.id[1] = 9;
  EXPECT_TRUE(says(store_error(hot, statics, 7, 6), "grain 9 in the hot store: ids end at 7"));
  hot.id[1] = 3;
  hot.v.pop_back();
  EXPECT_TRUE(says(store_error(hot, statics, 7, 6), "arrays differ in length"));
}

// A shorter, ascending perm (the grains that stay awake) is done in place; every array must follow
// it, as a reordering does.
TEST(Stores, PermuteKeepsTheNamedGrainsInEveryArrayOrReordersThem) {
  Grains g;
  for (GrainId id = 0; id < 6; ++id) {
    g.add(id, {0.1 * id, 0, 0}, {0, 0.2 * id, 0}, 0.004 + 0.0002 * id, 2600);
    g.w.back() = {0, 0, 0.3 * id};
    g.state.back() = id % 2 ? GrainState::Interface : GrainState::Active;
  }
  const Grains before = g;
  auto holds = [&](const Grains& now, std::size_t k, std::size_t was) {
    return now.id[k] == before.id[was] && now.state[k] == before.state[was] &&
           now.x[k] == before.x[was] && now.v[k] == before.v[was] && now.w[k] == before.w[was] &&
           now.r[k] == before.r[was] && now.m[k] == before.m[was] &&
           now.inv_m[k] == before.inv_m[was] && now.inv_I[k] == before.inv_I[was];
  };
  const std::vector<std::uint32_t> keep{0, 2, 3, 5};
  g.permute(keep);
  ASSERT_EQ(g.size(), keep.size());
  ASSERT_EQ(g.x.size(), keep.size());
  ASSERT_EQ(g.inv_I.size(), keep.size());
  for (std::size_t k = 0; k < keep.size(); ++k) EXPECT_TRUE(holds(g, k, keep[k])) << "slot " << k;
  Grains h = before;
  const std::vector<std::uint32_t> order{4, 1, 5, 0, 3, 2};
  h.permute(order);
  for (std::size_t k = 0; k < order.size(); ++k) EXPECT_TRUE(holds(h, k, order[k])) << "slot " << k;
}

}  // namespace
}  // namespace sandflow
