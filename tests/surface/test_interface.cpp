// The four transitions of the particle interface (docs/design.md §5) against a given static top h.
#include <gtest/gtest.h>

#include <set>
#include <vector>

#include "core/rng.hpp"
#include "surface/interface_layer.hpp"

namespace sandflow {
namespace {

constexpr Real kR = 0.005;

struct Fixture {
  HeightField hf;
  Grains hot;
  StaticStore st{static_frame(hf, -1.0, 1.0, 0.004, 0.006)};
  InterfaceLayer layer;

  // a flat static top at h_level over a 10 x 10 grid of 1 cm columns, sand up to h_level + 1 cm
  explicit Fixture(Real h_level)
      : hf(params(), std::vector<Real>(100, 0.0)), layer(interface_params()) {
    set_h(h_level);
  }
  static HeightFieldParams params() {
    HeightFieldParams p;
    p.cell = 0.01;
    p.nx = p.ny = 10;
    return p;
  }
  static InterfaceParams interface_params() {
    InterfaceParams p;
    p.thickness = 0.015;
    p.seat.trap_speed = 0.1;
    p.margin = 0.0025;
    return p;
  }
  void set_h(Real h_level) {
    hf.set_surface(std::vector<Real>(100, h_level + 0.01));
    hf.set_static_top(std::vector<Real>(100, h_level));
  }
  TransitionCounts transfer() {
    std::vector<std::uint8_t> contacts(hot.size(), DemSolver::kTouches | DemSolver::kSeated);
    return layer.transfer(hf, hot, st, contacts).counts;
  }
  GrainState state_of(GrainId id) const {
    for (std::size_t i = 0; i < hot.size(); ++i)
      if (hot.id[i] == id) return hot.state[i];
    bool held = false;
    st.for_each([&](const StaticGrain& g) { held = held || g.id == id; });
    if (held) return GrainState::Static;
    ADD_FAILURE() << "grain " << id << " was lost";
    return GrainState::Static;
  }
  void expect_conserved(std::size_t n) const {
    std::set<GrainId> ids(hot.id.begin(), hot.id.end());
    st.for_each([&](const StaticGrain& g) {
      EXPECT_TRUE(ids.insert(g.id).second) << "grain " << g.id << " is twice";
    });
    EXPECT_EQ(ids.size(), n);
  }
};

TEST(Interface, SlowGrainBelowTheStaticTopIsTrapped) {
  Fixture f(0.05);
  f.hot.add(0, {0.05, 0.05, 0.045}, {0.01, 0, 0}, kR, 2600);  // slow, below h
  f.hot.add(1, {0.03, 0.05, 0.045}, {0.5, 0, 0}, kR, 2600);   // fast, below h
  f.hot.add(2, {0.07, 0.05, 0.055}, {0, 0, 0}, kR, 2600);     // at rest, above h
  f.hot.w[0] = {3, 0, 0};
  const TransitionCounts n = f.transfer();
  EXPECT_EQ(n.trapped, 1);
  EXPECT_EQ(f.state_of(0), GrainState::Interface);
  EXPECT_EQ(f.hot.v[0], Vec3{});  // frozen
  EXPECT_EQ(f.hot.w[0], Vec3{});
  EXPECT_EQ(f.state_of(1), GrainState::Active);  // a fast grain is never trapped
  EXPECT_EQ(f.state_of(2), GrainState::Active);
  f.expect_conserved(3);
}

TEST(Interface, ErosionDislodgesAndDeepGrainsSleep) {
  Fixture f(0.05);
  f.hot.add(0, {0.05, 0.05, 0.045}, {}, kR, 2600);
  f.hot.add(1, {0.05, 0.05, 0.025}, {}, kR, 2600);  // deeper than h - T - margin = 0.0325
  f.hot.state[0] = f.hot.state[1] = GrainState::Interface;
  TransitionCounts n = f.transfer();
  EXPECT_EQ(n.slept, 1);
  EXPECT_EQ(f.state_of(1), GrainState::Static);
  ASSERT_EQ(f.st.size(), 1u);
  EXPECT_EQ(f.st.grain(0).column, 5u * 10 + 5);  // filed by its column
  EXPECT_EQ(f.state_of(0), GrainState::Interface);

  // erosion: h falls 2 cm; grain 0 is now above h (dislodged), the static one within T (woken)
  f.set_h(0.03);
  n = f.transfer();
  EXPECT_EQ(n.dislodged, 1);
  EXPECT_EQ(n.woken, 1);
  EXPECT_EQ(f.state_of(0), GrainState::Active);
  EXPECT_EQ(f.state_of(1), GrainState::Interface);
  f.expect_conserved(2);
}

TEST(Interface, WithoutListChangesOnlyTrappingHappensAndTheRestWaits) {
  // what a surface update does when the pair list is fresh: a trap keeps the list (the pair of
  // two frozen grains only leaves it at the next rebuild); dislodging, sleeping and waking wait
  Fixture f(0.05);
  f.hot.add(0, {0.05, 0.05, 0.045}, {0.01, 0, 0}, kR, 2600);  // slow, below h: trapped
  f.st.add(2, {0.03, 0.03, 0.035}, kR, 3 * 10 + 3);           // static
  EXPECT_EQ(f.transfer().trapped, 1);
  f.hot.add(1, {0.05, 0.05, 0.005}, {}, kR, 2600);  // frozen, deep below the new h - T - m
  f.hot.state[1] = GrainState::Interface;
  f.hot.add(3, {0.07, 0.07, 0.025}, {0.01, 0, 0}, kR, 2600);  // slow, below the new h
  f.set_h(0.03);  // 0 is now above h + m, 1 below h - T - m, and 2 within T of h
  std::vector<std::uint8_t> contacts(f.hot.size(), DemSolver::kTouches | DemSolver::kSeated);
  TransitionCounts n = f.layer.transfer(f.hf, f.hot, f.st, contacts, false).counts;
  EXPECT_EQ(n.trapped, 1);
  EXPECT_EQ(f.state_of(3), GrainState::Interface);
  EXPECT_EQ(n.dislodged + n.slept + n.woken, 0);
  EXPECT_EQ(f.state_of(0), GrainState::Interface);
  EXPECT_EQ(f.state_of(1), GrainState::Interface);
  EXPECT_EQ(f.state_of(2), GrainState::Static);
  // the next transfer that may change the list does what waited, waking where h fell since the
  // last such transfer (not since the last update)
  contacts.assign(f.hot.size(), DemSolver::kTouches | DemSolver::kSeated);
  n = f.layer.transfer(f.hf, f.hot, f.st, contacts, true).counts;
  EXPECT_EQ(n.dislodged, 1);
  EXPECT_EQ(n.slept, 1);
  EXPECT_EQ(n.woken, 1);
  EXPECT_EQ(f.state_of(0), GrainState::Active);
  EXPECT_EQ(f.state_of(1), GrainState::Static);
  EXPECT_EQ(f.state_of(2), GrainState::Interface);
  f.expect_conserved(4);
}

TEST(Interface, GrainInFlightIsNeverTrapped) {
  Fixture f(0.05);
  f.hot.add(0, {0.05, 0.05, 0.045}, {}, kR, 2600);  // slow and below h, but touching nothing
  std::vector<std::uint8_t> contacts{0};
  EXPECT_EQ(f.layer.transfer(f.hf, f.hot, f.st, contacts).counts.trapped, 0);
  EXPECT_EQ(f.state_of(0), GrainState::Active);
}

TEST(Interface, GrainNearAnActiveOneNeverSleeps) {
  // static grains push nothing: an active grain within the Verlet skin of a sleeping one could
  // reach it before the next update and sink into the static layer
  Fixture f(0.05);
  f.hot.add(0, {0.05, 0.05, 0.02}, {}, kR, 2600);
  f.hot.state[0] = GrainState::Interface;
  std::vector<std::uint8_t> contacts{DemSolver::kTouches | DemSolver::kTouchesActive |
                                     DemSolver::kNearActive};
  EXPECT_EQ(f.layer.transfer(f.hf, f.hot, f.st, contacts).counts.slept, 0);
  contacts[0] = DemSolver::kTouches | DemSolver::kNearActive;  // not touching, but within reach
  EXPECT_EQ(f.layer.transfer(f.hf, f.hot, f.st, contacts).counts.slept, 0);
  EXPECT_EQ(f.state_of(0), GrainState::Interface);
  contacts[0] = DemSolver::kTouches;  // only interface neighbours: it may sleep
  EXPECT_EQ(f.layer.transfer(f.hf, f.hot, f.st, contacts).counts.slept, 1);
}

TEST(Interface, HysteresisKeepsGrainsNearTheEdgesStill) {
  Fixture f(0.05);
  f.hot.add(0, {0.05, 0.05, 0.051}, {}, kR, 2600);  // 1 mm above h: inside the margin
  f.hot.add(1, {0.05, 0.03, 0.034}, {}, kR, 2600);  // 1 mm above h - T - margin
  f.hot.state[0] = f.hot.state[1] = GrainState::Interface;
  EXPECT_EQ(f.transfer().total(), 0);
}

TEST(Interface, GrainsOutsideTheGridStaySimulated) {
  Fixture f(0.05);
  f.hot.add(0, {0.5, 0.5, 0.001}, {}, kR, 2600);  // far outside, far below h
  EXPECT_EQ(f.transfer().total(), 0);
  EXPECT_EQ(f.state_of(0), GrainState::Active);
}

TEST(Interface, StaticGrainsWakeOnlyWhereTheStaticTopFell) {
  Fixture f(0.05);
  f.st.add(7, {0.05, 0.05, 0.04}, kR, 55);  // within T of h: would wake if its column were visited
  f.transfer();                             // first call: h has not fallen anywhere
  EXPECT_EQ(f.state_of(7), GrainState::Static);
}

TEST(Interface, StaticTopsFollowSleepAndWakeAsIfComputedAfresh) {
  // the tops are kept as grains sleep and wake; a layer that never saw the store computes them
  // from every static grain: the two must agree exactly (both are maxima of the same hits)
  Fixture f(0.05);
  Rng rng(7);
  GrainId id = 0;
  for (int k = 0; k < 300; ++k, ++id) {
    const Vec3 x{rng.uniform(0, 0.1), rng.uniform(0, 0.1), rng.uniform(0.0, 0.03)};
    f.st.add(id, x, rng.uniform(0.0045, 0.0055), static_cast<std::uint32_t>(f.hf.column_of(x.x, x.y)));
  }
  for (int k = 0; k < 100; ++k, ++id) {  // frozen grains, some deep enough to sleep
    f.hot.add(id, {rng.uniform(0, 0.1), rng.uniform(0, 0.1), rng.uniform(0.01, 0.05)}, {},
              rng.uniform(0.0045, 0.0055), 2600);
    f.hot.state.back() = GrainState::Interface;
  }
  auto afresh = [&]() -> std::vector<Real> {
    InterfaceLayer fresh(Fixture::interface_params());
    return fresh.static_tops(f.hf, f.st);
  };
  const std::vector<Real> before = f.layer.static_tops(f.hf, f.st);
  EXPECT_EQ(before, afresh());

  TransitionCounts n = f.transfer();  // h = 0.05: the deep ones sleep
  EXPECT_GT(n.slept, 10);
  EXPECT_EQ(f.layer.static_tops(f.hf, f.st), afresh());
  EXPECT_NE(f.layer.static_tops(f.hf, f.st), before);

  f.set_h(0.02);  // the static top falls: grains above h - T wake
  const std::vector<Real> asleep = f.layer.static_tops(f.hf, f.st);
  n = f.transfer();
  EXPECT_GT(n.woken, 10);
  EXPECT_EQ(f.layer.static_tops(f.hf, f.st), afresh());
  EXPECT_NE(f.layer.static_tops(f.hf, f.st), asleep);
  f.expect_conserved(400);
}

}  // namespace
}  // namespace sandflow
