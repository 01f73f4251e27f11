#include "dem/dem_solver.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace sandflow {

DemSolver::DemSolver(const DemParams& params)
    : params_(params), rolling_(params.contact.mu_r > 0) {}

void DemSolver::step(Grains& grains, const Geometry& geometry, Real dt, Profile& profile) {
  if (need_rebuild_ || wall_params_.size() != geometry.size()) {
    ScopedStage s(profile, Stage::Neighbours);
    rebuild(grains, geometry);
  }
  {
    ScopedStage s(profile, Stage::Forces);
    if (rolling_) pair_forces<true>(grains, dt);
    else pair_forces<false>(grains, dt);
  }
  ScopedStage s(profile, Stage::Integrate);
  const Real max_disp2 =
      rolling_ ? integrate<true>(grains, geometry, dt) : integrate<false>(grains, geometry, dt);
  // Lists stay valid while no two grains can have closed the skin between them.
  if (4 * max_disp2 > params_.skin * params_.skin) need_rebuild_ = true;
}

void DemSolver::sort_by_cell(Grains& grains) {
  // Row-major cell order (z, y, x) keeps neighbours close in memory.
  const std::size_t n = grains.size();
  if (n == 0) return;
  Vec3 lo = grains.x[0];
  Real r_max = 0;
  for (std::size_t i = 0; i < n; ++i) {
    lo = min(lo, grains.x[i]);
    r_max = std::max(r_max, grains.r[i]);
  }
  const Real inv = 1.0 / (2 * r_max + params_.skin);
  auto c = [&](Real v, Real l) {
    return static_cast<std::uint64_t>(std::min((v - l) * inv, 2097151.0));
  };
  std::vector<std::uint64_t> key(n);
  for (std::size_t i = 0; i < n; ++i)
    key[i] = c(grains.x[i].z, lo.z) << 42 | c(grains.x[i].y, lo.y) << 21 | c(grains.x[i].x, lo.x);
  std::vector<std::uint32_t> perm(n);
  std::iota(perm.begin(), perm.end(), 0u);
  std::stable_sort(perm.begin(), perm.end(), [&](auto a, auto b) { return key[a] < key[b]; });
  grains.permute(perm);
}

void DemSolver::rebuild(Grains& grains, const Geometry& geometry) {
  const std::size_t n = grains.size();
  const auto& cp = params_.contact;
  if (wall_params_.size() != geometry.size()) {
    wall_params_.clear();
    for (const Obstacle& o : geometry.obstacles()) {
      ContactParams w = cp;
      w.mu = o.friction;
      w.mu_r = o.rolling_friction;
      wall_params_.push_back(w);
    }
  }
  if (params_.sort_every > 0 && rebuild_count_ % params_.sort_every == 0) sort_by_cell(grains);
  ++rebuild_count_;
  ++counters_.rebuilds;

  std::swap(pairs_, old_pairs_);
  std::swap(walls_, old_walls_);
  build_pair_list(grains, params_.skin, rolling_, grid_, old_pairs_, slot_of_id_, pairs_);
  // the normal damping of a pair depends on its masses only: computed once per list
#pragma omp parallel for schedule(static) if (n >= kParallelMinGrains)
  for (std::size_t i = 0; i < n; ++i)
    for (std::uint32_t s = pairs_.start[i]; s < pairs_.start[i + 1]; ++s) {
      const std::uint32_t j = pairs_.j[s];
      pairs_.c_n[s] = normal_damping(cp, grains.m[i] * grains.m[j] / (grains.m[i] + grains.m[j]));
    }

  // wall candidates: obstacles within reach of each grain, history carried by grain id
  const Real skin = params_.skin;
  const std::size_t n_obs = geometry.size();
  auto near = [&](std::size_t i, std::size_t k) {
    return geometry.obstacles()[k].solid->closest(grains.x[i]).distance < grains.r[i] + skin;
  };
  walls_.start.assign(n + 1, 0);
#pragma omp parallel for schedule(static) if (n >= kParallelMinGrains)
  for (std::size_t i = 0; i < n; ++i) {
    std::uint32_t c = 0;
    for (std::size_t k = 0; k < n_obs; ++k) c += near(i, k);
    walls_.start[i + 1] = c;
  }
  for (std::size_t i = 0; i < n; ++i) walls_.start[i + 1] += walls_.start[i];
  const std::size_t wslots = walls_.start[n];
  walls_.obstacle.resize(wslots);
  walls_.xi.assign(wslots, Vec3{});
  walls_.psi.assign(wslots, Vec3{});
#pragma omp parallel for schedule(static) if (n >= kParallelMinGrains)
  for (std::size_t i = 0; i < n; ++i) {
    std::uint32_t s = walls_.start[i];
    const GrainId id = grains.id[i];
    const std::uint32_t oi =
        old_walls_.start.empty() || id >= slot_of_id_.size() ? kNoSlot : slot_of_id_[id];
    for (std::uint32_t k = 0; k < n_obs; ++k) {
      if (!near(i, k)) continue;
      walls_.obstacle[s] = k;
      if (oi != kNoSlot)
        for (std::uint32_t os = old_walls_.start[oi]; os < old_walls_.start[oi + 1]; ++os)
          if (old_walls_.obstacle[os] == k) {
            walls_.xi[s] = old_walls_.xi[os];
            walls_.psi[s] = old_walls_.psi[os];
          }
      ++s;
    }
  }

  // remember where each id was, for the next carry-over
  GrainId max_id = 0;
  for (GrainId id : grains.id) max_id = std::max(max_id, id);
  slot_of_id_.assign(n ? max_id + 1 : 0, kNoSlot);
  for (std::size_t i = 0; i < n; ++i) slot_of_id_[grains.id[i]] = static_cast<std::uint32_t>(i);
  x_at_build_ = grains.x;
  need_rebuild_ = false;
}

