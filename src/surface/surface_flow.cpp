#include "surface/surface_flow.hpp"

#include <algorithm>

namespace sandflow {

SurfaceFlow::SurfaceFlow(const SurfaceParams& params, const Geometry& geometry)
    : p_(params),
      hf_(params.grid, terrain_columns(params, geometry)),
      interface_(params.interface) {}

bool SurfaceFlow::below_level(const Vec3& x) const {
  const std::int64_t c = hf_.column_of(x.x, x.y);
  return c >= 0 && x.z < hf_.terrain()[static_cast<std::size_t>(c)];
}

TransitionCounts SurfaceFlow::update(Grains& hot, StaticStore& st, DemSolver& dem,
                                     const Geometry& geometry, Real dt) {
  // a grain in flight touches nothing: only grains of the pile (and the interface) make H
  dem.contacts_of(hot, geometry, contacts_);
  counts_.resize(hot.size());
  for (std::size_t i = 0; i < hot.size(); ++i)
    counts_[i] = hot.state[i] != GrainState::Active || (contacts_[i] & DemSolver::kTouches);
  interface_.static_tops(hf_, st, static_top_);
  hf_.measure(hot, static_top_, counts_);
  // The columns where grains move: a fast grain in contact with the pile. There the rolling
  // layer flows (BCRE with theta0); elsewhere it is at rest and deposits up to theta_max.
  const Real v2_fast = p_.interface.trap_speed * p_.interface.trap_speed;
  flowing_.assign(hf_.columns(), 0);
  fast_.clear();
  for (std::size_t i = 0; i < hot.size(); ++i) {
    if (hot.state[i] != GrainState::Active || !(contacts_[i] & DemSolver::kTouches) ||
        norm2(hot.v[i]) < v2_fast || below_level(hot.x[i]))
      continue;
    fast_.push_back(static_cast<std::uint32_t>(i));
    hf_.for_each_ray_hit(hot.x[i], hot.r[i], [&](std::size_t c, Real, Real) { flowing_[c] = 1; });
  }
  hf_.exchange(dt, flowing_);
  // Impacts: a fast grain striking the pile sets the grains beneath it in motion in DEM, so the
  // static top stays a grain's diameter below the bottom of every fast grain in contact. Without
  // this the stream of a pour would hit a frozen apex and build a spike where DEM digs a plateau.
  // It reaches below the grain as far as the grain can fall before the next update.
  for (std::uint32_t i : fast_) {
    const Real floor_z = hot.x[i].z - 3 * hot.r[i] - std::max(-hot.v[i].z, 0.0) * dt;
    hf_.for_each_ray_hit(hot.x[i], hot.r[i],
                         [&](std::size_t c, Real, Real) { hf_.limit_static_top(c, floor_z); });
  }
  // An active grain inside the static layer (pushed through the interface between updates)
  // would sink through grains that push nothing: the static layer retreats below it, and the
  // grains around it wake.
  const Real T = p_.interface.thickness;
  for (std::size_t i = 0; i < hot.size(); ++i) {
    if (hot.state[i] != GrainState::Active) continue;
    const Vec3& x = hot.x[i];
    if (hf_.column_of(x.x, x.y) < 0 || below_level(x) || x.z >= hf_.static_top_at(x.x, x.y) - T)
      continue;
    const Real floor_z = x.z - hot.r[i] - T;
    hf_.for_each_ray_hit(x, hot.r[i],
                         [&](std::size_t c, Real, Real) { hf_.limit_static_top(c, floor_z); });
  }
  return interface_.transfer(hf_, hot, st, dem, contacts_);
}

}  // namespace sandflow
