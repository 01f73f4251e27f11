// Which grains are held by the pile and which move it (surface/seat.hpp), on constructed contact
// states: a grain in a pocket of a frozen bed at rest, too fast to stay, slipping, or balanced on
// a single grain; and what the height-field update does with each.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "core/error.hpp"
#include "sim/world.hpp"
#include "support/test_scenes.hpp"
#include "surface/seat.hpp"
#include "surface/surface_flow.hpp"
#include "surface/surface_params.hpp"

namespace sandflow {
namespace {

constexpr Real kSeatD = 0.01;  // grain diameter [m]
constexpr Real kSeatR = kSeatD / 2;

SceneConfig bed_scene() {
  SceneConfig s = test::grains_on_floor("seat", Mode::Surface, kSeatD);
  s.material.diameter_spread = 0;
  s.surface.extent = std::array<Real, 4>{-0.05, -0.05, 0.05, 0.05};
  return s;
}

TEST(Seat, TheRiseToTheSaddleIsThatOfASphereOnThreeEqualSpheres) {
  // centres of three touching spheres of radius r on a triangle of side 2r; the fourth rests on
  // them at height sqrt((2r)^2 - (2r/sqrt3)^2) above their plane, and passes over the midpoint of
  // two of them at sqrt((2r)^2 - r^2)
  const Real seat = std::sqrt(4.0 - 4.0 / 3.0), saddle = std::sqrt(3.0);
  EXPECT_NEAR(kSeatRise, saddle - seat, 1e-15);
  // at rest in its seat, without rotation, the bound is a speed of 0.31 sqrt(g d)
  SeatParams p;
  EXPECT_NEAR(std::sqrt(2 * p.hold_energy(kSeatR)), 0.3147 * std::sqrt(9.81 * kSeatD), 1e-4);
  EXPECT_EQ(p.hold_energy(kSeatR), p.move_energy(kSeatR));
  EXPECT_NEAR(p.hold_energy(2 * kSeatR), 2 * p.hold_energy(kSeatR),
              1e-15);  // the rise scales with r
}

TEST(Seat, SceneSpeedsOverrideTheSeatAndMayNotCross) {
  SceneConfig s = bed_scene();
  const Geometry g = Geometry::from_config(s.geometry, s.material);
  const SurfaceParams p = surface_params(s, g, 1e-4);
  EXPECT_NEAR(p.interface.seat.hold_energy(kSeatR), 9.81 * kSeatRise * kSeatR, 1e-15);

  s.surface.trap_speed = 0.05;
  s.surface.flow_speed = 0.2;
  const SeatParams set = surface_params(s, g, 1e-4).interface.seat;
  EXPECT_NEAR(set.hold_energy(kSeatR), 0.5 * 0.05 * 0.05, 1e-15);
  EXPECT_NEAR(set.move_energy(3 * kSeatR), 0.5 * 0.2 * 0.2, 1e-15);  // the same for every size

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
  s.surface.trap_speed = 0.25;  // above the seat's bound, which the flow takes when unset
  try {
    surface_params(s, g, 1e-4);
    FAIL() << "a trap speed above the default flow bound was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("flow_speed unset: the seat's bound"), std::string::npos)
        << e.what();
  }
}

// A bed three grains deep (two static layers under a frozen interface layer, square packing) and
// one ACTIVE grain on it, moving sideways at `speed` and spinning at `spin` about y. In a pocket
// between four interface grains, or balanced on one of them. One DEM step gives the contacts;
// then either the static top is set at the top grain's bottom (as a settled heap with R = R_min
// = d has it) and one height-field update runs, or the interface's transfer runs alone against a
// static top above the grain's centre.
struct TopGrain {
  std::uint8_t contacts = 0;  // DemSolver::contacts_of after the step
  bool held = false, moves = false;
  Real h_minus_bottom = 0;  // h at its column after the update minus its bottom [m]
  GrainState state = GrainState::Active;
};

TopGrain top_grain(Real speed, Real spin = 0, bool pocket = true, bool h_above = false) {
  const SceneConfig s = bed_scene();
  const Geometry geometry = Geometry::from_config(s.geometry, s.material);
  const Real dt = 1e-4;
  const SurfaceParams sp = surface_params(s, geometry, dt);
  SurfaceFlow flow(sp, geometry);
  DemParams dp;
  dp.contact = contact_params(s.material);
  dp.skin = 0.2 * kSeatD;
  dp.sort_every = 0;  // the top grain stays last
  DemSolver dem(dp);

  const HeightField& hf = flow.height_field();
  Grains hot;
  StaticStore st(static_frame(hf, -1.0, 1.0, 0.004, 0.006));
  GrainId id = 0;
  for (int layer = 0; layer < 3; ++layer)
    for (int j = -3; j <= 3; ++j)
      for (int i = -3; i <= 3; ++i) {
        const Vec3 x{i * kSeatD, j * kSeatD, (2 * layer + 1) * kSeatR};
        if (layer < 2) {
          st.add(id++, x, kSeatR, static_cast<std::uint32_t>(hf.column_of(x.x, x.y)));
        } else {
          hot.add(id++, x, {}, kSeatR, s.material.density);
          hot.state.back() = GrainState::Interface;
        }
      }
  // pressed in by a hair, so that it touches: between four grains, or on top of one
  const Vec3 top =
      pocket ? Vec3{0.5 * kSeatD, 0.5 * kSeatD, 5 * kSeatR + std::sqrt(2.0) * kSeatR - 1e-5}
             : Vec3{0, 0, 7 * kSeatR - 1e-5};
  hot.add(id++, top, {speed, 0, 0}, kSeatR, s.material.density);
  hot.w.back() = {0, spin, 0};
  Profile profile;
  dem.step(hot, geometry, dt, profile);  // builds the lists and sets the contacts' state
  hot.x.back() = top;
  hot.v.back() = {speed, 0, 0};
  hot.w.back() = {0, spin, 0};

  TopGrain out;
  std::vector<std::uint8_t> contacts;
  dem.contacts_of(hot, geometry, contacts);
  out.contacts = contacts.back();
  out.held = held(sp.interface.seat, hot, hot.size() - 1, out.contacts);
  out.moves = moves_pile(sp.interface.seat, hot, hot.size() - 1, out.contacts);

  if (h_above) {  // the transfer alone, against a static top above the grain's centre
    HeightField above(sp.grid, terrain_columns(sp, geometry));
    above.set_surface(std::vector<Real>(above.columns(), top.z + 2 * kSeatR));
    above.set_static_top(std::vector<Real>(above.columns(), top.z + kSeatR));
    InterfaceLayer layer(sp.interface);
    layer.transfer(above, hot, st, contacts);
  } else {
    SurfaceState state = flow.save_state();
    for (Real& h : state.columns.h) h = top.z - kSeatR;
    flow.restore_state(state);
    flow.update_height_field(hot, st, dem, geometry, sp.update_interval);
    flow.apply_impacts(hot, sp.update_interval);
    dem.apply(flow.transfer(hot, st, dem).changes);
    const std::int64_t c = hf.column_of(top.x, top.y);
    out.h_minus_bottom = hf.static_top()[static_cast<std::size_t>(c)] - (top.z - kSeatR);
  }
  for (std::size_t i = 0; i < hot.size(); ++i)
    if (hot.id[i] == id - 1) out.state = hot.state[i];
  return out;
}

const Real kEscape = std::sqrt(2 * 9.81 * kSeatRise * kSeatR);  // at rest in its seat, no rotation

TEST(Seat, AGrainAtRestInAPocketIsSeatedAndHeld) {
  const TopGrain g = top_grain(0);
  EXPECT_TRUE(g.contacts & DemSolver::kSeated) << int(g.contacts);
  EXPECT_FALSE(g.contacts & DemSolver::kSlips) << int(g.contacts);
  EXPECT_TRUE(g.held);
  EXPECT_FALSE(g.moves);
  // below h it is trapped; and it does not dig: the static top stays at its bottom
  EXPECT_EQ(top_grain(0, 0, true, true).state, GrainState::Interface);
  EXPECT_GT(g.h_minus_bottom, -0.1 * kSeatD);
}

TEST(Seat, AGrainWithTheEnergyToLeaveItsSeatMovesThePileAndDigs) {
  const TopGrain g = top_grain(1.5 * kEscape);
  EXPECT_FALSE(g.held);
  EXPECT_TRUE(g.moves);
  EXPECT_EQ(top_grain(1.5 * kEscape, 0, true, true).state, GrainState::Active);
  // the flowing layer under it (flowing_min, 2 d): the static top goes a diameter below its bottom
  EXPECT_LE(g.h_minus_bottom, -kSeatD + 1e-12);
  // rotation counts: slower than the bound, but spinning with the energy of a rolling grain
  // (2/5 of the translational) that takes it over
  const TopGrain rolling = top_grain(0.9 * kEscape, 0.9 * kEscape / kSeatR);
  EXPECT_FALSE(rolling.held);
  EXPECT_TRUE(rolling.moves);
  const TopGrain sliding = top_grain(0.9 * kEscape);
  EXPECT_TRUE(sliding.contacts & DemSolver::kSeated);
  EXPECT_TRUE(sliding.contacts & DemSolver::kSlips) << "its contacts, pressed by a hair, slip";
  EXPECT_FALSE(sliding.held) << "a grain sliding over the bed is not trapped";
  EXPECT_FALSE(sliding.moves) << "too slow to leave a seat: it does not dig";
  EXPECT_EQ(top_grain(0.9 * kEscape, 0, true, true).state, GrainState::Active);
  EXPECT_GT(sliding.h_minus_bottom, -0.1 * kSeatD);
}

TEST(Seat, AGrainBalancedOnOneGrainIsNotSeated) {
  const TopGrain g = top_grain(0, 0, false);
  EXPECT_TRUE(g.contacts & DemSolver::kTouches);
  EXPECT_FALSE(g.contacts & DemSolver::kSeated);
  EXPECT_FALSE(g.held);
  EXPECT_EQ(top_grain(0, 0, false, true).state, GrainState::Active);
}

}  // namespace
}  // namespace sandflow