template <bool kRolling>
void DemSolver::pair_forces(const Grains& grains, Real dt) {
  const std::size_t n = grains.size();
  const ContactParams& cp = params_.contact;
  PairList& pl = pairs_;
  const Vec3* x = grains.x.data();
  const Vec3* v = grains.v.data();
  const Vec3* w = grains.w.data();
  const Real* r = grains.r.data();
  const GrainState* st = grains.state.data();
  std::int64_t contacts = 0;
  Real max_ov = counters_.max_overlap_rel;

#pragma omp parallel for schedule(static) reduction(+ : contacts) reduction(max : max_ov) \
    if (n >= kParallelMinGrains)
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3 x_i = x[i];
    const Real r_i = r[i];
    const bool active_i = st[i] == GrainState::Active;
    for (std::uint32_t s = pl.start[i]; s < pl.start[i + 1]; ++s) {
      const std::uint32_t j = pl.j[s];
      const Vec3 d = x_i - x[j];
      const Real dist2 = norm2(d);
      const Real rsum = r_i + r[j];
      if (dist2 >= rsum * rsum || (!active_i && st[j] != GrainState::Active)) {
        // apart: the contact and its memory are gone (written only when it just ended)
        if (pl.touch[s]) {
          pl.touch[s] = 0;
          pl.xi[s] = {};
          if constexpr (kRolling) pl.psi[s] = {};
        }
        continue;
      }
      const Real dist = std::sqrt(dist2);
      ContactGeometry g;
      g.n = d * (1.0 / dist);
      g.delta = rsum - dist;
      g.arm_i = r_i;
      g.arm_j = r[j];
      g.c_n = pl.c_n[s];
      g.r_eff = r_i * r[j] / rsum;
      ContactHistory h{pl.xi[s], kRolling ? pl.psi[s] : Vec3{}};
      const ContactForce cf = contact_force<kRolling>(cp, g, v[i] - v[j], w[i], w[j], h, dt);
      pl.touch[s] = 1;
      pl.xi[s] = h.xi;
      pl.force[s] = cf.force_i;
      pl.q[s] = cf.q;
      if constexpr (kRolling) {
        pl.psi[s] = h.psi;
        pl.t_roll[s] = cf.t_roll;
      }
      ++contacts;
      max_ov = std::max(max_ov, g.delta / (2 * std::min(r_i, r[j])));
    }
  }
  counters_.contacts = contacts;
  counters_.max_overlap_rel = max_ov;
}

template <bool kRolling>
Real DemSolver::integrate(Grains& grains, const Geometry& geometry, Real dt) {
  const std::size_t n = grains.size();
  const PairList& pl = pairs_;
  const Vec3 g = params_.gravity;
  Real max_disp2 = 0;
  Real max_ov = counters_.max_overlap_rel;
  std::int64_t wall_contacts = 0;

#pragma omp parallel for schedule(static) reduction(max : max_disp2, max_ov) \
    reduction(+ : wall_contacts) if (n >= kParallelMinGrains)
  for (std::size_t i = 0; i < n; ++i) {
    if (grains.state[i] != GrainState::Active) continue;
    // gather the pair results in a fixed order: own slots, then reverse slots
    Vec3 f{}, q{}, t{};
    for (std::uint32_t s = pl.start[i]; s < pl.start[i + 1]; ++s) {
      if (!pl.touch[s]) continue;
      f += pl.force[s];
      q += pl.q[s];
      if constexpr (kRolling) t += pl.t_roll[s];
    }
    for (std::uint32_t k = pl.rev_start[i]; k < pl.rev_start[i + 1]; ++k) {
      const std::uint32_t s = pl.rev_slot[k];
      if (!pl.touch[s]) continue;
      f -= pl.force[s];
      q += pl.q[s];
      if constexpr (kRolling) t -= pl.t_roll[s];
    }
    const Real r_i = grains.r[i];
    t += q * (-r_i);
    // walls: same law, the obstacle as an immovable body with no radius
    for (std::uint32_t s = walls_.start[i]; s < walls_.start[i + 1]; ++s) {
      const std::uint32_t k = walls_.obstacle[s];
      const SurfacePoint sp = geometry.obstacles()[k].solid->closest(grains.x[i]);
      const Real delta = r_i - sp.distance;
      if (delta <= 0) {
        walls_.xi[s] = {};
        walls_.psi[s] = {};
        continue;
      }
      const ContactParams& wp = wall_params_[k];
      const ContactGeometry cg{sp.normal, delta, r_i, 0.0, normal_damping(wp, grains.m[i]), r_i};
      ContactHistory h{walls_.xi[s], walls_.psi[s]};
      const ContactForce cf =
          contact_force<kRolling>(wp, cg, grains.v[i], grains.w[i], Vec3{}, h, dt);
      walls_.xi[s] = h.xi;
      walls_.psi[s] = h.psi;
      f += cf.force_i;
      t += cf.torque_i(cg);
      ++wall_contacts;
      max_ov = std::max(max_ov, delta / (2 * r_i));
    }
    // symplectic Euler: velocities from the forces, then positions from the new velocities
    grains.v[i] += (f * grains.inv_m[i] + g) * dt;
    grains.w[i] += t * (grains.inv_I[i] * dt);
    grains.x[i] += grains.v[i] * dt;
    max_disp2 = std::max(max_disp2, norm2(grains.x[i] - x_at_build_[i]));
  }
  counters_.wall_contacts = wall_contacts;
  counters_.max_overlap_rel = max_ov;
  return max_disp2;
}

}  // namespace sandflow
