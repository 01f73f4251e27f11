// The surface-flow method of Zhu & Yang (docs/design.md §1): the height field of the static layer and
// the particle interface, updated together every few DEM steps.
#pragma once

#include <vector>

#include "dem/dem_solver.hpp"
#include "dem/grains.hpp"
#include "geometry/shapes.hpp"
#include "surface/height_field.hpp"
#include "surface/interface_layer.hpp"
#include "surface/surface_params.hpp"

namespace sandflow {

/// What a restart needs of the surface flow: the height field's columns and the interface's
/// memory of the last transfer (src/checkpoint/). The rest is scratch of one update.
struct SurfaceState {
  HeightField::State columns;
  std::vector<Real> h_seen, L_seen;
  bool pending = false;  ///< transitions wait for the pair list's next rebuild
};

class SurfaceFlow {
 public:
  SurfaceFlow(const SurfaceParams& params, const Geometry& geometry);

  /// The geometry changed (a solid was removed): traces the columns' terrain again.
  void retrace_terrain(const Geometry& geometry) { hf_.set_solids(terrain_columns(p_, geometry)); }

  /// One update over `dt` of simulated time, in the paper's order: measure H, evolve h through
  /// the exchange, then pass grains between the layers. Returns the changes of state, which the
  /// DEM applies (DemSolver::apply): the surface flow reads the solver, it does not change it.
  Transitions update(Grains& hot, StaticStore& st, const DemSolver& dem, const Geometry& geometry,
                     Real dt);

  /// Makes the transitions the last update left waiting, if `dem` rebuilds its lists anyway.
  Transitions catch_up(Grains& hot, StaticStore& st, const DemSolver& dem,
                       const Geometry& geometry);

  /// The invariant of the layers, before `dem` rebuilds its lists for steps of dt: every STATIC
  /// grain within reach of an ACTIVE grain wakes (InterfaceLayer::wake_within_reach).
  Transitions wake_within_reach(Grains& hot, StaticStore& st, const DemSolver& dem, Real dt);

  const SurfaceParams& params() const { return p_; }
  const HeightField& height_field() const { return hf_; }

  SurfaceState save_state() const {
    return {hf_.state(), interface_.h_seen(), interface_.L_seen(), pending_};
  }
  /// Restores a saved state (sizes checked by the caller).
  void restore_state(SurfaceState s) {
    hf_.restore(std::move(s.columns));
    interface_.restore_seen(std::move(s.h_seen), std::move(s.L_seen));
    pending_ = s.pending;
  }

 private:
  /// Under its column's level (an overhang, a wall's foot): the height field does not reach it.
  bool below_level(const Vec3& x) const;

  SurfaceParams p_;
  HeightField hf_;
  InterfaceLayer interface_;
  std::vector<std::uint8_t> contacts_, counts_, flowing_;
  std::vector<std::uint32_t> fast_;
  std::vector<Real> allow_;
  bool pending_ = false;  ///< transitions that change the pair list wait for its next rebuild
};

}  // namespace sandflow
