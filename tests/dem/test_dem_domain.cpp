// The sweep's look at the domain (DemSolver::all_inside), which spares World's per-step guard a
// pass over every grain: it must see every ACTIVE grain that leaves, or whose state is no longer
// finite, and ignore the frozen ones as the guard does.
#include <gtest/gtest.h>

#include <limits>

#include "dem/dem_solver.hpp"

namespace sandflow {
namespace {

constexpr Real kR = 0.005, kDt = 1e-3;

DemParams without_gravity() {
  DemParams p;
  p.contact.k_n = 1e3;
  p.gravity = {0, 0, 0};
  return p;
}

/// Two ACTIVE grains far apart in the box [-1, 1]^3, one moving along x at `speed`.
Grains two_grains(const Vec3& x_moving, Real speed) {
  Grains g;
  g.add(0, {0, 0, 0}, {}, kR, 2600);
  g.add(1, x_moving, {speed, 0, 0}, kR, 2600);
  return g;
}

TEST(DemDomain, TheSweepSaysWhetherEveryActiveGrainStayedInside) {
  DemSolver dem(without_gravity());
  dem.set_domain({-1, -1, -1}, {1, 1, 1});
  EXPECT_FALSE(dem.all_inside()) << "no sweep has looked yet";
  Grains g = two_grains({0.5, 0, 0}, 1.0);
  Profile prof;
  dem.step(g, Geometry{}, kDt, prof);
  EXPECT_TRUE(dem.all_inside());
  // 0.5 mm from the wall at 1 m/s: one step of 1 ms takes it 0.5 mm out
  g.x[1] = {1 - 0.0005, 0, 0};
  dem.step(g, Geometry{}, kDt, prof);
  ASSERT_GT(g.x[1].x, 1.0);
  EXPECT_FALSE(dem.all_inside());
  // back inside: the next sweep says so
  g.x[1] = {0.5, 0, 0};
  dem.step(g, Geometry{}, kDt, prof);
  EXPECT_TRUE(dem.all_inside());
}

TEST(DemDomain, ANonFiniteVelocityIsSeenThroughThePosition) {
  DemSolver dem(without_gravity());
  dem.set_domain({-1, -1, -1}, {1, 1, 1});
  for (const Real bad :
       {std::numeric_limits<Real>::quiet_NaN(), std::numeric_limits<Real>::infinity()}) {
    Grains g = two_grains({0.5, 0, 0}, bad);
    Profile prof;
    dem.step(g, Geometry{}, kDt, prof);
    EXPECT_FALSE(dem.all_inside()) << "velocity " << bad;
  }
}

TEST(DemDomain, FrozenGrainsOutsideAreNotTheSweepsConcern) {
  // (the guard skips them too: they do not move, and a frozen grain is where its pile put it)
  DemSolver dem(without_gravity());
  dem.set_domain({-1, -1, -1}, {1, 1, 1});
  Grains g = two_grains({1.5, 0, 0}, 0.0);
  g.state[1] = GrainState::Interface;
  Profile prof;
  dem.step(g, Geometry{}, kDt, prof);
  EXPECT_TRUE(dem.all_inside());
}

TEST(DemDomain, ARestoredSolverHasNotLooked) {
  DemSolver dem(without_gravity());
  dem.set_domain({-1, -1, -1}, {1, 1, 1});
  Grains g = two_grains({0.5, 0, 0}, 1.0);
  Profile prof;
  dem.step(g, Geometry{}, kDt, prof);
  ASSERT_TRUE(dem.all_inside());
  // (into a solver that has looked at other grains: a fresh one has not looked either way)
  DemSolver restored(without_gravity());
  restored.set_domain({-1, -1, -1}, {1, 1, 1});
  Grains other = two_grains({-0.5, 0, 0}, 1.0);
  restored.step(other, Geometry{}, kDt, prof);
  ASSERT_TRUE(restored.all_inside());
  restored.restore_state(dem.save_state(), Geometry{});
  EXPECT_FALSE(restored.all_inside());
  restored.step(g, Geometry{}, kDt, prof);
  EXPECT_TRUE(restored.all_inside());
}

}  // namespace
}  // namespace sandflow
