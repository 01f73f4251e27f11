#include "surface/surface_flow.hpp"

#include <algorithm>
#include <cmath>

#include <omp.h>

#include "dem/neighbor_list.hpp"  // kParallelMinGrains

namespace sandflow {

SurfaceFlow::SurfaceFlow(const SurfaceParams& params, const Geometry& geometry)
    : p_(params),
      hf_(params.grid, terrain_columns(params, geometry)),
      interface_(params.interface) {}

bool SurfaceFlow::below_level(const Vec3& x) const {
  const std::int64_t c = hf_.column_of(x.x, x.y);
  return c >= 0 && x.z < hf_.terrain()[static_cast<std::size_t>(c)];
}

void SurfaceFlow::update_height_field(const Grains& hot, const StaticStore& st,
                                      const DemSolver& dem, const Geometry& geometry, Real dt) {
  // a grain in flight touches nothing: only grains of the pile (and the interface) make H, and
  // those frozen or at rest on it even above a void
  dem.contacts_of(hot, geometry, contacts_);
  const std::size_t n = hot.size();
  counts_.resize(n);
#pragma omp parallel for schedule(static) if (n >= kParallelMinGrains)
  for (std::size_t i = 0; i < n; ++i)
    counts_[i] =
        hot.state[i] != GrainState::Active || at_rest(p_.interface.seat, hot, i, contacts_[i])
            ? HeightField::kHeldOnPile
            : (contacts_[i] & DemSolver::kTouches) != 0;
  // (a bed's ACTIVE grains, seated before the DEM has seen their contacts, are part of the pile)
  if (!seated_.empty()) {
    for (std::size_t i = 0; i < hot.size(); ++i)
      if (std::binary_search(seated_.begin(), seated_.end(), hot.id[i]))
        counts_[i] = HeightField::kHeldOnPile;
    seated_.clear();
  }
  const std::vector<Real>& tops = interface_.static_tops(hf_, st);
  hf_.measure(hot, tops, counts_, interface_.take_changed_tops());
  // The columns where grains move: a grain in contact with the pile with the energy to leave a
  // seat (seat.hpp). There the rolling layer flows (BCRE with theta0); elsewhere it is at rest
  // and deposits up to theta_max.
  if (flowing_.columns() != hf_.columns()) flowing_.resize(hf_.columns());
  if (eroding_.columns() != hf_.columns()) eroding_.resize(hf_.columns());
  flowing_.clear();
  eroding_.clear();
  // Of those, the flow digs the static layer only where a moving grain reaches down to it: the
  // layer of grains at rest between a flow and the static top shields it, as it does in DEM.
  const std::vector<Real>& h = hf_.static_top();
  const Real reach = hf_.params().erosion_reach;
  // (each thread lists the columns of its share of the grains in grain order, 2c + 1 for one
  // eroded; the lists joined in thread order fill the sets as one thread would)
#pragma omp parallel if (n >= kParallelMinGrains)
  {
#pragma omp single
    ray_columns_.resize(static_cast<std::size_t>(omp_get_num_threads()));
    // (the thread's own vector while it fills it: side by side in ray_columns_, each push_back
    // would pass their cache line between the cores)
    const std::size_t t = static_cast<std::size_t>(omp_get_thread_num());
    std::vector<std::uint64_t> mine = std::move(ray_columns_[t]);
    mine.clear();
#pragma omp for schedule(static)
    for (std::size_t i = 0; i < n; ++i) {
      if (hot.state[i] != GrainState::Active ||
          !moves_pile(p_.interface.seat, hot, i, contacts_[i]) || below_level(hot.x[i]))
        continue;
      hf_.for_each_ray_hit(hot.x[i], hot.r[i], [&](std::size_t c, Real bottom, Real) {
        mine.push_back(2 * std::uint64_t{c} + (bottom <= h[c] + reach ? 1 : 0));
      });
    }
    ray_columns_[t] = std::move(mine);
  }
  for (const std::vector<std::uint64_t>& list : ray_columns_)
    for (const std::uint64_t e : list) {
      flowing_.add(static_cast<std::uint32_t>(e / 2));
      if (e % 2) eroding_.add(static_cast<std::uint32_t>(e / 2));
    }
  hf_.exchange(dt, flowing_, &eroding_);
}

SurfaceFlow::Seating SurfaceFlow::seat_bed(Grains& hot, StaticStore& st,
                                           const std::vector<GrainId>& ids,
                                           const std::vector<Vec3>& x, const std::vector<Real>& r) {
  Seating out;
  const std::vector<Real>& L = hf_.terrain();
  // H: the top of the bed's grains in each column they reach (above its level)
  std::vector<Real> H = hf_.surface(), h = hf_.static_top();
  std::vector<std::uint8_t> bed(hf_.columns(), 0);
  for (std::size_t k = 0; k < x.size(); ++k) {
    hf_.for_each_ray_hit(x[k], r[k], [&](std::size_t c, Real, Real top) {
      if (x[k].z < L[c]) return;
      H[c] = std::max(H[c], top);
      bed[c] = 1;
    });
  }
  // h: at H, and the bed's columns closed, as a column at rest is (nothing has moved there), so
  // that the next update neither erodes nor wakes the bed
  hf_.set_surface(H);
  for (std::size_t c = 0; c < bed.size(); ++c)
    if (bed[c]) {
      h[c] = H[c];
      hf_.close(c);
    }
  hf_.set_static_top(h);

  // each grain to its layer: ACTIVE above h (or outside the height field's reach), STATIC below
  // it; the invariant of the layers wakes, at the first rebuild, what an ACTIVE grain can reach
  const Real density = p_.interface.density;
  seated_.clear();
  for (std::size_t k = 0; k < x.size(); ++k) {
    const std::int64_t c = hf_.column_of(x[k].x, x[k].y);
    const Real top = c < 0 ? 0 : hf_.static_top_at(x[k].x, x[k].y);
    if (c < 0 || x[k].z < L[static_cast<std::size_t>(c)] || x[k].z > top) {
      hot.add(ids[k], x[k], Vec3{}, r[k], density);
      seated_.push_back(ids[k]);
      ++out.active;
    } else {
      st.add(ids[k], x[k], r[k], static_cast<std::uint32_t>(c));
      ++out.statics;
    }
  }
  std::sort(seated_.begin(), seated_.end());
  return out;
}

void SurfaceFlow::apply_impacts(const Grains& hot, Real dt) {
  if (!p_.interface.blows) return;  // (only the blow rule strikes)
  // The static layer retreats to `floor_z` under a grain at x moving at v, along its way until
  // the next update: a grain skidding sideways at 3 m/s crosses a column between two updates, and
  // the bed of the column it enters must be moving when it arrives, as its contacts would set it.
  const Real half_cell = hf_.cell() / 2;
  auto clear_path = [&](const Vec3& x, const Vec3& v, Real r, Real floor_z) {
    const Real travel = std::min(std::hypot(v.x, v.y) * dt, 1.0);
    const int samples = 1 + static_cast<int>(std::ceil(travel / half_cell));
    for (int k = 0; k < samples; ++k) {
      const Real t = samples > 1 ? dt * k / (samples - 1) : 0.0;
      hf_.for_each_ray_hit(Vec3{x.x + v.x * t, x.y + v.y * t, x.z}, r,
                           [&](std::size_t c, Real, Real) { hf_.limit_static_top(c, floor_z); });
    }
  };
  // A grain in flight about to strike: the static top a grain's diameter below its bottom, as
  // far down as it falls before the next update. (Grains in contact that move the pile are not
  // struck: the flowing layer, flowing_min deep under them, is the bed that yields. Struck too,
  // each pitted h a grain below itself, and the pits' steep edges eroded the static top around
  // them: the 100,000-grain floor kept 38 % of its grains simulated over the last half against
  // 31 %, and came out no nearer plain DEM: docs/physics.md, "Impacts".)
  auto strike = [&](std::size_t i) {
    const Vec3& x = hot.x[i];
    const Vec3& v = hot.v[i];
    clear_path(x, v, hot.r[i], x.z - 3 * hot.r[i] - std::max(-v.z, 0.0) * dt);
  };
  strike_with_blows(hot, dt, strike);
}

template <class Strike>
void SurfaceFlow::strike_with_blows(const Grains& hot, Real dt, Strike&& strike) {
  // The blow rule (surface.blows; docs/physics.md, "Blows"). A grain in flight that reaches the
  // static top before the next update strikes as one in contact does: the clod of an impact falls
  // 2 cm between two updates, and would land on a bed that does not yield. And a body of grains
  // falling into the bed faster than the flow speed shares its whole momentum with the bed, not
  // one grain's: each blow is a record of where it struck and of the downward momentum brought
  // into its footprint, down to the bed's level there, by every fast-falling grain (each counted
  // once), decaying as the bed it set moving stops (seat.hpp, blow_lifetime). While it lasts, the
  // static top stays under the half-sphere that momentum sets moving (seat.hpp, blow_radius).
  const SeatParams& seat = p_.interface.seat;
  for (Blow& b : blows_) {
    const Real v_flow = seat.move_speed(b.d / static_cast<Real>(b.n) / 2);
    const Real life = blow_lifetime(v_flow, p_.interface.friction, seat.gravity, b.rho);
    b.p *= std::exp(-dt / std::max(life, 1e-12));
  }
  for (std::size_t i = 0; i < hot.size(); ++i) {
    if (hot.state[i] != GrainState::Active ||
        kinetic_energy_per_mass(hot, i) < seat.move_energy(hot.r[i]) || below_level(hot.x[i]))
      continue;
    const Vec3& x = hot.x[i];
    const Vec3& v = hot.v[i];
    const Real low = x.z - hot.r[i] + std::min(v.z, 0.0) * dt;  // its bottom at the next update
    const bool lands = low <= hf_.static_top_at(x.x, x.y);
    if (lands && !(contacts_[i] & DemSolver::kTouches)) strike(i);
    if (-v.z <= seat.move_speed(hot.r[i]) || counted_.count(hot.id[i])) continue;
    Blow* into = nullptr;
    for (Blow& b : blows_) {
      const Real d = b.d / static_cast<Real>(b.n);
      if (std::hypot(x.x - b.px / b.p0, x.y - b.py / b.p0) < std::max(b.rho, 2 * d) &&
          low <= b.z0 + d) {
        into = &b;
        break;
      }
    }
    if (!into && !lands) continue;
    if (!into) {
      // a new blow, centred on the sand's surface where it strikes
      const std::int64_t c = hf_.column_of(x.x, x.y);
      Blow b;
      b.z0 = hf_.static_top_at(x.x, x.y);
      if (c >= 0) b.z0 = std::max(b.z0, hf_.surface()[static_cast<std::size_t>(c)]);
      blows_.push_back(b);
      into = &blows_.back();
    }
    const Real p = hot.m[i] * -v.z;
    into->p += p;
    into->p0 += p;
    into->px += p * x.x;
    into->py += p * x.y;
    into->m += hot.m[i];
    into->d += 2 * hot.r[i];
    ++into->n;
    counted_.insert(hot.id[i]);
  }
  // each blow's half-sphere; one whose momentum no longer opens more than a grain's strike ends
  std::size_t kept = 0;
  for (Blow& b : blows_) {
    const Real n = static_cast<Real>(b.n), d = b.d / n;
    b.rho = blow_radius(b.p / (b.m / n), seat.move_speed(d / 2), d);
    if (b.rho <= d) continue;
    hf_.for_each_ray_hit(Vec3{b.px / b.p0, b.py / b.p0, b.z0}, b.rho,
                         [&](std::size_t c, Real bottom, Real) { hf_.limit_static_top(c, bottom); });
    blows_[kept++] = b;
  }
  blows_.resize(kept);
  if (blows_.empty()) counted_.clear();
}

Transitions SurfaceFlow::transfer(Grains& hot, StaticStore& st, const DemSolver& dem) {
  // Dislodging, sleeping and waking change the pair list: unless it is rebuilt anyway at this
  // step, they wait for its next rebuild, and at most until the next update.
  const bool now = dem.needs_rebuild() || pending_;
  pending_ = !now;
  if (!now) return interface_.transfer(hf_, hot, st, contacts_, false);
  return interface_.transfer(hf_, hot, st, contacts_, true, take_moved());
}

Transitions SurfaceFlow::wake_within_reach(Grains& hot, StaticStore& st, DemSolver& dem, Real dt) {
  // (the rebuild after it takes the same allowances)
  return interface_.wake_within_reach(hf_, hot, st, dem.allowances_for_rebuild(hot, dt));
}

Transitions SurfaceFlow::catch_up(Grains& hot, StaticStore& st, const DemSolver& dem,
                                  const Geometry& geometry) {
  if (!pending_ || !dem.needs_rebuild()) return {};
  pending_ = false;
  dem.contacts_of(hot, geometry, contacts_);
  return interface_.transfer(hf_, hot, st, contacts_, true, take_moved());
}

const std::vector<std::uint32_t>* SurfaceFlow::take_moved() {
  bool all = false;
  hf_.take_moved(moved_, all);
  return all ? nullptr : &moved_;
}

}  // namespace sandflow
