// The sweep's look at the domain (DemSolver::all_inside), which spares World's per-step guard a
// pass over every grain: it must see every ACTIVE grain that leaves, or whose state is no longer
// finite, and ignore the frozen ones as the guard does.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "core/rng.hpp"
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

TEST(DemDomain, AGrainThatCrossesTheWallWithinItsNearMarginIsSeen) {
  // 1.5 um inside the wall at 1 mm/s: out after two steps of 1 ms, 2 um moved, well within its
  // near margin (the way it goes in 32 steps, 32 um): the sweep's one test per grain must still
  // know the wall is nearer than that
  DemSolver dem(without_gravity());
  dem.set_domain({-1, -1, -1}, {1, 1, 1});
  Grains g = two_grains({1 - 1.5e-6, 0, 0}, 1e-3);
  Profile prof;
  dem.step(g, Geometry{}, kDt, prof);
  ASSERT_LT(g.x[1].x, 1.0);
  EXPECT_TRUE(dem.all_inside());
  dem.step(g, Geometry{}, kDt, prof);
  ASSERT_GT(g.x[1].x, 1.0);
  EXPECT_FALSE(dem.all_inside());
}

// The ball the sweep watches (watch_radius2): every point in it, as the sweep computes its
// distances, is within the grain's near margin, within its allowance of where it stood at the
// rebuild, and inside the domain; and the ball is not needlessly small.
TEST(DemWatch, EveryPointOfTheWatchedBallIsInsideTheThreeLimits) {
  Rng rng(7);
  int watched = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    const Real scale = trial % 2 ? 1.0 : 1e3;  // (coordinates of a metre and of a kilometre)
    const Vec3 x{rng.uniform(-scale, scale), rng.uniform(-scale, scale),
                 rng.uniform(-scale, scale)};
    const Real margin = rng.uniform(1e-6, 1e-3), allow = margin * rng.uniform(1.0, 3.0);
    const Vec3 dir = Vec3{rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)};
    const Vec3 x_at_build = x + dir * (allow * rng.uniform(0.0, 1.2) / std::max(norm(dir), 1e-9));
    // walls at a few margins, some nearer than the margin, one side open
    const Vec3 lo = x - Vec3{margin * rng.uniform(0.0, 3.0), margin * rng.uniform(0.0, 3.0),
                             std::numeric_limits<Real>::infinity()};
    const Vec3 hi = x + Vec3{margin * rng.uniform(0.0, 3.0), margin * rng.uniform(0.0, 3.0),
                             margin * rng.uniform(0.0, 3.0)};
    const Real w2 = watch_radius2(x, margin, allow, x_at_build, lo, hi);
    if (norm(x - x_at_build) > allow) {
      EXPECT_EQ(w2, -1) << "outside its allowance already";
    }
    if (w2 <= 0) continue;
    ++watched;
    for (int k = 0; k < 20; ++k) {  // points on the ball's surface and just inside
      Vec3 u{rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)};
      if (k < 6) {  // (along the axes, toward each wall)
        u = Vec3{k % 3 == 0 ? 1.0 : 0.0, k % 3 == 1 ? 1.0 : 0.0, k % 3 == 2 ? 1.0 : 0.0} *
            (k < 3 ? 1.0 : -1.0);
      }
      const Vec3 y = x + u * (std::sqrt(w2) * (k % 2 ? 1.0 : 1 - 1e-12) / norm(u));
      if (!(norm2(y - x) <= w2)) continue;  // (the sweep would look closer: nothing to check)
      ASSERT_LE(norm2(y - x), margin * margin) << "trial " << trial;
      ASSERT_LE(norm2(y - x_at_build), allow * allow) << "trial " << trial;
      ASSERT_TRUE(y.x >= lo.x && y.x <= hi.x && y.y >= lo.y && y.y <= hi.y && y.z >= lo.z &&
                  y.z <= hi.z)
          << "trial " << trial;
    }
  }
  EXPECT_GT(watched, 2000);
  // a grain where it stood at the rebuild, far from the walls: the ball is its margin
  const Real far = std::numeric_limits<Real>::infinity();
  const Real w2 = watch_radius2({0.3, 0.2, 0.1}, 1e-4, 2e-4, {0.3, 0.2, 0.1}, {-far, -far, -far},
                                {far, far, far});
  EXPECT_GT(w2, 0.9999 * 1e-8);
  EXPECT_LE(w2, 1e-8);
}

}  // namespace
}  // namespace sandflow
