// The BCRE exchange of the height field on analytic slopes (docs/design.md §4), and the measurement of
// H from grains.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include <omp.h>

#include "surface/column_set.hpp"
#include "surface/height_field.hpp"

namespace sandflow {
namespace {

constexpr Real kCell = 0.01;

HeightFieldParams ramp_params(Real rolling_min = 0.0) {
  HeightFieldParams p;
  p.x0 = 0;
  p.y0 = 0;
  p.cell = kCell;
  p.nx = 20;
  p.ny = 3;
  p.gamma = 30;
  p.theta0 = deg_to_rad(32);
  p.theta_max = deg_to_rad(38);
  p.rolling_min = rolling_min;
  p.avalanche_depth = kCell;
  return p;
}

// A plane rising along x at `angle` for h, with a rolling layer of thickness R on top, over a
// terrain at `terrain_z`.
HeightField ramp(Real angle_deg, Real R, Real rolling_min = 0.0, Real base = 0.05,
                 Real terrain_z = 0.0) {
  const HeightFieldParams p = ramp_params(rolling_min);
  HeightField hf(p, std::vector<Real>(static_cast<std::size_t>(p.nx) * p.ny, terrain_z));
  std::vector<Real> h(hf.columns()), H(hf.columns());
  const Real t = std::tan(deg_to_rad(angle_deg));
  for (std::size_t c = 0; c < hf.columns(); ++c) {
    h[c] = terrain_z + base + t * hf.centre(c).x;
    H[c] = h[c] + R;
  }
  hf.set_surface(H);
  hf.set_static_top(h);
  return hf;
}

// The interior columns: the lowest and highest x columns have a one-sided slope.
template <class F>
void for_interior(const HeightField& hf, F&& f) {
  for (int j = 0; j < hf.ny(); ++j)
    for (int i = 1; i + 1 < hf.nx(); ++i) f(static_cast<std::size_t>(j) * hf.nx() + i);
}

TEST(Exchange, SlopeAboveReposeErodesTheStaticLayer) {
  HeightField hf = ramp(35, 0.01);
  const std::vector<Real> before = hf.static_top();
  hf.exchange(0.003);
  for_interior(hf, [&](std::size_t c) {
    EXPECT_LT(hf.static_top()[c], before[c]) << c;
    EXPECT_GT(hf.exchange_rate()[c], 0) << c;               // Gamma > 0: erosion
    EXPECT_NEAR(hf.slope()[c], deg_to_rad(35), 1e-9) << c;  // the upwind slope of a plane
  });
}

TEST(Exchange, SlopeBelowReposeDeposits) {
  HeightField hf = ramp(25, 0.01);
  const std::vector<Real> before = hf.static_top();
  hf.exchange(0.003);
  for_interior(hf, [&](std::size_t c) {
    EXPECT_GT(hf.static_top()[c], before[c]) << c;
    EXPECT_LT(hf.exchange_rate()[c], 0) << c;
  });
}

TEST(Exchange, AtTheReposeAngleNothingMoves) {
  HeightField hf = ramp(32, 0.01);
  const std::vector<Real> before = hf.static_top();
  hf.exchange(0.003);
  // Gamma = gamma R (theta - theta0) = 0 up to the rounding of tan/atan
  for_interior(hf, [&](std::size_t c) { EXPECT_NEAR(hf.static_top()[c], before[c], 1e-12) << c; });
}

TEST(Exchange, LayerAtRestDepositsUpToThetaMaxAndAFlowingOneErodesToTheta0) {
  // 35 degrees: between theta0 (32) and theta_max (38)
  HeightField resting = ramp(35, 0.01), flowing = ramp(35, 0.01);
  const std::vector<Real> before = resting.static_top();
  resting.exchange(0.003, std::vector<std::uint8_t>(resting.columns(), 0));
  flowing.exchange(0.003, std::vector<std::uint8_t>(flowing.columns(), 1));
  for_interior(resting, [&](std::size_t c) {
    EXPECT_GT(resting.static_top()[c], before[c]) << c;  // grains at rest on it join it
    EXPECT_LT(flowing.static_top()[c], before[c]) << c;  // a flow erodes it
  });
  // above theta_max even a layer at rest erodes
  HeightField steep = ramp(42, 0.01);
  const std::vector<Real> s0 = steep.static_top();
  steep.exchange(0.003, std::vector<std::uint8_t>(steep.columns(), 0));
  for_interior(steep, [&](std::size_t c) { EXPECT_LT(steep.static_top()[c], s0[c]) << c; });
}

// Grains flowing over grains at rest do not dig the static top beneath those (erosion_reach): a
// flowing column that no moving grain reaches keeps its static top above theta0, still deposits
// below it, and still fails above theta_max; one a moving grain reaches erodes.
TEST(Exchange, AFlowThatDoesNotReachTheStaticTopDoesNotErodeIt) {
  for (const Real angle : {35.0, 25.0, 42.0}) {
    HeightField shielded = ramp(angle, 0.03), reached = ramp(angle, 0.03);
    const std::vector<Real> before = shielded.static_top();
    ColumnSet all(shielded.columns()), none(shielded.columns());
    all.add_all();
    shielded.exchange(0.003, all, &none);
    reached.exchange(0.003, all, &all);
    for_interior(shielded, [&](std::size_t c) {
      if (angle == 35.0) {
        EXPECT_EQ(shielded.static_top()[c], before[c]) << c;  // no erosion
        EXPECT_LT(reached.static_top()[c], before[c]) << c;   // the flow that reaches it digs
      } else if (angle == 25.0) {
        EXPECT_GT(shielded.static_top()[c], before[c]) << c;  // a deposit all the same
        EXPECT_EQ(shielded.static_top()[c], reached.static_top()[c]) << c;
      } else {
        EXPECT_LT(shielded.static_top()[c], before[c]) << c;  // an avalanche all the same
      }
    });
  }
}

TEST(Exchange, DepositionNeverTakesMoreThanTheRollingLayer) {
  // flat and thin: the exchange rate times a long step would bury ten times R
  HeightField hf = ramp(0, 0.002);
  const std::vector<Real> h0 = hf.static_top();
  const std::vector<Real> R0 = hf.rolling();
  hf.exchange(10.0);
  for (std::size_t c = 0; c < hf.columns(); ++c) {
    EXPECT_LE(hf.static_top()[c] - h0[c], R0[c] * (1 + 1e-12)) << c;
    EXPECT_GE(hf.rolling()[c], 0) << c;
  }
}

TEST(Exchange, ErosionNeverDigsBelowTheTerrain) {
  // a steep thin static layer on a raised terrain, eroded for many long steps
  HeightField hf = ramp(60, 0.02, 0.0, 0.0005, 0.3);
  for (int k = 0; k < 200; ++k) {
    hf.exchange(0.05);
    for (std::size_t c = 0; c < hf.columns(); ++c)
      ASSERT_GE(hf.static_top()[c], hf.terrain()[c]) << "update " << k << " column " << c;
  }
}

TEST(Exchange, RollingLayerNeverThinnerThanRmin) {
  const Real r_min = 0.01;
  for (Real angle : {0.0, 20.0, 32.0, 40.0}) {
    HeightField hf = ramp(angle, 0.004, r_min);  // starts thinner than R_min
    for (int k = 0; k < 50; ++k) {
      hf.exchange(0.003);
      for (std::size_t c = 0; c < hf.columns(); ++c)
        if (hf.surface()[c] - hf.terrain()[c] >= r_min) {
          ASSERT_GE(hf.rolling()[c], r_min - 1e-12) << angle << " deg, column " << c;
        }
    }
  }
}

TEST(Exchange, AFlowingLayerKeepsFlowingMinAndOneAtRestOnlyRmin) {
  // a thick rolling layer on a gentle slope deposits; where it flows the static top stays
  // flowing_min below the surface, where it rests it may rise to R_min below it
  const Real r_min = 0.01, flowing_min = 0.04;
  for (std::uint8_t flows : {0, 1}) {
    HeightField hf = ramp(10, 0.08, r_min);
    HeightFieldParams p = hf.params();
    p.flowing_min = flowing_min;
    HeightField field(p, hf.terrain());
    field.set_surface(hf.surface());
    field.set_static_top(hf.static_top());
    for (int k = 0; k < 200; ++k)
      field.exchange(0.003, std::vector<std::uint8_t>(field.columns(), flows));
    const Real floor = flows ? flowing_min : r_min;
    for_interior(field, [&](std::size_t c) {
      EXPECT_GE(field.rolling()[c], floor - 1e-12) << "flows " << int(flows) << ", column " << c;
      EXPECT_LE(field.rolling()[c], floor + 1e-9) << "flows " << int(flows) << ", column " << c;
    });
  }
}

TEST(Exchange, AStoppedFlowKeepsFlowingMinForFlowingHoldThenOnlyRmin) {
  // a layer that stops flowing keeps flowing_min while DEM brings it to rest, for flowing_hold
  // (counted from its last flowing update), then deposits down to R_min
  const Real r_min = 0.01, flowing_min = 0.04, hold = 0.3, dt = 0.003;
  HeightField hf = ramp(10, 0.08, r_min);
  HeightFieldParams p = hf.params();
  p.flowing_min = flowing_min;
  p.flowing_hold = hold;
  HeightField field(p, hf.terrain());
  field.set_surface(hf.surface());
  field.set_static_top(hf.static_top());
  for (int k = 0; k < 100; ++k) field.exchange(dt, std::vector<std::uint8_t>(field.columns(), 1));
  const std::vector<std::uint8_t> at_rest(field.columns(), 0);
  Real t = 0;
  for (; t < hold - 2 * dt; t += dt) {
    field.exchange(dt, at_rest);
    for_interior(field, [&](std::size_t c) {
      ASSERT_GE(field.rolling()[c], flowing_min - 1e-12) << "at " << t << " s, column " << c;
    });
  }
  for (int k = 0; k < 200; ++k) field.exchange(dt, at_rest);
  for_interior(
      field, [&](std::size_t c) { EXPECT_LE(field.rolling()[c], r_min + 1e-9) << "column " << c; });
}

TEST(Exchange, FlowingHoldNeverOutlastsCloseAfter) {
  // a column closed after close_after freezes whole, however long flowing_hold is
  HeightField hf = ramp(10, 0.08, 0.01);
  HeightFieldParams p = hf.params();
  p.flowing_min = 0.04;
  p.flowing_hold = 10;
  p.close_after = 0.1;
  HeightField field(p, hf.terrain());
  field.set_surface(hf.surface());
  field.set_static_top(hf.static_top());
  for (int k = 0; k < 400; ++k)
    field.exchange(0.003, std::vector<std::uint8_t>(field.columns(), 0));
  for_interior(field, [&](std::size_t c) {
    EXPECT_TRUE(field.closed(c)) << c;
    EXPECT_LE(field.rolling()[c], 0.01 + 1e-9) << c;
  });
}

TEST(Exchange, FlowingMinBelowRminChangesNothing) {
  // flowing_min never thins the layer below R_min
  HeightField hf = ramp(10, 0.08, 0.01);
  HeightFieldParams p = hf.params();
  p.flowing_min = 0.002;
  HeightField field(p, hf.terrain());
  field.set_surface(hf.surface());
  field.set_static_top(hf.static_top());
  for (int k = 0; k < 200; ++k) {
    hf.exchange(0.003, std::vector<std::uint8_t>(hf.columns(), 1));
    field.exchange(0.003, std::vector<std::uint8_t>(field.columns(), 1));
  }
  for (std::size_t c = 0; c < hf.columns(); ++c)
    EXPECT_EQ(field.static_top()[c], hf.static_top()[c]) << c;
}

TEST(Exchange, AvalancheStartsOnlyAboveThetaMax) {
  // no rolling layer: BCRE alone would hold any slope; theta_max makes the steep one fail
  HeightField steep = ramp(45, 0.0);
  HeightField held = ramp(35, 0.0);  // between theta0 and theta_max: a static slope can stand
  const std::vector<Real> s0 = steep.static_top(), h0 = held.static_top();
  steep.exchange(0.003);
  held.exchange(0.003);
  for_interior(steep, [&](std::size_t c) {
    EXPECT_LT(steep.static_top()[c], s0[c]) << c;
    EXPECT_DOUBLE_EQ(held.static_top()[c], h0[c]) << c;
  });
}

// A 30 x 30 field on a flat terrain at 0, sand 2 mm deep, with a 10 x 10 block of static sand
// 20 cm high in the middle; the sand surface H is `beside` outside the block and the block's top
// inside it.
HeightField block(Real beside) {
  HeightFieldParams p = ramp_params();
  p.nx = p.ny = 30;
  HeightField hf(p, std::vector<Real>(static_cast<std::size_t>(p.nx) * p.ny, 0.0));
  std::vector<Real> h(hf.columns(), 0.002), H(hf.columns(), beside);
  for (int j = 10; j < 20; ++j)
    for (int i = 10; i < 20; ++i)
      h[static_cast<std::size_t>(j) * p.nx + i] = H[static_cast<std::size_t>(j) * p.nx + i] = 0.2;
  hf.set_surface(H);
  hf.set_static_top(h);
  return hf;
}

// Checks that no column of hf's static top stands steeper than theta_max (upwind, as the
// exchange measures slopes) and none below the terrain; returns the highest top.
Real highest_within_theta_max(const HeightField& hf) {
  const std::vector<Real>& top = hf.static_top();
  const HeightFieldParams& p = hf.params();
  const Real s = kCell * std::tan(p.theta_max);
  auto at = [&](int i, int j) {
    return i < 0 || j < 0 || i >= p.nx || j >= p.ny ? std::numeric_limits<Real>::infinity()
                                                    : top[static_cast<std::size_t>(j) * p.nx + i];
  };
  Real highest = 0;
  for (int j = 0; j < p.ny; ++j)
    for (int i = 0; i < p.nx; ++i) {
      const Real z = at(i, j);
      const Real gx = std::max(0.0, z - std::min(at(i - 1, j), at(i + 1, j)));
      const Real gy = std::max(0.0, z - std::min(at(i, j - 1), at(i, j + 1)));
      EXPECT_LE(std::hypot(gx, gy), s * (1 + 1e-6)) << i << " " << j;
      EXPECT_GE(z, 0.0);
      highest = std::max(highest, z);
    }
  return highest;
}

TEST(Exchange, AFreeFaceAboveThetaMaxFailsWithTheWedgeBehindIt) {
  // the block stands free, as a tube's sand does when the tube is lifted away: one update leaves
  // no column steeper than theta_max, a cone of theta_max slopes where the block stood, and the
  // sand around it untouched. The avalanche's rate alone lowers the wall by about a millimetre
  // an update.
  HeightField hf = block(0.002);
  hf.exchange(0.003);
  const Real s = kCell * std::tan(hf.params().theta_max);
  const Real highest = highest_within_theta_max(hf);
  // the centre stands five steps of theta_max above the sand around the block, not lower
  EXPECT_GT(highest, 0.002 + 4.5 * s);
  EXPECT_LT(highest, 0.002 + 5.5 * s * std::sqrt(2.0));
  EXPECT_DOUBLE_EQ(hf.static_top()[2 * 30 + 2], 0.002);
}

TEST(Exchange, FreeFacesFailAlikeOnOneThreadAndOnTwo) {
  // 3,600 columns, so the search for free faces runs on the threads (from 1,024 seeds), and two
  // blocks apart, one in each thread's share of the columns: each fails to its cone, bit for bit
  // the same whatever the thread count.
  std::vector<std::vector<Real>> tops;
  for (const int threads : {1, 2}) {
    omp_set_num_threads(threads);
    HeightFieldParams p = ramp_params();
    p.nx = p.ny = 60;
    HeightField hf(p, std::vector<Real>(static_cast<std::size_t>(p.nx) * p.ny, 0.0));
    std::vector<Real> h(hf.columns(), 0.002), H = h;
    for (const int j0 : {5, 40})
      for (int j = j0; j < j0 + 15; ++j)
        for (int i = 20; i < 35; ++i)
          h[static_cast<std::size_t>(j) * p.nx + i] = H[static_cast<std::size_t>(j) * p.nx + i] =
              0.2;
    hf.set_surface(H);
    hf.set_static_top(h);
    hf.exchange(0.003);
    const Real s = kCell * std::tan(p.theta_max);
    EXPECT_LT(highest_within_theta_max(hf), 0.002 + 8 * s * std::sqrt(2.0));
    tops.push_back(hf.static_top());
  }
  omp_set_num_threads(omp_get_num_procs());
  EXPECT_EQ(tops[0], tops[1]);
}

TEST(Exchange, StaticSandButtressedByMovingSandDoesNotFail) {
  // the same block with sand as high around it (H), moving (not static): an impact's pit in the
  // static layer, not a free face. Only the avalanche's rate erodes its edge.
  HeightField hf = block(0.2);
  hf.exchange(0.003);
  const HeightFieldParams& p = hf.params();
  for (int j = 10; j < 20; ++j)
    for (int i = 10; i < 20; ++i)
      EXPECT_GT(hf.static_top()[static_cast<std::size_t>(j) * p.nx + i], 0.19) << i << " " << j;
}

// Six columns in a row on a floor, sand at rest 5 cm deep in the first three (static, H = h), the
// others empty; a wall of height `wall` on the edge between columns 2 and 3 (none: no wall).
HeightField walled_bed(Real wall) {
  HeightFieldParams p = ramp_params();
  p.nx = 6;
  p.ny = 1;
  TerrainColumns t;
  for (int c = 0; c < p.nx; ++c) {
    std::vector<TerrainColumns::Wall> walls;
    if (c == 2 && std::isfinite(wall))
      walls.push_back({0, -std::numeric_limits<Real>::infinity(), wall});
    t.add_column({{-std::numeric_limits<Real>::infinity(), 0.0}}, walls);
  }
  HeightField hf(p, std::move(t));
  const std::vector<Real> sand{0.05, 0.05, 0.05, 0, 0, 0};
  hf.set_surface(sand);
  hf.set_static_top(sand);
  return hf;
}

TEST(Exchange, AWallBetweenColumnsHoldsTheStaticLayerBehindIt) {
  constexpr Real kNone = -std::numeric_limits<Real>::infinity();
  // no wall: the bed's edge is a free face; it fails and erodes towards the empty columns
  HeightField open = walled_bed(kNone);
  // a wall higher than the sand: nothing erodes, whatever the time
  HeightField held = walled_bed(0.06);
  // a wall lower than the sand: the sand above it may go, what the wall holds stays
  HeightField low = walled_bed(0.03);
  for (int k = 0; k < 100; ++k)
    for (HeightField* hf : {&open, &held, &low}) hf->exchange(0.003);
  EXPECT_LT(open.static_top()[2], 0.04);
  for (int c = 0; c < 3; ++c) EXPECT_EQ(held.static_top()[c], 0.05) << c;
  EXPECT_LT(low.static_top()[2], 0.05);
  EXPECT_GE(low.static_top()[2], 0.03);
  // a grain beside the wall on the empty side finds no static sand under it (interpolation would
  // carry the bed's over the wall)
  EXPECT_EQ(held.static_top_at(3.2 * kCell, 0.5 * kCell), 0.0);
  EXPECT_GT(walled_bed(kNone).static_top_at(3.2 * kCell, 0.5 * kCell), 0.01);
  EXPECT_EQ(held.wall_top(2, 3), 0.06);
  EXPECT_EQ(held.wall_top(3, 2), 0.06);
  EXPECT_EQ(held.wall_top(1, 2), kNone);
}

TEST(Exchange, StableForLongUpdateSteps) {
  // the exact integration with the no-overshoot cap: however long the step, h stays between L
  // and H and no checkerboard grows (an unstable update makes the total variation of h along
  // the ramp blow up; a stable one keeps it within that of the sand surface H)
  for (Real dt : {0.001, 0.01, 0.1, 1.0}) {
    HeightField hf = ramp(40, 0.05);
    auto variation = [&](const std::vector<Real>& f) {
      Real tv = 0;
      for (int j = 0; j < hf.ny(); ++j)
        for (int i = 0; i + 1 < hf.nx(); ++i)
          tv += std::abs(f[static_cast<std::size_t>(j) * hf.nx() + i + 1] -
                         f[static_cast<std::size_t>(j) * hf.nx() + i]);
      return tv;
    };
    const Real tv_surface = variation(hf.surface());
    for (int k = 0; k < 100; ++k) {
      hf.exchange(dt);
      for (std::size_t c = 0; c < hf.columns(); ++c) {
        ASSERT_TRUE(std::isfinite(hf.static_top()[c]));
        ASSERT_GE(hf.static_top()[c], hf.terrain()[c]);
        ASSERT_LE(hf.static_top()[c], hf.surface()[c]);
      }
    }
    // h may overshoot a neighbour while a long step deposits at the foot, but never keeps a
    // checkerboard: after 100 updates it is as smooth as the sand surface
    EXPECT_LE(variation(hf.static_top()), tv_surface * (1 + 1e-9)) << "dt " << dt;
    // and, given a second or more, it settles: the interior ends at theta0 or below (deposition
    // fills from the foot)
    if (dt >= 0.01)
      for_interior(hf,
                   [&](std::size_t c) { EXPECT_LE(hf.slope()[c], deg_to_rad(32) + 0.02) << dt; });
  }
}

TEST(Measure, GrainsInFlightDoNotLiftTheSurface) {
  HeightFieldParams p = ramp_params();
  p.nx = p.ny = 5;
  p.gap = 0.0025;
  HeightField hf(p, std::vector<Real>(25, 0.0));
  const std::size_t c = 2 * 5 + 2;  // the middle column, centre (0.025, 0.025)
  Grains g;
  g.add(0, {0.025, 0.025, 0.005}, {}, 0.005, 2600);   // on the floor
  g.add(1, {0.025, 0.025, 0.0145}, {}, 0.005, 2600);  // stacked on it
  g.add(2, {0.025, 0.025, 0.1}, {}, 0.005, 2600);     // falling, far above
  g.add(3, {0.005, 0.005, 0.05}, {}, 0.005, 2600);    // falling over an empty corner
  hf.measure(g, hf.terrain());
  EXPECT_NEAR(hf.surface()[c], 0.0195, 1e-12);  // the stack's top, not the falling grain's
  EXPECT_DOUBLE_EQ(hf.surface()[0], 0.0);       // nothing under the lone grain: the terrain
  // a grain that does not count (no contact) is not part of the pile
  hf.measure(g, hf.terrain(), {1, 0, 1, 1});
  EXPECT_NEAR(hf.surface()[c], 0.010, 1e-12);
}

TEST(Measure, GrainHeldUpBesideTheRayStillCounts) {
  // In a random packing a resting grain is often held up by neighbours outside a column's ray, a
  // few millimetres above the grain below it in the ray. A gap of d/4 cut H there and made pits
  // that pinned h (see docs/physics.md); only a gap of a whole diameter means flight, and only
  // for a grain that moves.
  HeightFieldParams p = ramp_params();
  p.nx = p.ny = 5;
  p.gap = 0.01;
  HeightField hf(p, std::vector<Real>(25, 0.0));
  const std::size_t c = 2 * 5 + 2;
  Grains g;
  g.add(0, {0.025, 0.025, 0.005}, {}, 0.005, 2600);  // on the floor
  g.add(1, {0.025, 0.025, 0.021}, {}, 0.005, 2600);  // 6 mm above it, held from the side
  hf.measure(g, hf.terrain());
  EXPECT_NEAR(hf.surface()[c], 0.026, 1e-12);
  g.x[1].z = 0.0265;  // 11.5 mm above: in flight
  hf.measure(g, hf.terrain());
  EXPECT_NEAR(hf.surface()[c], 0.010, 1e-12);
  // ... unless it is at rest on the pile (kHeldOnPile), held by grains beside the ray across a
  // void under it (as along a container's wall): the void is part of the pile
  g.x[1].z = 0.035;
  hf.measure(g, hf.terrain(), {HeightField::kHeldOnPile, 1});
  EXPECT_NEAR(hf.surface()[c], 0.010, 1e-12);
  hf.measure(g, hf.terrain(), {HeightField::kHeldOnPile, HeightField::kHeldOnPile});
  EXPECT_NEAR(hf.surface()[c], 0.040, 1e-12);
}

TEST(Measure, ThickRayFindsTheTopBetweenGrains) {
  // a ray at a column centre between grains still meets the grains within half a cell of it
  HeightFieldParams p = ramp_params();
  p.nx = p.ny = 3;
  HeightField hf(p, std::vector<Real>(9, 0.0));
  Grains g;
  g.add(0, {0.015 + 0.007, 0.015, 0.005}, {}, 0.005, 2600);  // 7 mm off the centre column's axis
  hf.measure(g, hf.terrain());
  // the ray's rim (5 mm) is 2 mm from the grain's centre: height sqrt(r^2 - 2mm^2) above it
  EXPECT_NEAR(hf.surface()[4], 0.005 + std::sqrt(0.005 * 0.005 - 0.002 * 0.002), 1e-12);
}

TEST(Measure, AGrainBehindAWallIsNotSandBeyondIt) {
  // a grain on the floor in column 2, 1 mm from the edge to column 3: column 3's thick ray reaches
  // it, but a wall on that edge higher than the grain's centre stands between
  Grains g;
  g.add(0, {2.9 * kCell, 0.5 * kCell, 0.005}, {}, 0.005, 2600);
  for (const Real wall : {-std::numeric_limits<Real>::infinity(), 0.003, 0.06}) {
    HeightField hf = walled_bed(wall);
    hf.set_static_top(std::vector<Real>(6, 0.0));
    hf.measure(g, hf.terrain());
    EXPECT_NEAR(hf.surface()[2], 0.01, 1e-12) << wall;
    if (wall > 0.005)
      EXPECT_EQ(hf.surface()[3], 0.0);  // behind the wall
    else
      EXPECT_GT(hf.surface()[3], 0.009) << wall;  // no wall, or one below the grain's centre
  }
}

}  // namespace
}  // namespace sandflow
