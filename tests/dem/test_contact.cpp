// The contact law against closed forms (docs/design.md §3).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <tuple>

#include "core/error.hpp"
#include "dem/contact.hpp"
#include "dem/dem_solver.hpp"
#include "sim/world.hpp"
#include "support/test_scenes.hpp"

namespace sandflow {
namespace {

ContactParams params(Real e, Real mu, Real mu_r) {
  MaterialConfig m;
  m.k_n = 1e4;
  m.restitution = e;
  m.friction = mu;
  m.rolling_friction = mu_r;
  return contact_params(m);
}

ContactGeometry pair_geometry(Real delta) {
  const Real r = 0.005, m = 2600 * 4.0 / 3.0 * kPi * r * r * r;
  MaterialConfig mat;
  mat.k_n = 1e4;
  return {Vec3{0, 0, 1}, delta, r, r, normal_damping(contact_params(mat), m / 2), r / 2};
}

// Two grains meet head-on with no gravity; the integrator and the law together must give back the
// restitution coefficient. The damping is calibrated for the clamped law (contact.cpp), so the
// only error left is the integrator's: O(dt), from where in a step the contact begins. At
// dt = t_c/50 that is under 2 % on average over the onset phase and under 5 % for any phase
// (measured; at the default t_c/20 the mean error is -3.6 % for e = 0.3, -1.1 % for e = 0.5).
struct Restitution {
  Real mean, worst_rel_error;
};
// With `frozen`, the second grain is an INTERFACE grain (surface mode): it pushes but never moves,
// and the first one bounces off it as off a wall.
Restitution measured_restitution(Real e, Real dt_fraction, bool frozen = false) {
  MaterialConfig mat;
  mat.k_n = 1e4;
  mat.restitution = e;
  mat.friction = 0.5;
  mat.rolling_friction = 0.1;
  DemParams p;
  p.contact = contact_params(mat);
  p.gravity = {0, 0, 0};
  p.skin = 0.002;
  const Real r = 0.005;
  const Real m_eff = mat.density * 4.0 / 3.0 * kPi * r * r * r / 2;
  const Real dt = dt_fraction * contact_time(m_eff, mat.k_n);
  const Real v0 = 0.5;
  const int phases = 16;
  Restitution out{0, 0};
  for (int k = 0; k < phases; ++k) {
    // the initial gap sweeps one step's worth of approach
    const Real gap = 2 * v0 * dt * (k + 0.5) / phases;
    Grains g;
    g.add(0, {0, 0, 0}, {v0, 0, 0}, r, mat.density);
    g.add(1, {2 * r + gap, 0, 0}, {-v0, 0, 0}, r, mat.density);
    if (frozen) {
      // the same approach speed against a partner at rest: the contact lasts sqrt(2) longer
      g.v[0] = {2 * v0, 0, 0};
      g.v[1] = {};
      g.state[1] = GrainState::Interface;
    }
    DemSolver dem(p);
    Geometry none;
    Profile prof;
    for (int s = 0; s < static_cast<int>(5 / dt_fraction); ++s) dem.step(g, none, dt, prof);
    const Real measured = (g.v[1].x - g.v[0].x) / (2 * v0);
    out.mean += measured / phases;
    out.worst_rel_error = std::max(out.worst_rel_error, std::abs(measured - e) / e);
  }
  return out;
}

TEST(ContactLaw, HeadOnRestitutionWithinTwoPercent) {
  for (Real e : {0.3, 0.5, 0.9}) {
    const Restitution m = measured_restitution(e, 0.02);
    EXPECT_NEAR(m.mean, e, 0.02 * e) << "restitution " << e;
    EXPECT_LT(m.worst_rel_error, 0.05) << "restitution " << e;
  }
}

TEST(ContactLaw, BounceOnAFrozenGrainKeepsTheRestitution) {
  // damped with the pair's reduced mass, a grain bounced off a frozen one at e = 0.44 for 0.3
  for (Real e : {0.3, 0.5, 0.9}) {
    const Restitution m = measured_restitution(e, 0.02, true);
    EXPECT_NEAR(m.mean, e, 0.02 * e) << "restitution " << e;
    EXPECT_LT(m.worst_rel_error, 0.05) << "restitution " << e;
  }
}

TEST(ContactLaw, NormalForceNeverPulls) {
  // separating fast: the dashpot would pull, the clamp forbids it
  ContactHistory h;
  const auto f =
      contact_force<true>(params(0.3, 0.5, 0.1), pair_geometry(1e-6), {0, 0, 10}, {}, {}, h, 1e-5);
  EXPECT_EQ(f.f_n, 0.0);
  EXPECT_EQ(f.force_i.z, 0.0);
}

TEST(ContactLaw, TangentialSpringBelowTheCap) {
  const ContactParams p = params(0.5, 10.0, 0.0);
  ContactHistory h;
  const Real dt = 1e-5;
  const Vec3 v_t{0.01, 0, 0};
  const auto f = contact_force<false>(p, pair_geometry(1e-4), v_t, {}, {}, h, dt);
  const Real c_n = pair_geometry(1e-4).c_n;
  // F_t = -k_t xi - c_t v_t with xi = v_t dt after one step
  EXPECT_NEAR(f.force_i.x, -p.k_t * v_t.x * dt - p.c_t_ratio * c_n * v_t.x, 1e-12);
  EXPECT_DOUBLE_EQ(h.xi.x, v_t.x * dt);
}

TEST(ContactLaw, CoulombCapHolds) {
  const ContactParams p = params(0.5, 0.4, 0.0);
  ContactHistory h;
  h.xi = {1e-3, 0, 0};  // a large stored displacement: the spring alone would exceed mu F_n
  const auto f = contact_force<false>(p, pair_geometry(1e-4), {0.02, 0, 0}, {}, {}, h, 1e-5);
  const Vec3 f_t{f.force_i.x, f.force_i.y, 0};
  EXPECT_NEAR(norm(f_t), 0.4 * f.f_n, 1e-12 * f.f_n);
  EXPECT_LT(f_t.x, 0);  // opposes the sliding
  // on slip the history is rescaled so the spring alone gives the capped force
  const Real c_t = p.c_t_ratio * pair_geometry(1e-4).c_n;
  EXPECT_NEAR(-p.k_t * h.xi.x - c_t * 0.02, f_t.x, 1e-12 * f.f_n);
}

// k_t_ratio = 0 and rolling_stiffness_ratio = 0 are allowed: a contact of no tangential (or
// rolling) stiffness is a dashpot capped at Coulomb's bound, and its history stays finite when it
// slips (it was divided by k = 0, and the next step was NaN).
TEST(ContactLaw, SpringsOfNoStiffnessSlipWithAFiniteHistory) {
  MaterialConfig m;
  m.k_n = 1e4;
  m.restitution = 0.5;
  m.friction = 0.1;
  m.rolling_friction = 0.1;
  m.k_t_ratio = 0;
  m.rolling_stiffness_ratio = 0;
  const ContactParams p = contact_params(m);
  ASSERT_EQ(p.k_t, 0.0);
  ASSERT_EQ(p.k_r, 0.0);
  const ContactGeometry g = pair_geometry(1e-4);
  ContactHistory h;
  // fast sliding and spinning: both dashpots exceed their caps
  const auto f = contact_force<true>(p, g, {50, 0, 0}, {0, 0, 0}, {400, 0, 0}, h, 1e-5);
  EXPECT_TRUE(f.sliding);
  EXPECT_EQ(h.xi, Vec3{});
  EXPECT_EQ(h.psi, Vec3{});
  const Vec3 f_t{f.force_i.x, f.force_i.y, 0};
  EXPECT_NEAR(norm(f_t), 0.1 * f.f_n, 1e-12 * f.f_n);
  EXPECT_TRUE(std::isfinite(norm(f.t_roll)));
}

TEST(ContactLaw, RollingTorqueCapHolds) {
  const ContactParams p = params(0.5, 0.5, 0.2);
  const ContactGeometry g = pair_geometry(1e-4);
  ContactHistory h;
  h.psi = {0, -1e-2, 0};  // a large stored rolling displacement, along the rolling motion
  // opposite spins about x: the surfaces roll on each other without sliding
  const auto f = contact_force<true>(p, g, {}, {25, 0, 0}, {-25, 0, 0}, h, 1e-5);
  // no sliding, so the torque on i is the rolling torque alone
  const Real cap = 0.2 * g.r_eff * f.f_n;
  EXPECT_NEAR(norm(f.torque_i(g)), cap, 1e-12 * cap);
  EXPECT_LT(f.torque_i(g).x, 0);  // opposes the spin
  EXPECT_NEAR(f.torque_j(g).x, -f.torque_i(g).x, 1e-15);
}

// Twisting: a dashpot on the relative spin about the normal, c_t R_eff^2, capped at
// mu_tw R_eff F_n; equal and opposite on the two grains. Without twisting friction the law has no
// torque about the normal at all (the rolling torque n x F_r lies across it).
TEST(ContactLaw, TwistingTorqueIsADashpotOnTheSpinAboutTheNormalCappedByFriction) {
  ContactParams p = params(0.5, 0.5, 0.2);
  p.mu_tw = 0.1;
  const ContactGeometry g = pair_geometry(1e-4);
  const Real c_t = p.c_t_ratio * g.c_n;
  for (const Real spin : {1e-3, -2e-3, 40.0, -40.0}) {
    ContactHistory h;
    const auto f = contact_force<true>(p, g, {}, {0, 0, spin}, {0, 0, -spin}, h, 1e-5);
    const Real cap = 0.1 * g.r_eff * f.f_n;
    const Real dashpot = c_t * g.r_eff * g.r_eff * 2 * spin;
    ASSERT_TRUE(std::abs(dashpot) < cap || std::abs(spin) > 1) << "a slow spin stays below the cap";
    EXPECT_NEAR(f.torque_i(g).z, -std::clamp(dashpot, -cap, cap), 1e-12 * cap) << spin;
    EXPECT_NEAR(f.torque_j(g).z, -f.torque_i(g).z, 1e-15) << spin;
    EXPECT_EQ(f.torque_i(g).x, 0.0);
    EXPECT_EQ(f.torque_i(g).y, 0.0);
  }
  p.mu_tw = 0;
  ContactHistory h;
  const auto f = contact_force<true>(p, g, {}, {0, 0, 40}, {0, 0, -40}, h, 1e-5);
  EXPECT_EQ(f.torque_i(g).z, 0.0);
  // twisting without rolling friction: rolling across the normal gives no torque and no history
  p.mu_r = 0;
  p.mu_tw = 0.1;
  const auto t = contact_force<true>(p, g, {}, {25, 0, 3}, {-25, 0, 0}, h, 1e-5);
  EXPECT_EQ(h.psi, Vec3{});
  EXPECT_EQ(t.t_roll.x, 0.0);
  EXPECT_EQ(t.t_roll.y, 0.0);
  EXPECT_LT(t.t_roll.z, 0.0);
}

// A grain resting on the floor and spinning about the vertical: rolling resistance does not
// touch that spin, so without twisting friction it spins for ever. With it, the capped torque
// mu_tw r m g slows it at 2.5 mu_tw g / r (I = 0.4 m r^2) until the dashpot takes over near 0.
TEST(ContactLaw, AGrainSpinningOnTheFloorStopsAsTwistingFrictionSays) {
  // (walls_only: the grains resist neither rolling nor twisting between themselves)
  auto spin_after = [](Real mu_tw, Real t, bool walls_only = false) {
    MaterialConfig mat;
    mat.k_n = 1e4;
    mat.restitution = 0.3;
    mat.rolling_friction = walls_only ? 0 : 0.3;
    mat.wall_rolling_friction = 0.3;
    mat.twisting_friction = walls_only ? 0 : mu_tw;
    mat.wall_twisting_friction = mu_tw;
    DemParams p;
    p.contact = contact_params(mat);
    p.walls_resist_turning = true;
    p.gravity = {0, 0, -9.81};
    const Real r = 0.005, m = mat.density * 4.0 / 3.0 * kPi * r * r * r;
    const Real dt = 0.02 * contact_time(m, mat.k_n);
    Grains g;
    g.add(0, {0, 0, r - m * 9.81 / mat.k_n}, {}, r, mat.density);  // at rest on its overlap
    g.w[0] = {0, 0, 50};
    const Geometry floor = Geometry::from_config({test::floor_plane()}, mat);
    DemSolver dem(p);
    Profile prof;
    for (int s = 0; s < static_cast<int>(std::lround(t / dt)); ++s) dem.step(g, floor, dt, prof);
    EXPECT_LT(std::abs(g.v[0].z), 1e-3);  // it stayed at rest on the floor
    return g.w[0].z;
  };
  EXPECT_NEAR(spin_after(0.0, 0.2), 50.0, 1e-9);
  const Real mu_tw = 0.1, slowing = 2.5 * mu_tw * 9.81 / 0.005;  // 490.5 rad/s^2
  // (within the 3.6e-3 rad/s one step of 7.3 us makes: t is rounded to whole steps)
  EXPECT_NEAR(spin_after(mu_tw, 0.05), 50 - slowing * 0.05, 0.01);
  EXPECT_LT(std::abs(spin_after(mu_tw, 0.15)), 1e-3);  // stopped after 50 / 490.5 = 0.102 s
  EXPECT_NEAR(spin_after(mu_tw, 0.05, true), 50 - slowing * 0.05, 0.01);
}

// The walls' rolling and twisting resistance act whatever the grains' own: the scene's walls
// make the sweep run the law's rolling part (it ran only for the grains' before).
TEST(ContactLaw, WallsResistTurningWhenOnlyTheyHaveRollingOrTwistingFriction) {
  for (const auto& [wall_mu_r, wall_mu_tw, resists] :
       {std::tuple{0.3, 0.0, true}, std::tuple{0.0, 0.1, true}, std::tuple{0.0, 0.0, false}}) {
    SceneConfig s = test::grains_on_floor("walls", Mode::Dem, 0.01);
    s.material.rolling_friction = 0;
    s.material.wall_rolling_friction = wall_mu_r;
    s.material.wall_twisting_friction = wall_mu_tw;
    s.emitters = {test::disk_pour({0, 0, 0.05}, 0.02, 50, 1, {0, 0, -1})};
    const World w(s);
    EXPECT_EQ(w.dem().resists_turning(), resists) << wall_mu_r << " " << wall_mu_tw;
  }
}

TEST(ContactLaw, HistoryRotatesIntoTheTangentPlaneKeepingItsLength) {
  const Vec3 xi{3, 0, 4};
  const Vec3 r = rotate_into_plane(xi, {0, 0, 1});
  EXPECT_NEAR(r.z, 0, 1e-15);
  EXPECT_NEAR(norm(r), 5, 1e-12);
}

TEST(ContactLaw, HistoryRotatedBySmallTurnsKeepsItsLengthTo1e12) {
  // the normal turns by 1e-6 to 1e-2 rad in a step: w = (a.n)^2 / |a|^2 from 1e-12 to 1e-4, both
  // sides of the series' switch at 1e-6; the length kept to 1e-12 relative, the result in the plane
  const Vec3 xi{2e-5, -1e-5, 0};
  for (Real turn : {1e-6, 1e-4, 9e-4, 1.1e-3, 1e-2}) {
    const Vec3 n{std::sin(turn), 0, std::cos(turn)};
    const Vec3 r = rotate_into_plane(xi, n);
    EXPECT_NEAR(norm(r) / norm(xi), 1, 1e-12) << turn;
    EXPECT_NEAR(dot(r, n) / norm(xi), 0, 1e-15) << turn;
  }
  // along the normal: nothing is left in the plane
  EXPECT_EQ(rotate_into_plane(Vec3{0, 0, 3e-5}, Vec3{0, 0, 1}), Vec3{});
  EXPECT_EQ(rotate_into_plane(Vec3{}, Vec3{0, 0, 1}), Vec3{});
}

TEST(ContactLaw, DampingBetaMatchesRestitution) {
  // unclamped: e = exp(-beta pi / sqrt(1 - beta^2)) for the damped linear oscillator
  for (Real e : {0.1, 0.5, 0.95}) {
    const Real b = damping_beta_unclamped(e);
    EXPECT_NEAR(std::exp(-b * kPi / std::sqrt(1 - b * b)), e, 1e-12);
  }
  // clamped: without damping nothing is lost; the clamp makes grains leave faster than the
  // unclamped formula, so the calibrated beta is larger
  EXPECT_NEAR(clamped_restitution(0.0), 1.0, 1e-6);
  for (Real e : {0.1, 0.3, 0.5, 0.9}) {
    EXPECT_NEAR(clamped_restitution(damping_beta(e)), e, 1e-6);
    EXPECT_GT(damping_beta(e), damping_beta_unclamped(e));
  }
}

TEST(TimeStep, SceneDtAboveTheStableBoundIsRefusedWithTheBound) {
  SceneConfig s;
  s.path = "x.toml";
  s.simulation.dt = 1.0;
  try {
    choose_time_step(s);
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("stable bound"), std::string::npos) << e.what();
  }
  s.simulation.dt.reset();
  const TimeStep ts = choose_time_step(s);
  EXPECT_LE(ts.dt, ts.t_c / 20 * (1 + 1e-12));
  EXPECT_NEAR(ts.dt * ts.substeps, 1.0 / s.output.fps, 1e-12);
}

TEST(TimeStep, AFrameOfMoreStepsThanTheLimitIsRefusedBeforeCountingThemInAnInt) {
  // 10^-15 s steps: 3.3e13 a frame, beyond an int (the cast would be undefined) and any run
  SceneConfig s;
  s.path = "x.toml";
  s.simulation.dt = 1e-15;
  try {
    choose_time_step(s);
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("more than the limit of 100000000"), std::string::npos)
        << e.what();
  }
  s.simulation.dt = 1e-9;  // 3.3e7 steps a frame: allowed
  EXPECT_EQ(choose_time_step(s).substeps, 33'333'334);
}

}  // namespace
}  // namespace sandflow
