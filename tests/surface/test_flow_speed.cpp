// Which grains move the rolling layer (surface.flow_speed): a grain rolling slowly over the bed
// leaves the static top where it is; a fast one (an impact) holds it a diameter below its bottom.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "core/error.hpp"
#include "scene/world.hpp"
#include "support/test_scenes.hpp"
#include "surface/surface_flow.hpp"
#include "surface/surface_params.hpp"

namespace sandflow {
namespace {

constexpr Real kD = 0.01;  // grain diameter [m]

SceneConfig bed_scene() {
  SceneConfig s = test::grains_on_floor("flow_speed", Mode::Surface, kD);
  s.material.diameter_spread = 0;
  s.surface.extent = std::array<Real, 4>{-0.05, -0.05, 0.05, 0.05};
  return s;
}

TEST(FlowSpeed, DefaultIsSixTenthsOfSqrtGdAndItMayNotBeBelowTheTrapSpeed) {
  SceneConfig s = bed_scene();
  const Geometry g = Geometry::from_config(s.geometry, s.material);
  const SurfaceParams p = surface_params(s, g, 1e-4);
  EXPECT_NEAR(p.flow_speed, 0.6 * std::sqrt(9.81 * kD), 1e-12);
  EXPECT_LT(p.interface.trap_speed, p.flow_speed);

  s.surface.trap_speed = 0.2;
  s.surface.flow_speed = 0.1;
  try {
    surface_params(s, g, 1e-4);
    FAIL() << "flow_speed below trap_speed was accepted";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("surface.flow_speed = 0.1 m/s is less than surface.trap_speed = 0.2 m/s"),
              std::string::npos)
        << what;
  }
  s.surface.flow_speed.reset();
  s.surface.trap_speed = 0.25;  // above the default flow speed: the message says it is the default
  try {
    surface_params(s, g, 1e-4);
    FAIL() << "a trap speed above the default flow speed was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("flow_speed unset"), std::string::npos) << e.what();
  }
}

// A bed three grains deep (two static layers under a frozen interface layer, square packing)
// and one ACTIVE grain resting in a pocket on top of it, moving sideways at `speed`. The static
// top starts at the top grain's bottom, as a settled heap with R = R_min = d has it; then one
// height-field update runs. Returns h at the top grain's column minus the top grain's bottom.
Real static_top_under_grain_after_update(Real speed) {
  const SceneConfig s = bed_scene();
  const Geometry geometry = Geometry::from_config(s.geometry, s.material);
  const Real dt = 1e-4;
  const SurfaceParams sp = surface_params(s, geometry, dt);
  SurfaceFlow flow(sp, geometry);
  DemParams dp;
  dp.contact = contact_params(s.material);
  dp.skin = 0.2 * kD;
  dp.sort_every = 0;  // the top grain stays last
  DemSolver dem(dp);

  const Real r = kD / 2;
  const HeightField& hf = flow.height_field();
  Grains hot;
  StaticStore st;
  GrainId id = 0;
  for (int layer = 0; layer < 3; ++layer)
    for (int j = -3; j <= 3; ++j)
      for (int i = -3; i <= 3; ++i) {
        const Vec3 x{i * kD, j * kD, (2 * layer + 1) * r};
        if (layer < 2) {
          st.add(id++, x, r, static_cast<std::uint32_t>(hf.column_of(x.x, x.y)));
        } else {
          hot.add(id++, x, {}, r, s.material.density);
          hot.state.back() = GrainState::Interface;
        }
      }
  st.file_by_column(hf.columns());
  // in the pocket between four interface grains, pressed in by a hair so that it touches them
  const Vec3 top{0.5 * kD, 0.5 * kD, 5 * r + std::sqrt(2.0) * r - 1e-5};
  hot.add(id++, top, {speed, 0, 0}, r, s.material.density);
  Profile profile;
  dem.step(hot, geometry, dt, profile);  // builds the lists: contacts_of needs them
  hot.x.back() = top;
  hot.v.back() = {speed, 0, 0};

  SurfaceState state = flow.save_state();
  for (Real& h : state.columns.h) h = top.z - r;
  flow.restore_state(state);
  flow.update(hot, st, dem, geometry, sp.update_interval);
  const std::int64_t c = hf.column_of(top.x, top.y);
  return hf.static_top()[static_cast<std::size_t>(c)] - (top.z - r);
}

TEST(FlowSpeed, SlowRollerLeavesTheStaticTopAndAFastGrainDigs) {
  const Real trap = 0.3 * std::sqrt(9.81 * kD), flow = 0.6 * std::sqrt(9.81 * kD);
  // between trap_speed and flow_speed: not trapped, and it does not dig; the static top stays
  // at its bottom (R = R_min), where the exchange and R_min put it
  const Real slow = 0.5 * (trap + flow);
  EXPECT_GT(static_top_under_grain_after_update(slow), -0.1 * kD);
  // above flow_speed: the static top goes a diameter below its bottom (the impact rule)
  EXPECT_LE(static_top_under_grain_after_update(1.5 * flow), -kD + 1e-12);
}

}  // namespace
}  // namespace sandflow
