// Whether a grain is held by the pile or moves over it, from its own contacts and motion
// (docs/physics.md, "Trapping and flowing"). A sphere resting on a bed of equal spheres sits in
// the hollow of three; to leave, it must roll over the saddle between two of them, which lies
// (sqrt(3) - 2 sqrt(2/3)) r = 0.099 r above its seat. So a grain is held when it is seated (three
// grain contacts, or the geometry), none of its contacts slips, and its kinetic energy, rotation
// included, is below m |g| 0.099 r: it cannot climb out. A grain touching the pile with more
// energy than that moves over it. At rest in its seat and without rotation the bound is a speed
// of 0.31 sqrt(|g| d).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "dem/dem_solver.hpp"
#include "dem/grains.hpp"

namespace sandflow {

/// The rise from a sphere's seat in three equal spheres to the saddle between two of them, per
/// radius: sqrt(3) - 2 sqrt(2/3).
constexpr Real kSeatRise = 0.0990576457134251;

struct SeatParams {
  Real gravity = 9.81;  ///< |g| [m/s^2]
  /// When set (>= 0): the speed below which a seated grain is held, and the one above which a
  /// grain touching the pile moves it, for every grain size (the scene's trap_speed and
  /// flow_speed) [m/s]. Unset (negative): the seat's energy.
  Real trap_speed = -1, flow_speed = -1;

  /// Kinetic energy per mass below which a grain of radius r cannot leave its seat [J/kg].
  Real hold_energy(Real r) const {
    return trap_speed >= 0 ? 0.5 * trap_speed * trap_speed : gravity * kSeatRise * r;
  }
  /// Kinetic energy per mass above which a grain of radius r touching the pile moves it [J/kg].
  Real move_energy(Real r) const {
    return flow_speed >= 0 ? 0.5 * flow_speed * flow_speed : gravity * kSeatRise * r;
  }
  /// move_energy as a speed, v_flow [m/s].
  Real move_speed(Real r) const { return std::sqrt(2 * move_energy(r)); }
};

/// Kinetic energy per mass of grain i, rotation included [J/kg].
inline Real kinetic_energy_per_mass(const Grains& g, std::size_t i) {
  return 0.5 * (norm2(g.v[i]) + norm2(g.w[i]) * g.inv_m[i] / g.inv_I[i]);
}

/// Whether grain i, with the contact flags `contacts` (DemSolver::contacts_of), is held in its
/// seat: seated, no contact slipping, too slow to leave.
inline bool held(const SeatParams& p, const Grains& g, std::size_t i, std::uint8_t contacts) {
  return (contacts & DemSolver::kSeated) && !(contacts & DemSolver::kSlips) &&
         kinetic_energy_per_mass(g, i) < p.hold_energy(g.r[i]);
}

/// Whether grain i rests where it is: touching something, no contact slipping, too slow to leave a
/// seat. In a column where nothing has moved the pile for a while (a closed column) this is enough
/// to trap it, seated on three or leaning on two: it is not bouncing, or the column would flow.
inline bool at_rest(const SeatParams& p, const Grains& g, std::size_t i, std::uint8_t contacts) {
  return (contacts & DemSolver::kTouches) && !(contacts & DemSolver::kSlips) &&
         kinetic_energy_per_mass(g, i) < p.hold_energy(g.r[i]);
}

/// Whether grain i moves the pile it touches: touching it with more than the seat's energy.
inline bool moves_pile(const SeatParams& p, const Grains& g, std::size_t i, std::uint8_t contacts) {
  return (contacts & DemSolver::kTouches) && kinetic_energy_per_mass(g, i) >= p.move_energy(g.r[i]);
}

/// Packing fraction of the bed a blow strikes, in blow_radius: poured sand's.
constexpr Real kBlowPacking = 0.6;

/// How far a blow sets a bed in motion [m]: a body of grains of mean mass m and diameter d that
/// strikes it with momentum m v (v: the speed one grain would need to carry it) shares the
/// momentum with the bed's grains in a half-sphere of radius rho about the point it strikes
/// (packing kBlowPacking); they move the pile while their shared speed is still v_flow:
/// m v = (m + phi 2/3 pi rho^3 rho_s) v_flow, so rho = d cbrt((v / v_flow - 1) / (4 phi)).
/// 0 at or below v_flow.
inline Real blow_radius(Real v, Real v_flow, Real d) {
  if (!(v > v_flow) || !(v_flow > 0)) return 0;
  return d * std::cbrt((v / v_flow - 1) / (4 * kBlowPacking));
}

/// How long the bed a blow of radius rho set moving keeps moving [s]: friction stops bed moving at
/// v_flow in v_flow / (mu g), but the sand of the half-sphere it opened falls and flows back into
/// it over the crater's own time, sqrt(rho / g) (a crater's growth in the gravity regime: the
/// time gravity takes to undo an opening of size rho), and the blow holds the bed open as long.
inline Real blow_lifetime(Real v_flow, Real friction, Real gravity, Real rho) {
  return std::max(v_flow / (friction * gravity), std::sqrt(rho / gravity));
}

}  // namespace sandflow
