#include "dem/dem_solver.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cmath>
#include <limits>
#include <numeric>
#include <string>

#include <fmt/format.h>
#include <omp.h>

#include "core/assert.hpp"

namespace sandflow {

namespace {

/// (assertions) The largest run whose pair list is checked against the brute-force reference
/// after every rebuild: O(n^2), 2 million distances at this size.
constexpr std::size_t kPairCheckMaxGrains = 2000;

/// (assertions) The contact law gives finite results for a finite state with a contact normal; a
/// non-finite state, or centres that meet (no normal), is a blow-up that the guards report
/// (docs/scenes.md, "Guards"). Finite here means |a| < 1e154, so that no product of two such
/// numbers inside the law overflows.
[[maybe_unused]] bool tame(const Vec3& a) {
  return std::isfinite(norm2(a));
}
[[maybe_unused]] bool finite_result(const ContactForce& cf, const ContactHistory& h, bool rolling) {
  return is_finite(cf.force_i) && is_finite(cf.q) && is_finite(h.xi) &&
         (!rolling || (is_finite(cf.t_roll) && is_finite(h.psi)));
}

// The rare paths of the sweep, kept out of its loop.

/// The energy in the springs of listed contact s, whose grains (centres sqrt(dist2) apart) are
/// both frozen now: the contact goes inert.
[[gnu::cold, gnu::noinline]] Real inert_energy(const ContactParams& cp, const PairList& pl,
                                               std::uint32_t s, Real rsum, Real dist2,
                                               bool rolling) {
  const Real d0 = pl.touch[s] & kPreloaded ? pl.delta0[s] : 0;
  return elastic_energy(cp, std::max(rsum - std::sqrt(dist2) - d0, 0.0),
                        {pl.xi[s], rolling ? pl.psi[s] : Vec3{}});
}

/// What relax_preload leaves: the overlap the spring sees [m], and the energy it gained [J].
struct Relaxed {
  Real delta;
  Real work;
};

/// A preloaded contact (opened inside by a change of state): its spring rests at delta0, which
/// follows the grains apart and decays by `decay`, so that it gives back only the overlap they
/// add and pushes them apart slowly. Returns what the spring sees of overlap delta, and the
/// energy the spring gained by the decay. (delta by value: an address taken would keep the
/// sweep's contact geometry on the stack for every contact.)
[[gnu::cold, gnu::noinline]] Relaxed relax_preload(Real k_n, Real decay, Real& delta0, Real delta) {
  const Real d0 = delta0, d0_new = std::min(d0 * decay, delta);
  const Real work = d0_new < d0 && delta > d0
                        ? 0.5 * k_n * (d0 - d0_new) * (2 * delta - d0 - d0_new)
                        : 0.0;
  delta0 = d0_new;
  return {delta - d0_new, work};
}

/// What a grain's move leaves (DemSolver::sweep): its allowance (the lists are rebuilt), its near
/// margin (the near list is made again), the domain (DemSolver::all_inside).
constexpr int kLeftAllowance = 2, kLeftNearMargin = 1, kLeftDomain = 4;

/// Forgets the contact of pair slot s: its flags and its memory (the rolling one with kRolling).
/// `pl` is the PairList or the sweep's view of its arrays.
template <bool kRolling, class Pairs>
[[gnu::always_inline]] inline void forget_contact(Pairs& pl, std::uint32_t s) {
  pl.touch[s] = 0;
  pl.delta0[s] = 0;
  pl.xi[s] = {};
  if constexpr (kRolling) pl.psi[s] = {};
}

/// The first slot of grain i's row that reaches past `end` (rows are sorted by j); `pl` is the
/// PairList or the sweep's view of its arrays.
template <class Pairs>
[[gnu::always_inline]] inline std::uint32_t first_reaching(const Pairs& pl, std::size_t i,
                                                           std::size_t end) {
  std::uint32_t first = pl.start[i + 1];
  while (first > pl.start[i] && pl.j[first - 1] >= end) --first;
  return first;
}

}  // namespace

DemSolver::DemSolver(const DemParams& params)
    : params_(params),
      rolling_(params.contact.mu_r > 0 || params.contact.mu_tw > 0 || params.walls_resist_turning),
      use_avx512_(avx512_available()) {}

bool DemSolver::avx512_available() {
  // (the operating system's support for the registers' state included)
  return __builtin_cpu_supports("avx512f");
}

void DemSolver::step(Grains& grains, const Geometry& geometry, Real dt, Profile& profile) {
  timed(profile, Stage::Neighbours, [&] { update_lists(grains, geometry, dt); });
  timed(profile, Stage::Forces, [&] { advance(grains, geometry, dt); });
}

void DemSolver::update_lists(Grains& grains, const Geometry& geometry, Real dt) {
  if (need_rebuild_ || wall_params_.size() != geometry.size()) rebuild(grains, geometry, dt);
  if (need_near_) build_near(grains, dt);
}

// The near list. A settled grain's Verlet row holds about twice the pairs that touch (a skin of
// 0.2 d), and every listed pair costs the sweep its partner's position and a branch that a
// predictor cannot learn; a list of only the touching pairs takes a fifth off the sweep of a
// settled bed (docs/performance.md, seventy-third entry). Rebuilt with the cell grid each time a
// grain moves so little, it would cost more than it saves; filtered from the Verlet rows it
// costs a fraction of a step. Each grain gets a near margin b_i (its allowance, or less when it is
// slow), and a listed pair enters when its gap is under b_i + b_j: no pair left out can touch
// before some grain has moved further than its margin, which the sweep checks as it checks the
// allowance. The rows keep their slot order, so the sweep adds the same terms in the same order
// with or without it: the results are bit for bit those of the Verlet rows.
void DemSolver::build_near(const Grains& grains, Real dt) {
  const std::size_t n = grains.size();
  const std::size_t listed = pairs_.start.empty() ? 0 : pairs_.start.size() - 1;
  x_at_near_ = grains.x;
  near2_.resize(n);
  // a grain's margin: the way it goes in skin_steps steps (32 when unset) from its present speed
  // under gravity, within its allowance, and at least a hundredth of the least allowance, so
  // that grains at rest do not make the list again every few steps. The settled bed of
  // bench_bed, whose grains creep at micrometres a second, took its sweep 1.2 times faster with
  // a two-hundredth of the skin (2.50 near pairs a grain, 2.36 touching, 4.39 listed) than
  // with none, and about as fast as with a thousandth (2.44 near, more builds); gravity's part
  // keeps a grain that starts to fall from making it again every dozen steps in a surface run
  // (docs/performance.md, seventy-third)
  const Real b_min = params_.skin / 200;
  const Real horizon = dt * (params_.skin_steps > 0 ? params_.skin_steps : 32);
  const Real fall = 0.5 * norm(params_.gravity) * horizon * horizon;
  const Real a_min = params_.skin / 2;  // (a grain allowed more is fast: its margin is that)
  std::vector<Real> margin(n);
  watch2_.resize(n);
  const bool built_here = x_at_build_.size() == n;
#pragma omp parallel for schedule(static) if (n >= kParallelMinGrains)
  for (std::size_t i = 0; i < n; ++i) {
    margin[i] = grains.state[i] != GrainState::Active ? 0
                : allow_[i] > a_min
                    ? allow_[i]
                    : std::min(allow_[i], std::max(b_min, norm(grains.v[i]) * horizon + fall));
    near2_[i] = margin[i] * margin[i];
    watch2_[i] = built_here ? watch_radius2(grains.x[i], margin[i], allow_[i], x_at_build_[i],
                                            domain_lo_, domain_hi_)
                            : -1;
  }
  pairs_.near.resize(pairs_.j.size());
  pairs_.near_count.assign(listed, 0);
  PairList& pl = pairs_;
#pragma omp parallel for schedule(static) if (n >= kParallelMinGrains)
  for (std::size_t i = 0; i < listed; ++i) {
    std::uint32_t k = pl.start[i];
    for (std::uint32_t s = pl.start[i]; s < pl.start[i + 1]; ++s) {
      const std::uint32_t j = pl.j[s];
      const Real reach = grains.r[i] + grains.r[j] + margin[i] + margin[j];
      if (norm2(grains.x[i] - grains.x[j]) < reach * reach) {
        pl.near[k++] = s;
      } else if (pl.touch[s]) {  // apart now: the sweep would end the contact in this step
        rolling_ ? forget_contact<true>(pl, s) : forget_contact<false>(pl, s);
      }
    }
    pl.near_count[i] = k - pl.start[i];
  }
  need_near_ = false;
  ++counters_.near_builds;
}

void DemSolver::apply(std::span<const StateChange> changes) {
  for (const StateChange& c : changes) {
    // (only a grain woken into the interface leaves the kept allowances as they are)
    if (c.from != GrainState::Static || c.to == GrainState::Active) kept_ids_.clear();
    if (c.from == GrainState::Static) forget_history(c.id);  // woken: no history
    if (c.to == GrainState::Static)
      need_rebuild_ = true;  // asleep: it leaves the lists
    else if (c.from != GrainState::Active)
      release(c.id);  // woken or dislodged
  }
}

void DemSolver::advance(Grains& grains, const Geometry& geometry, Real dt) {
  // Lists stay valid while every grain stays within its allowance.
  const int left =
      rolling_ ? sweep<true>(grains, geometry, dt) : sweep<false>(grains, geometry, dt);
  if (left & kLeftAllowance) need_rebuild_ = true;
  kept_ids_.clear();  // (the grains moved)
  if (left & kLeftNearMargin) need_near_ = true;
  maybe_outside_ = (left & kLeftDomain) != 0;
  // (assertions) the lists are the grains' (added or removed ones rebuild them)
  SANDFLOW_ASSERT(x_at_build_.size() == grains.size(),
                  "grains were added or removed without a rebuild");
}

void DemSolver::set_boundary(BoundaryParticles boundary) {
  boundary_ = std::move(boundary);
  boundary_params_.clear();
  for (std::size_t k = 0; k < boundary_.friction.size(); ++k) {
    ContactParams p = params_.contact;
    p.mu = boundary_.friction[k];
    p.mu_r = boundary_.rolling_friction[k];
    p.mu_tw = boundary_.twisting_friction[k];
    boundary_params_.push_back(p);
  }
  boundary_grid_.build(boundary_.x, 2 * boundary_.radius);
  need_rebuild_ = true;
}

void DemSolver::contacts_of(const Grains& grains, const Geometry& geometry,
                            std::vector<std::uint8_t>& out) const {
  out.assign(grains.size(), 0);
  const std::size_t n = std::min(grains.size(), pairs_.start.empty() ? 0 : pairs_.start.size() - 1);
  std::vector<std::uint8_t> touching(out.size(), 0);  // grain contacts, up to kSeatContacts
  // each thread flags and counts into its own copies, then the copies are joined grain by grain:
  // an or and a sum, so the result does not depend on the thread count
  std::vector<std::vector<std::uint8_t>> flags_of, counts_of;  // (a thread's copies)
#pragma omp parallel if (n >= kParallelMinGrains)
  {
#pragma omp single
    {
      flags_of.resize(static_cast<std::size_t>(omp_get_num_threads()));
      counts_of.resize(flags_of.size());
    }
    std::vector<std::uint8_t> mine(out.size(), 0), count(out.size(), 0);
    auto add = [&](std::size_t k) { count[k] += count[k] < kSeatContacts; };
#pragma omp for schedule(static) nowait
    for (std::size_t i = 0; i < n; ++i) {
      for (std::uint32_t s = pairs_.start[i]; s < pairs_.start[i + 1]; ++s) {
        const std::uint32_t j = pairs_.j[s];
        // listed pairs are within reach of the skin: a frozen grain that an active one may
        // touch before the next rebuild must keep pushing
        if (grains.state[j] == GrainState::Active) mine[i] |= kNearActive;
        if (grains.state[i] == GrainState::Active) mine[j] |= kNearActive;
        if (!pairs_.touch[s]) continue;
        const std::uint8_t slips = pairs_.touch[s] & kSlipping ? kSlips : 0;
        mine[i] |= kTouches | slips | (grains.state[j] == GrainState::Active ? kTouchesActive : 0);
        mine[j] |= kTouches | slips | (grains.state[i] == GrainState::Active ? kTouchesActive : 0);
        add(i);
        add(j);
      }
    }
    flags_of[static_cast<std::size_t>(omp_get_thread_num())] = std::move(mine);
    counts_of[static_cast<std::size_t>(omp_get_thread_num())] = std::move(count);
#pragma omp barrier
#pragma omp for schedule(static)
    for (std::size_t i = 0; i < out.size(); ++i) {
      int c = 0;
      for (std::size_t t = 0; t < flags_of.size(); ++t) {
        out[i] |= flags_of[t][i];
        c += counts_of[t][i];
      }
      touching[i] = static_cast<std::uint8_t>(std::min<int>(c, kSeatContacts));
    }
    // the geometry: a grain touching it is seated (a plane, a wall's face, a mesh's particles)
#pragma omp for schedule(static)
    for (std::size_t i = 0; i < n; ++i) {
      if (touching[i] >= kSeatContacts) {
        out[i] |= kSeated;
        continue;
      }
      bool wall = false;
      for (std::uint32_t s = walls_.start.size() > i + 1 ? walls_.start[i] : 0;
           !wall && walls_.start.size() > i + 1 && s < walls_.start[i + 1]; ++s)
        wall = geometry.obstacles()[walls_.obstacle[s]].solid->closest(grains.x[i]).distance <
               grains.r[i];
      const Real reach = grains.r[i] + boundary_.radius;
      for (std::uint32_t s = bounds_.start.size() > i + 1 ? bounds_.start[i] : 0;
           !wall && bounds_.start.size() > i + 1 && s < bounds_.start[i + 1]; ++s)
        wall = norm2(grains.x[i] - boundary_.x[bounds_.obstacle[s]]) < reach * reach;
      if (wall) out[i] |= kTouches | kSeated;
    }
  }
}

std::vector<std::uint32_t> cell_order(const Grains& grains, Real skin) {
  // Row-major cell order keeps neighbours close in memory. The threads' ranges of the sweep are
  // contiguous in this order, so they are slabs across its outermost axis, and the pairs that
  // cross between two ranges lie in the face between two slabs: the outermost axis is the one
  // the grains spread furthest along. A pour settled into a box ten grains deep, split across z
  // (the order before), had 10 % of its pairs crossing, and 1 % split across x.
  const std::size_t n = grains.size();
  if (n == 0) return {};
  Vec3 lo = grains.x[0], sum{}, sum2{};
  Real r_max = 0;
  for (std::size_t i = 0; i < n; ++i) {
    lo = min(lo, grains.x[i]);
    r_max = std::max(r_max, grains.r[i]);
    const Vec3 p = grains.x[i] - grains.x[0];  // (about the first grain: no cancellation)
    sum += p;
    sum2 += Vec3{p.x * p.x, p.y * p.y, p.z * p.z};
  }
  // the spread along each axis (its variance, times n), which a few far grains or a stream
  // above a heap barely move
  const Vec3 spread =
      sum2 - Vec3{sum.x * sum.x, sum.y * sum.y, sum.z * sum.z} * (1.0 / static_cast<Real>(n));
  std::array<int, 3> axes{0, 1, 2};  // outermost first
  std::stable_sort(axes.begin(), axes.end(), [&](int a, int b) { return spread[a] > spread[b]; });
  const Real inv = 1.0 / (2 * r_max + skin);
  auto c = [&](const Vec3& p, int axis) {
    return static_cast<std::uint64_t>(std::min((p[axis] - lo[axis]) * inv, 2097151.0));
  };
  std::vector<std::uint64_t> key(n);
  for (std::size_t i = 0; i < n; ++i)
    key[i] =
        c(grains.x[i], axes[0]) << 42 | c(grains.x[i], axes[1]) << 21 | c(grains.x[i], axes[2]);
  std::vector<std::uint32_t> perm(n);
  std::iota(perm.begin(), perm.end(), 0u);
  std::stable_sort(perm.begin(), perm.end(), [&](auto a, auto b) { return key[a] < key[b]; });
  return perm;
}

Real watch_radius2(const Vec3& x, Real margin, Real allow, const Vec3& x_at_build, const Vec3& lo,
                   const Vec3& hi) {
  const Vec3 to_lo = x - lo, to_hi = hi - x;
  const Real to_wall = std::min({to_lo.x, to_lo.y, to_lo.z, to_hi.x, to_hi.y, to_hi.z});
  const Real size = std::max({std::abs(x.x), std::abs(x.y), std::abs(x.z), 1.0});
  // (the margin is within the allowance, for most grains with room to spare: no square root)
  const Real moved2 = norm2(x - x_at_build), spare = allow - margin;
  const Real to_allowance =
      spare >= 0 && moved2 <= spare * spare ? margin : allow - std::sqrt(moved2);
  const Real watch = std::min({margin, to_allowance, to_wall}) * (1 - 1e-9) - 1e-15 * size;
  return watch > 0 ? watch * watch : -1;  // (a position that is not finite fails the test anyway)
}

void DemSolver::sort_by_cell(Grains& grains) {
  if (grains.size() > 0) grains.permute(cell_order(grains, params_.skin));
}

void DemSolver::set_wall_params(const Geometry& geometry) {
  wall_params_.clear();
  for (const Obstacle& o : geometry.obstacles()) {
    ContactParams w = params_.contact;
    w.mu = o.friction;
    w.mu_r = o.rolling_friction;
    w.mu_tw = o.twisting_friction;
    wall_params_.push_back(w);
  }
}

DemState DemSolver::save_state() const {
  DemState s;
  s.pairs.start = pairs_.start;
  s.pairs.j = pairs_.j;
  s.pairs.touch = pairs_.touch;
  s.pairs.delta0 = pairs_.delta0;
  s.pairs.c_n = pairs_.c_n;
  s.pairs.xi = pairs_.xi;
  s.pairs.psi = pairs_.psi;
  s.walls = walls_;
  s.bounds = bounds_;
  s.slot_of_id = slot_of_id_;
  s.x_at_build = x_at_build_;
  s.allow = allow_;
  s.need_rebuild = need_rebuild_;
  s.rebuild_count = rebuild_count_;
  return s;
}

void DemSolver::restore_state(DemState s, const Geometry& geometry) {
  const std::size_t slots = s.pairs.j.size(), n = s.allow.size();
  pairs_ = std::move(s.pairs);
  // per-step results and accumulators: written before they are read, sized as a rebuild does
  pairs_.force.resize(slots);
  pairs_.q.resize(slots);
  pairs_.t_roll.resize(rolling_ ? slots : 0);
  walls_ = std::move(s.walls);
  bounds_ = std::move(s.bounds);
  slot_of_id_ = std::move(s.slot_of_id);
  ids_at_build_.clear();
  for (GrainId id = 0; id < slot_of_id_.size(); ++id)
    if (slot_of_id_[id] != kNoSlot) ids_at_build_.push_back(id);
  x_at_build_ = std::move(s.x_at_build);
  allow_ = std::move(s.allow);
  allow2_.resize(n);
  for (std::size_t i = 0; i < n; ++i) allow2_[i] = allow_[i] * allow_[i];
  acc_f_.assign(n, Vec3{});
  acc_q_.assign(n, Vec3{});
  acc_t_.assign(rolling_ ? n : 0, Vec3{});
  need_rebuild_ = s.need_rebuild;
  need_near_ = true;
  maybe_outside_ = true;  // (no sweep has looked at the restored grains)
  rebuild_count_ = s.rebuild_count;
  ranges_stale_ = true;
  set_wall_params(geometry);
}

DeepestOverlap DemSolver::deepest_overlap(const Grains& grains, const Geometry& geometry) const {
  DeepestOverlap d;
  const std::size_t n = std::min(grains.size(), pairs_.start.empty() ? 0 : pairs_.start.size() - 1);
  auto consider = [&](DeepestOverlap::Kind kind, Real rel, std::size_t i, std::uint32_t other) {
    if (rel > d.rel) d = {kind, rel, static_cast<std::uint32_t>(i), other};
  };
  for (std::size_t i = 0; i < n; ++i) {
    for (std::uint32_t s = pairs_.start[i]; s < pairs_.start[i + 1]; ++s) {
      const std::uint32_t j = pairs_.j[s];
      if (j >= grains.size() || (grains.state[i] != GrainState::Active &&
                                 grains.state[j] != GrainState::Active))
        continue;  // (as in the sweep: two frozen grains do not interact)
      const Real delta = grains.r[i] + grains.r[j] - norm(grains.x[i] - grains.x[j]);
      consider(DeepestOverlap::kGrain, delta / (2 * std::min(grains.r[i], grains.r[j])), i, j);
    }
    if (grains.state[i] != GrainState::Active) continue;  // a frozen grain feels no wall
    if (walls_.start.size() > i + 1)
      for (std::uint32_t s = walls_.start[i]; s < walls_.start[i + 1]; ++s) {
        const std::uint32_t k = walls_.obstacle[s];
        const Real delta = grains.r[i] - geometry.obstacles()[k].solid->closest(grains.x[i]).distance;
        consider(DeepestOverlap::kWall, delta / (2 * grains.r[i]), i, k);
      }
    if (bounds_.start.size() > i + 1)
      for (std::uint32_t s = bounds_.start[i]; s < bounds_.start[i + 1]; ++s) {
        const std::uint32_t b = bounds_.obstacle[s];
        const Real delta = grains.r[i] + boundary_.radius - norm(grains.x[i] - boundary_.x[b]);
        consider(DeepestOverlap::kBoundary, delta / (2 * grains.r[i]), i, b);
      }
  }
  return d;
}

void DemSolver::rebuild(Grains& grains, const Geometry& geometry, Real dt) {
  const std::size_t n = grains.size();
  const auto& cp = params_.contact;
  if (wall_params_.size() != geometry.size()) set_wall_params(geometry);
  if (params_.sort_every > 0 && rebuild_count_ % params_.sort_every == 0) sort_by_cell(grains);
  ++rebuild_count_;
  ++counters_.rebuilds;

  // allowances; a frozen grain has none, so its pairs reach only as far as the active partner
  // may go and it searches for none itself
  if (kept_allowances_hold(grains)) {
    allow_.swap(kept_allow_);
    allow_.resize(n, 0.0);  // (the frozen grains appended since)
  } else {
    allowances(grains, dt, allow_);
  }
  kept_allow_.clear();
  kept_ids_.clear();
  // (assertions) the kept allowances are those the rebuild would compute, bit for bit (a grain
  // with a non-finite speed has a NaN allowance, which equals nothing)
  if constexpr (kAssertions) {
    std::vector<Real> fresh;
    allowances(grains, dt, fresh);
    const auto same_bits = [](Real a, Real b) {
      return std::bit_cast<std::uint64_t>(a) == std::bit_cast<std::uint64_t>(b);
    };
    SANDFLOW_ASSERT(std::equal(fresh.begin(), fresh.end(), allow_.begin(), allow_.end(), same_bits),
                    "the kept allowances are not the rebuild's");
  }
  allow2_.resize(n);
  for (std::size_t i = 0; i < n; ++i) allow2_[i] = allow_[i] * allow_[i];

  std::swap(pairs_, old_pairs_);
  std::swap(walls_, old_walls_);
  std::swap(bounds_, old_bounds_);
  build_pair_list(grains, allow_, rolling_, grids_, old_pairs_, slot_of_id_, pairs_);
  // (assertions) the grid found every pair the brute-force reference finds, in small runs
  if constexpr (kAssertions) {
    if (n <= kPairCheckMaxGrains) {
      const std::string fault = pair_list_error(grains, allow_, pairs_);
      SANDFLOW_ASSERT(fault.empty(), "the pair list after a rebuild: " + fault);
    }
  }
  // the normal damping of a pair depends on its masses only: computed once per list
#pragma omp parallel for schedule(static) if (n >= kParallelMinGrains)
  for (std::size_t i = 0; i < n; ++i)
    for (std::uint32_t s = pairs_.start[i]; s < pairs_.start[i + 1]; ++s) {
      const std::uint32_t j = pairs_.j[s];
      pairs_.c_n[s] = normal_damping(cp, grains.m[i] * grains.m[j] / (grains.m[i] + grains.m[j]));
    }

  // the candidates of the geometry, beside the pairs: obstacles and boundary particles within
  // reach
  build_wall_list(grains, allow_, geometry, old_walls_, slot_of_id_, walls_);
  build_boundary_list(grains, allow_, boundary_.x, boundary_.radius, boundary_grid_, old_bounds_,
                      slot_of_id_, bounds_);
  if (!released_.empty()) open_released_contacts(grains, dt);

  // remember where each id was, for the next carry-over. The table is as long as the largest id,
  // which in surface mode is a bed's millions of static grains: only the entries of the last
  // rebuild's grains are cleared, so that a rebuild costs what the simulated grains cost
  GrainId max_id = 0;
  for (GrainId id : grains.id) max_id = std::max(max_id, id);
  for (GrainId id : ids_at_build_)
    if (id < slot_of_id_.size()) slot_of_id_[id] = kNoSlot;
  slot_of_id_.resize(n ? max_id + 1 : 0, kNoSlot);
  for (std::size_t i = 0; i < n; ++i) slot_of_id_[grains.id[i]] = static_cast<std::uint32_t>(i);
  ids_at_build_ = grains.id;
  x_at_build_ = grains.x;
  // accumulators are zero between steps; only their size follows the grains
  acc_f_.resize(n);
  acc_q_.resize(n);
  acc_t_.resize(rolling_ ? n : 0);
  need_rebuild_ = false;
  need_near_ = true;
  ranges_stale_ = true;
}

const std::vector<Real>& DemSolver::allowances_for_rebuild(const Grains& grains, Real dt) {
  allowances(grains, dt, kept_allow_);
  kept_ids_ = grains.id;
  return kept_allow_;
}

bool DemSolver::kept_allowances_hold(const Grains& grains) const {
  const std::size_t kept = kept_ids_.size(), n = grains.size();
  if (kept == 0 || kept > n || !std::equal(kept_ids_.begin(), kept_ids_.end(), grains.id.begin()))
    return false;
  for (std::size_t i = kept; i < n; ++i)
    if (grains.state[i] == GrainState::Active) return false;
  return true;
}

void DemSolver::allowances(const Grains& grains, Real dt, std::vector<Real>& out) const {
  const std::size_t n = grains.size();
  const Real horizon = dt * params_.skin_steps;
  const Real a_min = params_.skin / 2;
  const Real a_max = std::max(a_min, params_.skin_max);
  // squared speeds: each ACTIVE grain's own, then raised to that of a faster partner that can
  // reach it within the horizon. Squares of non-negative doubles order as their bit patterns, so
  // the partners' maxima are atomic integer maxima: the same for any thread count and order.
  std::vector<std::uint64_t> speed2(n, 0);
  std::vector<Real> own2(n, 0);
#pragma omp parallel for schedule(static) if (n >= kParallelMinGrains)
  for (std::size_t i = 0; i < n; ++i)
    if (grains.state[i] == GrainState::Active) {
      own2[i] = norm2(grains.v[i]);
      speed2[i] = std::bit_cast<std::uint64_t>(own2[i]);
    }
  const std::size_t listed = pairs_.start.empty() ? 0 : pairs_.start.size() - 1;
  if (horizon > 0 && listed > 0) {
    // a partner faster than this would get more than a_min of its own: slower ones change nothing
    const Real fast2 = (a_min / horizon) * (a_min / horizon);
    std::vector<std::uint32_t> now(listed, kNoSlot);  // slot at the last rebuild -> index now
#pragma omp parallel for schedule(static) if (n >= kParallelMinGrains)
    for (std::size_t i = 0; i < n; ++i) {  // (ids are unique: each slot is written once)
      const GrainId id = grains.id[i];
      const std::uint32_t o = id < slot_of_id_.size() ? slot_of_id_[id] : kNoSlot;
      if (o < listed) now[o] = static_cast<std::uint32_t>(i);
    }
    auto raise = [&](std::uint32_t k, Real v2) {
      std::atomic_ref<std::uint64_t> a(speed2[k]);
      const std::uint64_t b = std::bit_cast<std::uint64_t>(v2);
      std::uint64_t cur = a.load(std::memory_order_relaxed);
      while (cur < b && !a.compare_exchange_weak(cur, b, std::memory_order_relaxed)) {
      }
    };
#pragma omp parallel for schedule(static) if (n >= kParallelMinGrains)
    for (std::size_t o = 0; o < listed; ++o) {
      const std::uint32_t i = now[o];
      if (i == kNoSlot) continue;
      for (std::uint32_t s = pairs_.start[o]; s < pairs_.start[o + 1]; ++s) {
        const std::uint32_t j = now[pairs_.j[s]];
        if (j == kNoSlot || (own2[i] <= fast2 && own2[j] <= fast2)) continue;
        const Real gap = norm(grains.x[i] - grains.x[j]) - grains.r[i] - grains.r[j];
        if (gap >= (std::sqrt(own2[i]) + std::sqrt(own2[j])) * horizon) continue;
        if (own2[j] > own2[i] && grains.state[i] == GrainState::Active)
          raise(i, own2[j]);
        else if (own2[i] > own2[j] && grains.state[j] == GrainState::Active)
          raise(j, own2[i]);
      }
    }
  }
  out.resize(n);
#pragma omp parallel for schedule(static) if (n >= kParallelMinGrains)
  for (std::size_t i = 0; i < n; ++i)
    out[i] = grains.state[i] != GrainState::Active
                 ? 0
                 : std::clamp(std::sqrt(std::bit_cast<Real>(speed2[i])) * horizon, a_min, a_max);
}

void DemSolver::open_released_contacts(const Grains& grains, Real dt) {
  GrainId max_id = 0;
  for (GrainId id : released_) max_id = std::max(max_id, id);
  std::vector<std::uint8_t> by_id(static_cast<std::size_t>(max_id) + 1, 0);
  for (GrainId id : released_) by_id[id] = 1;
  released_.clear();
  auto released = [&](std::size_t i) { return grains.id[i] <= max_id && by_id[grains.id[i]]; };
  // frozen before the change: frozen now (trapped, or woken), or released from it (dislodged)
  auto was_frozen = [&](std::size_t i) {
    return grains.state[i] != GrainState::Active || released(i);
  };
  const ContactParams& cp = params_.contact;
  const std::size_t n = grains.size();
  // per row, then the rows in order: the totals do not depend on the thread count
  std::vector<Real> row_preloaded(n, 0.0), row_added(n, 0.0);
#pragma omp parallel for schedule(static) if (n >= kParallelMinGrains)
  for (std::size_t i = 0; i < n; ++i)
    for (std::uint32_t s = pairs_.start[i]; s < pairs_.start[i + 1]; ++s) {
      const std::uint32_t j = pairs_.j[s];
      // (a contact carried over already acts: the change adds nothing to it)
      if (pairs_.touch[s] || (!released(i) && !released(j))) continue;
      const Real delta = grains.r[i] + grains.r[j] - norm(grains.x[i] - grains.x[j]);
      if (delta <= 0) continue;
      const Real energy = elastic_energy(cp, delta, {});
      // a contact opened within what the grains close in one step began during that step, as
      // every contact of the DEM begins: the check before the rebuild runs one step late
      const Real onset = norm(grains.v[i] - grains.v[j]) * dt;
      if (!(was_frozen(i) && was_frozen(j)) && delta <= onset) continue;
      if (was_frozen(i) && was_frozen(j)) {
        pairs_.touch[s] = kTouching | kPreloaded;
        pairs_.delta0[s] = delta;
        row_preloaded[i] += energy;
      } else {
        row_added[i] += energy;
      }
    }
  for (std::size_t i = 0; i < n; ++i) {
    counters_.energy_preloaded += row_preloaded[i];
    counters_.energy_released += row_added[i];
    counters_.energy_inside += row_added[i];
  }
}

void DemSolver::balance_ranges(const Grains& grains, std::size_t threads) {
  // the work of a grain: its pair slots, and its integration (walls included) when it moves;
  // split by grain count, the later ranges (the stream, the top of the pile: more active
  // grains) kept the other threads waiting at the barrier
  const std::size_t n = grains.size();
  constexpr std::uint64_t kMoveCost = 6;  // in pair slots (perf of a 100,000-grain floor)
  auto work = [&](std::size_t i) {
    return pairs_.start[i + 1] - pairs_.start[i] +
           (grains.state[i] == GrainState::Active ? kMoveCost : 0);
  };
  // The estimate is not the time: on a 100,000-grain floor the first range took 1.5-2.4 times as
  // long as the second on an even split. Each thread's share follows its measured speed (work
  // per second), halfway at each split so that one noisy period does not swing it.
  if (share_.size() != threads) {
    share_.assign(threads, 1.0 / static_cast<double>(threads));
    busy_.assign(threads, 0.0);
  } else if (*std::min_element(busy_.begin(), busy_.end()) > 0) {
    std::vector<double> speed(threads);
    for (std::size_t t = 0; t < threads; ++t) speed[t] = share_[t] / busy_[t];
    const double sum = std::accumulate(speed.begin(), speed.end(), 0.0);
    for (std::size_t t = 0; t < threads; ++t)
      share_[t] = std::clamp(0.5 * share_[t] + 0.5 * speed[t] / sum, 0.2 / threads, 1.0);
    const double total_share = std::accumulate(share_.begin(), share_.end(), 0.0);
    for (double& s : share_) s /= total_share;
  }
  std::fill(busy_.begin(), busy_.end(), 0.0);

  std::uint64_t total = 0;
  for (std::size_t i = 0; i < n; ++i) total += work(i);
  range_start_.assign(threads + 1, n);
  range_start_[0] = 0;
  std::uint64_t acc = 0;
  double target = share_[0] * static_cast<double>(total);
  std::size_t t = 1;
  for (std::size_t i = 0; i < n && t < threads; ++i) {
    acc += work(i);
    while (t < threads && static_cast<double>(acc) >= target) {
      range_start_[t] = i + 1;
      target += share_[t++] * static_cast<double>(total);
    }
  }
  // the rows whose pairs reach past their range's end
  cross_rows_.clear();
  for (std::size_t r = 0; r + 1 < threads; ++r)
    for (std::size_t i = range_start_[r]; i < range_start_[r + 1]; ++i)
      if (first_reaching(pairs_, i, range_start_[r + 1]) < pairs_.start[i + 1])
        cross_rows_.push_back(static_cast<std::uint32_t>(i));
  ranges_stale_ = false;
}

/// One thread's tallies, added into the sweep's reductions at its end. (Values of the thread's
/// own: references to the reduction variables were kept in memory across every pair's stores.)
struct SweepTally {
  std::int64_t contacts = 0;
  std::int64_t wall_contacts = 0;
  Real max_ov = 0;
  std::int64_t inert_fj = 0;    ///< in the springs of contacts going inert [fJ]
  std::int64_t relaxed_fj = 0;  ///< the work of preloads relaxing [fJ]
};

// The force pass and the integration are one sweep over the grains in storage order. Each pair
// (i, j), i < j, is computed once, from the state at the start of the step, when the sweep reaches
// i: its force goes to i's own sum and, reversed, to j's accumulator. Once i's own pairs are done,
// every pair that touches i has been computed (the others belong to grains below i) and nobody
// reads i's state again this step, so i is integrated on the spot, while its data are in cache.
//
// With T threads each takes a contiguous range of grains (of about equal work). The pairs that
// reach into a later range are computed first, shared among the threads, before anyone moves;
// each thread adds those of its grains' accumulators in grain order, and the rest wait in their
// slots until their grain's turn. Every grain therefore adds the same terms in the same
// order as a single thread would — its accumulator in ascending order of the other grain, its own
// pairs in slot order — and the state is bit-identical for any thread count.
//
// The sweep's kernels follow: the pairs (grain-grain), the fixed partners (walls, boundary
// particles, frozen grains), the integration and the thread partition. Each takes the arrays it
// needs and is inlined by force into the sweep's parallel region, so that the compiler sees the
// loops of one function. (GCC 12 stopped inlining the pair kernel as the sweep grew, which cost
// 11 % of a plain-DEM run: docs/performance.md, "The sweep's inlining".)
namespace {

/// The pair list's arrays as plain pointers, held in the thread's own copy of SweepData: read
/// through the PairList, each would be loaded again after every store of a contact's flags (a
/// byte store, which may alias anything).
struct Slots {
  const std::uint32_t* start;
  const std::uint32_t* j;
  const std::uint32_t* near;  ///< the near list (DemSolver::build_near)
  const std::uint32_t* near_count;
  std::uint8_t* touch;
  Real* delta0;
  const Real* c_n;
  Vec3* xi;
  Vec3* psi;
  Vec3* force;
  Vec3* q;
  Vec3* t_roll;
};

/// What the kernels share (sweep_data; each thread of a sweep builds its own copy): the law and
/// the step, the pair list with its history, the grains as plain arrays, their accumulators.
struct SweepData {
  const ContactParams& cp;
  PairList& pl;  ///< (for the rare paths; the sweep reads the arrays below)
  Slots slots;
  Vec3* x;
  Vec3* v;
  Vec3* w;
  const Real* r;
  const Real* m;
  const Real* inv_m;
  const Real* inv_I;
  const GrainState* st;
  const GrainId* id;  ///< (for the assertions' messages)
  /// per grain: the reversed pair results of this step that wait for its turn (acc_t: rolling)
  Vec3* acc_f;
  Vec3* acc_q;
  Vec3* acc_t;
  const Vec3* x_at_build;
  const Real* allow2;  ///< per grain: its allowance, squared [m^2]
  const Vec3* x_at_near;
  const Real* near2;   ///< per grain: its near margin, squared [m^2]
  const Real* watch2;  ///< per grain: DemSolver::watch2_ [m^2]
  Vec3 domain_lo, domain_hi;
  Vec3 gravity;
  Real dt;
  Real decay;  ///< what is left of a preload after one step
};

/// What never moves, as the sweep meets it: the obstacles and the boundary particles, each with
/// its candidate lists (and their history) and its laws.
struct FixedPartners {
  const Geometry& geometry;
  WallList& walls;
  const std::vector<ContactParams>& wall_params;  ///< per obstacle
  const std::vector<const HalfSpace*>& planes;    ///< per obstacle: the plane it is, or null
  WallList& bounds;
  const BoundaryParticles& boundary;
  const std::vector<ContactParams>& boundary_params;  ///< per group
  bool any_boundary;  ///< (most scenes have no boundary particles: their grains skip the loop)
};

/// The kernels' data for a step of dt: the grains' arrays, and the solver's pair list,
/// accumulators, positions at the last rebuild and squared allowances.
SweepData sweep_data(const DemParams& p, PairList& pairs, Grains& grains, std::vector<Vec3>& acc_f,
                     std::vector<Vec3>& acc_q, std::vector<Vec3>& acc_t,
                     const std::vector<Vec3>& x_at_build, const std::vector<Real>& allow2,
                     const std::vector<Vec3>& x_at_near, const std::vector<Real>& near2,
                     const std::vector<Real>& watch2, const Vec3& domain_lo, const Vec3& domain_hi,
                     Real dt) {
  return {.cp = p.contact,
          .pl = pairs,
          .slots = {.start = pairs.start.data(),
                    .j = pairs.j.data(),
                    .near = pairs.near.data(),
                    .near_count = pairs.near_count.data(),
                    .touch = pairs.touch.data(),
                    .delta0 = pairs.delta0.data(),
                    .c_n = pairs.c_n.data(),
                    .xi = pairs.xi.data(),
                    .psi = pairs.psi.data(),
                    .force = pairs.force.data(),
                    .q = pairs.q.data(),
                    .t_roll = pairs.t_roll.data()},
          .x = grains.x.data(),
          .v = grains.v.data(),
          .w = grains.w.data(),
          .r = grains.r.data(),
          .m = grains.m.data(),
          .inv_m = grains.inv_m.data(),
          .inv_I = grains.inv_I.data(),
          .st = grains.state.data(),
          .id = grains.id.data(),
          .acc_f = acc_f.data(),
          .acc_q = acc_q.data(),
          .acc_t = acc_t.data(),
          .x_at_build = x_at_build.data(),
          .allow2 = allow2.data(),
          .x_at_near = x_at_near.data(),
          .near2 = near2.data(),
          .watch2 = watch2.data(),
          .domain_lo = domain_lo,
          .domain_hi = domain_hi,
          .gravity = p.gravity,
          .dt = dt,
          .decay = p.preload_relax_time > 0 ? std::exp(-dt / p.preload_relax_time) : 1.0};
}

/// An energy in whole femtojoules. The sweep sums the energy of its transitions in integers:
/// integer sums do not depend on their order, so the totals are the same for any thread count
/// without keeping the terms to add them in slot order (keeping and sorting them was 3.5 % of a
/// surface run). Each term is rounded by at most half a femtojoule; an int64 holds 9,200 J, far
/// more than the springs of one step's contacts.
[[gnu::always_inline]] inline std::int64_t femtojoules(Real energy) {
  return static_cast<std::int64_t>(std::llround(energy * 1e15));
}

// --- fixed partners: walls, boundary particles, frozen grains --------------------------------

/// Grain i's state as its row of pairs reads it, loaded once for the row: the pairs' stores (to
/// the partners' accumulators, the histories) could alias the arrays, which would make the
/// compiler load i's state again for every pair.
struct RowGrain {
  Vec3 x, v, w;
  Real r, m;
  bool active;
};

[[gnu::always_inline]] inline RowGrain row_grain(const SweepData& d, std::size_t i) {
  return {d.x[i], d.v[i], d.w[i], d.r[i], d.m[i], d.st[i] == GrainState::Active};
}

/// The normal damping of pair slot s: its own, or, when one grain is frozen, as against a wall.
/// A frozen partner does not recoil: damped as against a wall, the restitution of a bounce on the
/// interface is the material's, not that of a grain half the mass.
[[gnu::always_inline]] inline Real pair_damping(const SweepData& d, const RowGrain& gi,
                                                std::uint32_t j, std::uint32_t s) {
  const bool active_j = d.st[j] == GrainState::Active;
  return gi.active && active_j ? d.slots.c_n[s] : normal_damping(d.cp, gi.active ? gi.m : d.m[j]);
}

/// A contact of grain i with something that never moves (a wall, a boundary particle): i alone
/// feels it, into f and torque.
template <bool kRolling>
[[gnu::always_inline]] inline void touch_fixed(const SweepData& d, std::size_t i,
                                               const ContactParams& p, const ContactGeometry& cg,
                                               Vec3& xi, Vec3& psi, Vec3& f, Vec3& torque,
                                               SweepTally& tally) {
  const Vec3* v = d.v;
  const Vec3* w = d.w;
  ContactHistory h{xi, psi};
  const ContactForce cf = contact_force<kRolling>(p, cg, v[i], w[i], Vec3{}, h, d.dt);
  SANDFLOW_ASSERT(!(tame(cg.n) && std::isfinite(cg.delta) && tame(v[i]) && tame(w[i]) && tame(xi) &&
                    (!kRolling || tame(psi))) ||
                      finite_result(cf, h, kRolling),
                  fmt::format("grain {}: the contact law gave a non-finite force or history "
                              "against the geometry from a finite state",
                              d.id[i]));
  xi = h.xi;
  psi = h.psi;
  f += cf.force_i;
  torque += cf.torque_i(cg);
  ++tally.wall_contacts;
  tally.max_ov = std::max(tally.max_ov, cg.delta / (2 * d.r[i]));
}

/// Grain i's contacts with the walls, then with the boundary particles, into f and torque.
template <bool kRolling>
[[gnu::always_inline]] inline void fixed_forces(const SweepData& d, const FixedPartners& fixed,
                                                std::size_t i, Vec3& f, Vec3& torque,
                                                SweepTally& tally) {
  const Vec3* x = d.x;
  const Real r_i = d.r[i];
  WallList& walls = fixed.walls;
  WallList& bounds = fixed.bounds;
  // walls: the same law, the obstacle an immovable body with no radius
  for (std::uint32_t s = walls.start[i]; s < walls.start[i + 1]; ++s) {
    const std::uint32_t k = walls.obstacle[s];
    // (a plane, the most common obstacle, inline: a call out of the sweep makes it save every
    // vector register it holds)
    const HalfSpace* plane = fixed.planes[k];
    const SurfacePoint sp =
        plane ? plane->closest(x[i]) : fixed.geometry.obstacles()[k].solid->closest(x[i]);
    const Real delta = r_i - sp.distance;
    if (delta <= 0) {
      walls.xi[s] = {};
      walls.psi[s] = {};
      continue;
    }
    const ContactParams& wp = fixed.wall_params[k];
    touch_fixed<kRolling>(d, i, wp, {sp.normal, delta, r_i, 0.0, normal_damping(wp, d.m[i]), r_i},
                          walls.xi[s], walls.psi[s], f, torque, tally);
  }
  // boundary particles: a grain that never moves, damped as against a wall
  if (!fixed.any_boundary) return;
  const Real rb = fixed.boundary.radius;
  for (std::uint32_t s = bounds.start[i]; s < bounds.start[i + 1]; ++s) {
    const Vec3 dx = x[i] - fixed.boundary.x[bounds.obstacle[s]];
    const Real dist2 = norm2(dx), rsum = r_i + rb;
    if (dist2 >= rsum * rsum) {
      bounds.xi[s] = {};
      bounds.psi[s] = {};
      continue;
    }
    const ContactParams& bp = fixed.boundary_params[fixed.boundary.group[bounds.obstacle[s]]];
    const Real dist = std::sqrt(dist2);
    touch_fixed<kRolling>(
        d, i, bp,
        {dx * (1.0 / dist), rsum - dist, r_i, rb, normal_damping(bp, d.m[i]), r_i * rb / rsum},
        bounds.xi[s], bounds.psi[s], f, torque, tally);
  }
}

// --- pairs: grain-grain ----------------------------------------------------------------------

/// Pair slot s, whose grains are apart (centres sqrt(dist2) apart) or both frozen: the contact
/// and its memory are gone (written only when it just ended); between two frozen grains it goes
/// inert, and the energy in its springs leaves with it.
template <bool kRolling>
[[gnu::always_inline]] inline void end_contact(const SweepData& d, std::uint32_t s, Real rsum,
                                               Real dist2, SweepTally& tally) {
  const Slots& pl = d.slots;
  if (!pl.touch[s]) return;
  if (dist2 < rsum * rsum) [[unlikely]]
    tally.inert_fj += femtojoules(inert_energy(d.cp, d.pl, s, rsum, dist2, kRolling));
  forget_contact<kRolling>(pl, s);
}

/// One pair slot of grain i: the contact law (true, with the results in cf) or the end of a
/// contact.
template <bool kRolling>
[[gnu::always_inline]] inline bool pair_force(const SweepData& d, const RowGrain& gi,
                                              [[maybe_unused]] std::size_t i, std::uint32_t s,
                                              ContactForce& cf, SweepTally& tally) {
  const ContactParams& cp = d.cp;
  const Slots& pl = d.slots;
  const std::uint32_t j = pl.j[s];
  const Vec3 dx = gi.x - d.x[j];
  const Real dist2 = norm2(dx);
  const Real r_j = d.r[j];
  const Real rsum = gi.r + r_j;
  if (dist2 >= rsum * rsum || (!gi.active && d.st[j] != GrainState::Active)) {
    end_contact<kRolling>(d, s, rsum, dist2, tally);
    return false;
  }
  // 1 / dist as dist / dist^2: the division runs beside the square root, not after it
  const Real dist = std::sqrt(dist2);
  const Real inv_dist2 = 1 / dist2;
  ContactGeometry g;
  g.n = dx * (dist * inv_dist2);
  g.delta = rsum - dist;
  g.arm_i = gi.r;
  g.arm_j = r_j;
  g.c_n = pair_damping(d, gi, j, s);
  g.r_eff = kRolling ? gi.r * r_j / rsum : 0.0;  // (a division the law without rolling skips)
  // relative overlap; the division only when it may be a new largest one
  const Real d_small = 2 * std::min(gi.r, r_j);
  if (g.delta > tally.max_ov * d_small) tally.max_ov = g.delta / d_small;
  if (pl.touch[s] & kPreloaded) [[unlikely]] {
    const Relaxed relaxed = relax_preload(cp.k_n, d.decay, pl.delta0[s], g.delta);
    g.delta = relaxed.delta;
    tally.relaxed_fj += femtojoules(relaxed.work);
  }
  ContactHistory h{pl.xi[s], kRolling ? pl.psi[s] : Vec3{}};
  const Vec3 v_j = d.v[j], w_j = d.w[j];
  cf = contact_force<kRolling>(cp, g, gi.v - v_j, gi.w, w_j, h, d.dt);
  SANDFLOW_ASSERT(!(dist > 0 && tame(dx) && tame(gi.v - v_j) && tame(gi.w) && tame(w_j) &&
                    tame(pl.xi[s]) && (!kRolling || tame(pl.psi[s]))) ||
                      finite_result(cf, h, kRolling),
                  fmt::format("grains {} and {}: the contact law gave a non-finite force or "
                              "history from a finite state",
                              d.id[i], d.id[j]));
  pl.touch[s] = (pl.touch[s] & kPreloaded) | kTouching | (cf.sliding ? kSlipping : 0);
  pl.xi[s] = h.xi;
  if constexpr (kRolling) pl.psi[s] = h.psi;
  ++tally.contacts;
  return true;
}

/// The reversed pair result, into the other grain's accumulator.
template <bool kRolling>
[[gnu::always_inline]] inline void scatter(const SweepData& d, std::uint32_t j,
                                           const ContactForce& cf) {
  d.acc_f[j] -= cf.force_i;
  d.acc_q[j] += cf.q;
  if constexpr (kRolling) d.acc_t[j] -= cf.t_roll;
}

/// Grain i's pair sums, into f, q and tr: its remaining pairs (computed here, their reverses
/// scattered), its waiting ones (from slot `split` on: those reaching past its range's end,
/// computed in the thread partition), then its accumulator, which is cleared. For a frozen grain,
/// which does not move, only its pairs' reverses.
template <bool kRolling>
[[gnu::always_inline]] inline void pair_sums(const SweepData& d, std::uint32_t split, std::size_t i,
                                             Vec3& f, Vec3& q, Vec3& tr, SweepTally& tally) {
  const Slots& pl = d.slots;
  // (a grain in flight has no near pair: its state is copied for the row only when there is one,
  // which took 19 of the 148 instructions a falling grain cost a step)
  if (const std::uint32_t count = pl.near_count[i]; count > 0) {
    const RowGrain gi = row_grain(d, i);
    const std::uint32_t* near = pl.near + pl.start[i];
    for (std::uint32_t k = 0; k < count && near[k] < split; ++k) {
      const std::uint32_t s = near[k];
      ContactForce cf;
      if (!pair_force<kRolling>(d, gi, i, s, cf, tally)) continue;
      f += cf.force_i;
      q += cf.q;
      if constexpr (kRolling) tr += cf.t_roll;
      // (a frozen grain does not move: nothing is added up for it, so its accumulator stays
      // zero, and a frozen row's sums end here: a surface run's rows are half frozen)
      const std::uint32_t j = pl.j[s];
      if (d.st[j] == GrainState::Active) scatter<kRolling>(d, j, cf);
    }
  }
  if (d.st[i] != GrainState::Active) return;
  for (std::uint32_t s = split; s < pl.start[i + 1]; ++s) {
    if (!pl.touch[s]) continue;
    f += pl.force[s];
    q += pl.q[s];
    if constexpr (kRolling) tr += pl.t_roll[s];
  }
  f += d.acc_f[i];
  q += d.acc_q[i];
  if constexpr (kRolling) tr += d.acc_t[i];
  // (one at a time: a chained assignment read the first back from memory for the second)
  store(d.acc_f[i], Vec3{});
  store(d.acc_q[i], Vec3{});
  if constexpr (kRolling) store(d.acc_t[i], Vec3{});
}

// --- integration -----------------------------------------------------------------------------

/// Grain i moves under force f and torque: symplectic Euler, velocities from the forces, then
/// positions from the new velocities. Returns what it has left (kLeftAllowance, kLeftNearMargin,
/// kLeftDomain: outside, or not finite, which a non-finite velocity makes the position too).
[[gnu::always_inline]] inline int integrate(const SweepData& d, std::size_t i, const Vec3& f,
                                            const Vec3& torque) {
  // (the new velocity and position are stored a coordinate at a time and read back from
  // registers: GCC copied them as whole vectors through the stack, or loaded v[i] as one pair of
  // doubles from three separate stores, which the processor cannot forward: a stall at every
  // grain; docs/performance.md)
  const Real dt = d.dt;
  const Vec3 v_new = d.v[i] + (f * d.inv_m[i] + d.gravity) * dt;
  const Vec3 x_new = d.x[i] + v_new * dt;
  store(d.v[i], v_new);
  d.w[i] += torque * (d.inv_I[i] * dt);
  store(d.x[i], x_new);
  // one test for the three limits (watch_radius2); NaN fails it
  const Real moved2 = norm2(x_new - d.x_at_near[i]);
  if (moved2 <= d.watch2[i]) [[likely]]
    return 0;
  return (norm2(x_new - d.x_at_build[i]) > d.allow2[i] ? kLeftAllowance : 0) |
         (moved2 > d.near2[i] ? kLeftNearMargin : 0) |
         (in_box(x_new, d.domain_lo, d.domain_hi) ? 0 : kLeftDomain);
}

// --- the thread partition --------------------------------------------------------------------

/// Phase 1 of the sweep, called by every thread of its parallel region (the `omp for` binds to
/// it); thread t's range is [range[t], range[t + 1]), the last one ending at n. The pairs that
/// reach into a later thread's range (in the rows `cross_rows`), from the state at the start of
/// the step, are computed into their slots by whichever thread is free: each slot's result
/// depends on its pair alone.
template <bool kRolling>
[[gnu::always_inline]] inline void cross_range_pairs(const SweepData& d,
                                                     const std::vector<std::size_t>& range,
                                                     const std::vector<std::uint32_t>& cross_rows,
                                                     SweepTally& tally) {
  const Slots& pl = d.slots;
#pragma omp for schedule(dynamic, 16)
  for (std::size_t k = 0; k < cross_rows.size(); ++k) {
    const std::uint32_t i = cross_rows[k];
    const std::size_t end_of_range =
        *std::upper_bound(range.begin(), range.end(), i);  // (i's range ends there)
    const RowGrain gi = row_grain(d, i);
    const std::uint32_t first = first_reaching(pl, i, end_of_range);
    const std::uint32_t* near = pl.near + pl.start[i];
    for (std::uint32_t m = 0, count = pl.near_count[i]; m < count; ++m) {
      const std::uint32_t s = near[m];
      if (s < first) continue;
      ContactForce cf;
      if (!pair_force<kRolling>(d, gi, i, s, cf, tally)) continue;
      pl.force[s] = cf.force_i;
      pl.q[s] = cf.q;
      if constexpr (kRolling) pl.t_roll[s] = cf.t_roll;
    }
  }
}

/// After phase 1 (and the barrier that ends it): the pairs of earlier ranges' rows that reach
/// into [lo, hi), into their grains' accumulators, in the order of the rows. Each row meets a
/// partner at most once, so every accumulator adds its terms in ascending order of the other
/// grain, as on one thread. Reads only what phase 1 wrote and the list: a per-grain array
/// written by either thread would pass its cache lines between the cores every step.
template <bool kRolling>
[[gnu::always_inline]] inline void take_cross_pairs(const SweepData& d,
                                                    const std::vector<std::uint32_t>& cross_rows,
                                                    std::size_t lo, std::size_t hi) {
  const Slots& pl = d.slots;
  for (std::size_t k = 0; k < cross_rows.size() && cross_rows[k] < lo; ++k) {
    const std::uint32_t i = cross_rows[k];
    for (std::uint32_t s = first_reaching(pl, i, lo); s < pl.start[i + 1]; ++s) {
      const std::uint32_t j = pl.j[s];
      if (!pl.touch[s] || j >= hi || d.st[j] != GrainState::Active) continue;
      d.acc_f[j] -= pl.force[s];
      d.acc_q[j] += pl.q[s];
      if constexpr (kRolling) d.acc_t[j] -= pl.t_roll[s];
    }
  }
}

}  // namespace

template <bool kRolling>
int DemSolver::sweep(Grains& grains, const Geometry& geometry, Real dt) {
  const std::size_t n = grains.size();
  std::int64_t contacts = 0, wall_contacts = 0;
  Real max_ov = counters_.max_overlap_rel;
  std::int64_t inert_fj = 0, relaxed_fj = 0;  // (femtojoules: see there)
  int moved_out = 0;  // what some grain left: kLeftAllowance, kLeftNearMargin, kLeftDomain
  const bool wide = use_avx512_;
  wall_planes_.resize(geometry.size());
  for (std::size_t k = 0; k < geometry.size(); ++k)
    wall_planes_[k] = dynamic_cast<const HalfSpace*>(geometry.obstacles()[k].solid.get());

#pragma omp parallel if (n >= kParallelMinGrains) \
    reduction(+ : contacts, wall_contacts, inert_fj, relaxed_fj) reduction(max : max_ov) reduction(| : moved_out)
  {
    SweepTally tally{.max_ov = max_ov};
    moved_out |= wide ? sweep_part_avx512<kRolling>(grains, geometry, dt, tally)
                      : sweep_part<kRolling>(grains, geometry, dt, tally);
    contacts += tally.contacts;
    wall_contacts += tally.wall_contacts;
    max_ov = std::max(max_ov, tally.max_ov);
    inert_fj += tally.inert_fj;
    relaxed_fj += tally.relaxed_fj;
  }
  counters_.contacts = contacts;
  counters_.wall_contacts = wall_contacts;
  counters_.max_overlap_rel = max_ov;
  counters_.energy_inert += static_cast<Real>(inert_fj) * 1e-15;
  counters_.energy_released += static_cast<Real>(relaxed_fj) * 1e-15;
  return moved_out;
}

template <bool kRolling>
[[gnu::always_inline]] inline int DemSolver::sweep_part(Grains& grains, const Geometry& geometry,
                                                        Real dt, SweepTally& tally) {
  const std::size_t n = grains.size();
  const std::size_t threads = static_cast<std::size_t>(omp_get_num_threads());
  const std::size_t t = static_cast<std::size_t>(omp_get_thread_num());
  // each thread's own copy: no store through the arrays can change it, so the compiler need
  // not load the pointers again after each store
  const SweepData data =
      sweep_data(params_, pairs_, grains, acc_f_, acc_q_, acc_t_, x_at_build_, allow2_, x_at_near_,
                 near2_, watch2_, domain_lo_, domain_hi_, dt);
  const FixedPartners fixed{geometry, walls_,    wall_params_,     wall_planes_,
                            bounds_,  boundary_, boundary_params_, boundary_.size() > 0};
  int moved_out = 0;

  // 1. the threads' ranges (cut again after a rebuild), and the pairs that reach into a later
  // thread's range
#pragma omp single
  if (ranges_stale_ || range_start_.size() != threads + 1 || range_start_.back() != n)
    balance_ranges(grains, threads);
  const std::size_t lo = range_start_[t], hi = range_start_[t + 1];
  cross_range_pairs<kRolling>(data, range_start_, cross_rows_, tally);

  // 2. the sweep: the pairs of phase 1 that reach into this range, then i's remaining pairs,
  // its waiting ones, and i moves (all of it timed: the thread's share follows its time)
  const double sweep_start = omp_get_wtime();
  take_cross_pairs<kRolling>(data, cross_rows_, lo, hi);
  // the next row with pairs past hi: only those rows need their split searched
  auto next_cross = std::lower_bound(cross_rows_.begin(), cross_rows_.end(), lo);
  for (std::size_t i = lo; i < hi; ++i) {
    std::uint32_t split = data.slots.start[i + 1];
    if (next_cross != cross_rows_.end() && *next_cross == i) [[unlikely]] {
      split = first_reaching(data.slots, i, hi);
      ++next_cross;
    }
    Vec3 f{}, q{}, tr{};
    pair_sums<kRolling>(data, split, i, f, q, tr, tally);
    if (data.st[i] != GrainState::Active) continue;
    Vec3 torque = tr + q * (-data.r[i]);
    fixed_forces<kRolling>(data, fixed, i, f, torque, tally);
    moved_out |= integrate(data, i, f, torque);
  }
  busy_[t] += omp_get_wtime() - sweep_start;
  return moved_out;
}

// The same code compiled for AVX-512 (chosen at run time, DemSolver::use_avx512): its 32 vector
// registers hold the row's grain and sums that the 16 of x86-64 spill to the stack: 8 % off the
// sweep of a pour (docs/performance.md, eighty-fifth). The same operations in the same order and
// no fused multiply-add (-ffp-contract=off): the results are bit for bit those of x86-64.
template <bool kRolling>
[[gnu::target("avx512f")]] int DemSolver::sweep_part_avx512(Grains& grains,
                                                            const Geometry& geometry, Real dt,
                                                            SweepTally& tally) {
  return sweep_part<kRolling>(grains, geometry, dt, tally);
}

}  // namespace sandflow
