// Energy through the changes of state (docs/design.md §5: a transition creates no energy): trapping
// removes the grain's kinetic energy and the springs of its contacts with frozen grains, and
// counts them; a dislodged grain that lies inside a frozen one starts with its contact preloaded,
// so that the spring gives back nothing at once and pushes the two apart slowly.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "sim/world.hpp"
#include "surface/interface_layer.hpp"

namespace sandflow {
namespace {

constexpr Real kD = 0.01;
constexpr Real kR = kD / 2;
constexpr Real kDensity = 2600;

DemParams params() {
  DemParams p;
  MaterialConfig m;
  m.k_n = 1e4;
  p.contact = contact_params(m);
  p.skin = 0.2 * kD;
  p.gravity = {};
  return p;
}

// contact time of a grain against a fixed one at k_n = 1e4 N/m
Real contact_time_on_fixed() {
  const Real m = kDensity * kPi / 6 * kD * kD * kD;
  return contact_time(m, 1e4);
}

TEST(TransitionEnergy, TrappingCountsTheKineticEnergyItRemoves) {
  HeightFieldParams p;
  p.cell = kD;
  p.nx = p.ny = 4;
  HeightField hf(p, std::vector<Real>(16, 0.0));
  hf.set_surface(std::vector<Real>(16, 0.03));
  hf.set_static_top(std::vector<Real>(16, 0.02));
  InterfaceLayer layer{InterfaceParams{}};
  Grains hot;
  StaticStore st(static_frame(hf, -1.0, 1.0, 0.004, 0.006));
  hot.add(0, {0.015, 0.015, 0.01}, {0.03, -0.04, 0.0}, kR, kDensity);  // below h, slow
  hot.w[0] = {2, 0, 1};
  const Real kinetic =
      0.5 * hot.m[0] * norm2(hot.v[0]) + 0.5 / hot.inv_I[0] * norm2(hot.w[0]);
  std::vector<std::uint8_t> contacts(1, DemSolver::kTouches | DemSolver::kSeated);
  const TransitionCounts n = layer.transfer(hf, hot, st, contacts).counts;
  ASSERT_EQ(n.trapped, 1);
  EXPECT_NEAR(n.energy_trapped, kinetic, 1e-15);
}

TEST(TransitionEnergy, ContactsOfTwoFrozenGrainsGoInertWithTheirSpringEnergyCounted) {
  // two grains pressed together, both then frozen: their contact stops acting at the next step
  Grains hot;
  const Real delta = 0.05 * kD;
  hot.add(0, {0, 0, 0}, {}, kR, kDensity);
  hot.add(1, {kD - delta, 0, 0}, {}, kR, kDensity);
  DemSolver dem(params());
  Profile profile;
  dem.step(hot, Geometry{}, 1e-6, profile);  // the contact opens
  const Real gap = kD - norm(hot.x[1] - hot.x[0]);
  hot.state[0] = hot.state[1] = GrainState::Interface;
  dem.counters() = {};
  dem.step(hot, Geometry{}, 1e-6, profile);
  EXPECT_NEAR(dem.counters().energy_inert, 0.5 * 1e4 * gap * gap, 1e-12);
}

// Grain B, just dislodged, lies `delta` inside frozen grain A (two grains frozen inside each other
// by an impact, as a pour's stream leaves them). Returns the largest kinetic energy B reaches
// over `steps` steps, over the energy of the spring at that overlap; `released` says whether the
// change of state is made known to the DEM (DemSolver::apply), which preloads the contact.
struct Dislodged {
  Real peak_kinetic_over_spring = 0;
  Real preloaded = 0, relaxed = 0, final_overlap = 0, spring = 0;
};
Dislodged dislodge_inside(Real delta, bool released, int steps) {
  DemParams p = params();
  p.preload_relax_time = 5 * contact_time_on_fixed();
  DemSolver dem(p);
  Grains hot;
  hot.add(0, {0, 0, 0}, {}, kR, kDensity);
  hot.add(1, {kD - delta, 0, 0}, {}, kR, kDensity);
  hot.state[0] = GrainState::Interface;
  const StateChange dislodged[] = {{1, GrainState::Interface, GrainState::Active}};
  if (released)
    dem.apply(dislodged);
  else
    dem.invalidate();
  const Real dt = contact_time_on_fixed() / 50;
  Dislodged out;
  out.spring = 0.5 * 1e4 * delta * delta;
  Profile profile;
  for (int s = 0; s < steps; ++s) {
    dem.step(hot, Geometry{}, dt, profile);
    const Real kinetic = 0.5 * hot.m[1] * norm2(hot.v[1]);
    out.peak_kinetic_over_spring = std::max(out.peak_kinetic_over_spring, kinetic / out.spring);
  }
  out.preloaded = dem.counters().energy_preloaded;
  out.relaxed = dem.counters().energy_released;
  out.final_overlap = kD - norm(hot.x[1] - hot.x[0]);
  return out;
}

TEST(TransitionEnergy, ADislodgedGrainInsideAFrozenOneStartsPreloadedAndIsPushedOutSlowly) {
  const Real delta = 0.15 * kD;
  const Real tau = 5 * contact_time_on_fixed();
  const int steps = static_cast<int>(30 * tau / (contact_time_on_fixed() / 50));
  const Dislodged d = dislodge_inside(delta, true, steps);
  EXPECT_NEAR(d.preloaded, d.spring, 1e-12 * d.spring);  // the energy withheld
  // pushed apart about as fast as the preload decays (delta / tau): its kinetic energy stays a
  // small part of the spring's, (t_c / (pi tau))^2 = 0.4 % at the steady lag, with the start
  EXPECT_LT(d.peak_kinetic_over_spring, 0.03);
  EXPECT_LT(d.final_overlap, 0.01 * delta);  // and the overlap is gone
  // the springs' work as the preload relaxed: no more than the energy it withheld
  EXPECT_GT(d.relaxed, 0.0);
  EXPECT_LE(d.relaxed, d.spring * (1 + 1e-9));

  // unannounced, the same change of state fires the grain off with a large part of the spring
  const Dislodged raw = dislodge_inside(delta, false, steps);
  EXPECT_EQ(raw.preloaded, 0.0);
  EXPECT_GT(raw.peak_kinetic_over_spring, 0.1);
}

}  // namespace
}  // namespace sandflow
