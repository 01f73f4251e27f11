// The surface-flow method of Zhu & Yang (docs/design.md §1): the height field of the static layer
// and the particle interface, updated together every few DEM steps. An update is three stages,
// which World::step calls and times one by one, in the paper's order: the height field (measure H,
// evolve h through the exchange), the impacts (the static top held below the grains that move
// the pile), the transfer (the changes of state). The transfer and the invariant of the layers
// return the changes of state they made in the stores; the DEM applies them (DemSolver::apply):
// the surface flow reads the solver, it does not change it.
#pragma once

#include <algorithm>
#include <unordered_set>
#include <vector>

#include "dem/dem_solver.hpp"
#include "dem/grains.hpp"
#include "geometry/shapes.hpp"
#include "surface/height_field.hpp"
#include "surface/interface_layer.hpp"
#include "surface/surface_params.hpp"

namespace sandflow {

/// A blow under way (the blow rule, SurfaceFlow::apply_impacts): its momentum now and all it
/// received [kg m/s], the received momentum's sums of x and y, the mass and the diameters of the
/// grains counted and how many, where it struck (z0: the sand's surface there) and its radius [m].
struct Blow {
  Real p = 0, p0 = 0, px = 0, py = 0, m = 0, d = 0, z0 = 0, rho = 0;
  std::int64_t n = 0;
};

/// What a restart needs of the surface flow: the height field's columns, the interface's memory
/// of the last transfer and the blows under way (src/checkpoint/). The rest is scratch of one
/// update.
struct SurfaceState {
  HeightField::State columns;
  std::vector<Real> h_seen, L_seen;
  bool pending = false;  ///< transitions wait for the pair list's next rebuild
  std::vector<Blow> blows;
  std::vector<GrainId> counted;  ///< (ascending)
};

class SurfaceFlow {
 public:
  SurfaceFlow(const SurfaceParams& params, const Geometry& geometry);

  /// The geometry changed (a solid was removed): traces the columns' terrain again.
  void retrace_terrain(const Geometry& geometry) { hf_.set_solids(terrain_columns(p_, geometry)); }

  // One update over `dt` of simulated time: the three calls below, in this order.

  /// Stage "height field": measures H from the grains of the pile (the hot grains that touch
  /// something, and the static tops), finds the columns where grains move the pile, and evolves
  /// h there (BCRE with theta0) and elsewhere (deposit up to theta_max) through the exchange.
  void update_height_field(const Grains& hot, const StaticStore& st, const DemSolver& dem,
                           const Geometry& geometry, Real dt);
  /// Stage "impacts", the blow rule (surface.blows; nothing without it): the static top retreats
  /// under grains in flight about to strike it and under the blows under way.
  void apply_impacts(const Grains& hot, Real dt);
  /// Stage "transfer" after an update: trap, dislodge, sleep and wake against the new h. Only
  /// trapping keeps the pair list: unless `dem` rebuilds it at this step anyway, the rest waits
  /// for its next rebuild (catch_up), and at most until the next update.
  Transitions transfer(Grains& hot, StaticStore& st, const DemSolver& dem);
  /// Stage "transfer" between updates: the transitions the last update left waiting, if `dem`
  /// rebuilds its lists at this step anyway.
  Transitions catch_up(Grains& hot, StaticStore& st, const DemSolver& dem,
                       const Geometry& geometry);

  /// Stage "reach", the invariant of the layers, before `dem` rebuilds its lists for steps of dt:
  /// every STATIC grain within reach of an ACTIVE grain wakes (InterfaceLayer::wake_within_reach).
  Transitions wake_within_reach(Grains& hot, StaticStore& st, DemSolver& dem, Real dt);

  /// A bed born at rest (sim/emitters.hpp, docs/design.md §7): new grains ids[k] at x[k] with
  /// radii r[k] go straight to the layers an update would keep a pile at rest in. H, where they
  /// lie, rises to their top, and so does h: their columns start closed (HeightField::closed), so
  /// every grain is STATIC but one outside the grid or under its column's level, which is ACTIVE;
  /// the invariant of the layers wakes what such a grain can reach at the first rebuild. The ACTIVE
  /// grains count in the next measure of H though the DEM has not yet seen their contacts. Returns
  /// how many went to each state.
  struct Seating {
    std::int64_t active = 0, interface = 0, statics = 0;
  };
  Seating seat_bed(Grains& hot, StaticStore& st, const std::vector<GrainId>& ids,
                   const std::vector<Vec3>& x, const std::vector<Real>& r);

  const SurfaceParams& params() const { return p_; }
  const HeightField& height_field() const { return hf_; }

  SurfaceState save_state() const {
    std::vector<GrainId> counted(counted_.begin(), counted_.end());
    std::sort(counted.begin(), counted.end());
    return {hf_.state(), interface_.h_seen(), interface_.L_seen(), pending_, blows_, counted};
  }
  /// Restores a saved state (sizes checked by the caller).
  void restore_state(SurfaceState s) {
    hf_.restore(std::move(s.columns));
    interface_.restore_seen(std::move(s.h_seen), std::move(s.L_seen));
    pending_ = s.pending;
    blows_ = std::move(s.blows);
    counted_ = std::unordered_set<GrainId>(s.counted.begin(), s.counted.end());
  }

 private:
  /// Under its column's level (an overhang, a wall's foot): the height field does not reach it.
  bool below_level(const Vec3& x) const;

  SurfaceParams p_;
  HeightField hf_;
  InterfaceLayer interface_;
  /// The columns whose h or L changed since the last transfer that could wake grains (null: any
  /// may have).
  const std::vector<std::uint32_t>* take_moved();

  std::vector<std::uint8_t> contacts_, counts_;
  std::vector<std::vector<std::uint64_t>> ray_columns_;  ///< per thread: update_height_field's
  ColumnSet flowing_;                 ///< the columns where grains move the pile
  ColumnSet eroding_;                 ///< those whose static top a moving grain reaches
  std::vector<std::uint32_t> moved_;  ///< scratch of take_moved()
  template <class Strike>
  void strike_with_blows(const Grains& hot, Real dt, Strike&& strike);
  std::vector<Blow> blows_;              ///< the blows under way (the blow rule)
  std::unordered_set<GrainId> counted_;  ///< the grains the blows under way have counted
  /// ACTIVE grains seated by seat_bed: part of the pile at the next measure (sorted ids)
  std::vector<GrainId> seated_;
  bool pending_ = false;  ///< transitions that change the pair list wait for its next rebuild
};

}  // namespace sandflow
