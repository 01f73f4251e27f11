// The invariant of the layers (docs/design.md §5): no STATIC grain lies within reach of an ACTIVE
// grain, so that no grain can creep into the static layer (which pushes nothing) nor have a static
// grain wake inside it; and the band of interface grains is measured normal to the slope.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "sim/world.hpp"
#include "surface/interface_layer.hpp"

namespace sandflow {
namespace {

constexpr Real kGrainD = 0.01;  // grain diameter [m]
constexpr Real kGrainR = kGrainD / 2;

// A static layer three grains deep under a plane through the origin sloping at `theta` along x
// (a square lattice in the plane's frame, a hair looser than touching), and one ACTIVE grain a
// tenth of a diameter above it creeping straight into it at 0.2 m/s (a grain rolling slowly over a
// heap). Gravity off, so that only the creep brings it in.
struct Creep {
  HeightField hf;
  InterfaceLayer layer{InterfaceParams{}};
  DemSolver dem;
  Grains hot;
  StaticStore st{static_frame(hf, -1.0, 1.0, 0.004, 0.006)};
  Vec3 n;  // the slope's normal
  Real dt = 1e-5;

  static HeightFieldParams grid() {
    HeightFieldParams p;
    p.cell = kGrainD;
    p.nx = p.ny = 16;
    p.x0 = p.y0 = -0.08;
    return p;
  }
  static DemParams dem_params() {
    DemParams p;
    MaterialConfig m;
    m.k_n = 1e4;
    p.contact = contact_params(m);
    p.skin = 0.2 * kGrainD;
    p.gravity = {};
    return p;
  }
  explicit Creep(Real theta)
      : hf(grid(), std::vector<Real>(256, -1.0)), dem(dem_params()) {
    n = {-std::sin(theta), 0, std::cos(theta)};
    const Vec3 e1{std::cos(theta), 0, std::sin(theta)}, e2{0, 1, 0};
    const Real a = 1.0001 * kGrainD;
    GrainId id = 0;
    for (int k = 0; k < 3; ++k)
      for (int v = -4; v <= 4; ++v)
        for (int u = -4; u <= 4; ++u) {
          const Vec3 x = e1 * (u * a) + e2 * (v * a) - n * ((k + 0.5) * a);
          st.add(id++, x, kGrainR, static_cast<std::uint32_t>(hf.column_of(x.x, x.y)));
        }
    hot.add(id, n * (kGrainR + 0.1 * kGrainD), n * -0.2, kGrainR, 2600);
  }
  // one step as World::step takes it: the invariant before each rebuild, then the DEM.
  // `deepest` gets the deepest overlap of an ACTIVE grain with a STATIC one where the forces are
  // computed: between the two.
  TransitionCounts step(bool hold_invariant, Real* deepest = nullptr) {
    TransitionCounts c;
    if (hold_invariant && dem.needs_rebuild()) {
      std::vector<Real> allow;
      dem.allowances(hot, dt, allow);
      const Transitions t = layer.wake_within_reach(hf, hot, st, allow);
      dem.apply(t.changes);
      c = t.counts;
    }
    if (deepest) *deepest = std::max(*deepest, deepest_into_static());
    Profile profile;
    dem.step(hot, Geometry{}, dt, profile);
    return c;
  }
  // the deepest overlap of an ACTIVE grain with a STATIC one, by brute force [m]
  Real deepest_into_static() const {
    Real worst = 0;
    for (std::size_t i = 0; i < hot.size(); ++i) {
      if (hot.state[i] != GrainState::Active) continue;
      st.for_each([&](const StaticGrain& g) {
        worst = std::max(worst, hot.r[i] + g.r - norm(hot.x[i] - g.x));
      });
    }
    return worst;
  }
};

void expect_creep_stopped_at_the_layer(Real theta) {
  Creep c(theta);
  std::int64_t woken = 0;
  for (int s = 0; s < 3000; ++s) {
    Real deepest = 0;
    woken += c.step(true, &deepest).woken_by_reach;
    ASSERT_LE(deepest, 0.0) << "step " << s << ": an ACTIVE grain met a STATIC one";
  }
  EXPECT_GT(woken, 0);
  // the grain met the woken (INTERFACE) grains and went back the way it came
  EXPECT_GT(dot(c.hot.v[0], c.n), 0.0);
  EXPECT_EQ(c.dem.counters().energy_inside, 0.0);  // none woke inside it
}

TEST(LayerInvariant, AGrainCannotCreepIntoTheStaticLayerOnTheFlat) {
  expect_creep_stopped_at_the_layer(0.0);
}

TEST(LayerInvariant, AGrainCannotCreepIntoTheStaticLayerOnASlopeAtThetaMax) {
  expect_creep_stopped_at_the_layer(deg_to_rad(39.0));
}

TEST(LayerInvariant, WithoutItTheGrainGoesIntoTheStaticLayer) {
  // the same creep without the invariant: the static grains push nothing, and the grain goes in
  Creep c(deg_to_rad(39.0));
  Real deepest = 0;
  for (int s = 0; s < 3000; ++s) c.step(false, &deepest);
  EXPECT_GT(deepest, 0.3 * kGrainD);
}

// Erosion after the creep: the static top falls below the whole layer and every static grain
// wakes. The energy that contacts opened inside an ACTIVE grain would add (DemCounters::
// energy_inside) is what a grain that crept in gets back when the grains around it wake.
Real energy_when_the_layer_wakes(bool hold_invariant) {
  Creep c(deg_to_rad(20.0));
  for (int s = 0; s < 1500; ++s) c.step(hold_invariant);
  const std::size_t nc = c.hf.columns();
  c.layer.restore_seen(std::vector<Real>(nc, 0.4), c.hf.terrain());  // h was 0.4 m
  c.hf.set_surface(std::vector<Real>(nc, 0.5));
  c.hf.set_static_top(std::vector<Real>(nc, -0.5));
  const std::size_t static_before = c.st.size();
  std::vector<std::uint8_t> contacts(c.hot.size(), DemSolver::kTouches | DemSolver::kNearActive);
  const Transitions t = c.layer.transfer(c.hf, c.hot, c.st, contacts);
  c.dem.apply(t.changes);
  EXPECT_EQ(t.counts.woken, static_cast<std::int64_t>(static_before));
  EXPECT_EQ(c.st.size(), 0u);
  c.step(hold_invariant);  // the rebuild that opens the woken grains' contacts
  return c.dem.counters().energy_inside;
}

TEST(LayerInvariant, NoGrainWakesInsideAnActiveOne) {
  EXPECT_EQ(energy_when_the_layer_wakes(true), 0.0);
  // (the counter sees it when it happens: without the invariant the grain crept in, and the
  // grains around it wake inside it)
  EXPECT_GT(energy_when_the_layer_wakes(false), 1e-4);
}

// The band is T thick normal to the slope: in the vertical, T / cos theta.
TEST(LayerInvariant, TheBandIsMeasuredNormalToTheSlope) {
  EXPECT_DOUBLE_EQ(vertical_band(0.01, 0.0), 0.01);
  EXPECT_NEAR(vertical_band(0.01, deg_to_rad(40.0)), 0.01 / std::cos(deg_to_rad(40.0)), 1e-15);
  EXPECT_NEAR(vertical_band(0.01, deg_to_rad(89.0)), 0.02, 1e-12);  // a wall: at most 2 T

  // an INTERFACE grain T + 0.15 T below h (and the margin): asleep on the flat, still in the
  // band on a 40-degree slope, where the band reaches 1.31 T down
  for (const Real theta_deg : {0.0, 40.0}) {
    HeightFieldParams p;
    p.cell = kGrainD;
    p.nx = p.ny = 10;
    HeightField hf(p, std::vector<Real>(100, -1.0));
    const Real slope = std::tan(deg_to_rad(theta_deg));
    std::vector<Real> h(100), H(100);
    for (std::size_t c = 0; c < 100; ++c) {
      h[c] = 0.2 + slope * hf.centre(c).x;
      H[c] = h[c] + kGrainD;
    }
    hf.set_surface(H);
    hf.set_static_top(h);
    hf.exchange(1e-12);  // (the slopes; a vanishing interval moves nothing)
    InterfaceParams ip;
    ip.thickness = kGrainD;
    ip.margin = 0.25 * kGrainD;
    InterfaceLayer layer(ip);
    Grains hot;
    StaticStore st(static_frame(hf, -1.0, 1.0, 0.004, 0.006));
    const Vec3 at{0.05, 0.05, 0};
    hot.add(0, {at.x, at.y, hf.static_top_at(at.x, at.y) - 1.15 * kGrainD - ip.margin}, {}, kGrainR,
            2600);
    hot.state[0] = GrainState::Interface;
    std::vector<std::uint8_t> contacts(1, DemSolver::kTouches);
    const TransitionCounts n = layer.transfer(hf, hot, st, contacts).counts;
    EXPECT_EQ(n.slept, theta_deg == 0.0 ? 1 : 0) << theta_deg << " degrees";
  }
}

}  // namespace
}  // namespace sandflow
