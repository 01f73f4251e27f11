#include "surface/interface_layer.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

#include <omp.h>

#include "dem/neighbor_list.hpp"  // kParallelMinGrains

namespace sandflow {

namespace {

// Columns whose static top fell, from which the threads share the search for grains to wake: a
// parallel region costs some microseconds (3 on the AMD EPYC of docs/performance.md), the test of
// a column's grains a fraction of one, so fewer columns are not worth it.
constexpr std::size_t kParallelMinColumns = 64;

}  // namespace

Real vertical_band(Real thickness, Real theta) {
  return thickness / std::cos(std::min(std::abs(theta), deg_to_rad(60.0)));
}

StaticFrame static_frame(const HeightField& hf, Real z_lo, Real z_hi, Real r_lo, Real r_hi) {
  StaticFrame f;
  f.x0 = hf.params().x0;
  f.y0 = hf.params().y0;
  f.cell = hf.cell();
  f.nx = static_cast<std::uint32_t>(hf.nx());
  f.ny = static_cast<std::uint32_t>(hf.ny());
  f.z_lo = z_lo;
  f.z_hi = z_hi;
  f.r_lo = r_lo;
  f.r_hi = r_hi;
  return f;
}

const std::vector<Real>& InterfaceLayer::static_tops(const HeightField& hf,
                                                     const StaticStore& st) {
  if (tops_follow(st) && tops_.size() == hf.columns() && tops_level_ == hf.level_revision())
    return tops_;
  tops_ = tops_L_ = hf.terrain();
  tops_level_ = hf.level_revision();
  tops_r_max_ = 0;
  tops_all_changed_ = true;
  tops_changed_.resize(hf.columns());
  // each thread takes its share of the columns into its own copy, then the copies are joined: a
  // maximum, so the result does not depend on the thread count
  const std::size_t n = st.size(), nc = st.columns();
#pragma omp parallel if (n >= kParallelMinGrains)
  {
    std::vector<Real> mine(tops_);
    Real r_max = 0;
#pragma omp for schedule(static) nowait
    for (std::size_t c = 0; c < nc; ++c)
      st.for_each_in_column(c, [&](const StaticGrain& g) {
        hf.for_each_ray_hit(
            g.x, g.r, [&](std::size_t cc, Real, Real top) { mine[cc] = std::max(mine[cc], top); });
        r_max = std::max(r_max, g.r);
      });
#pragma omp critical
    {
      for (std::size_t c = 0; c < tops_.size(); ++c) tops_[c] = std::max(tops_[c], mine[c]);
      tops_r_max_ = std::max(tops_r_max_, r_max);
    }
  }
  tops_of_ = n;
  return tops_;
}

const std::vector<std::uint32_t>* InterfaceLayer::take_changed_tops() {
  if (tops_all_changed_ || tops_changed_.columns() != tops_.size()) {
    tops_all_changed_ = false;
    tops_changed_.resize(tops_.size());
    return nullptr;
  }
  tops_changed_out_ = tops_changed_.list();
  tops_changed_.clear();
  return &tops_changed_out_;
}

void InterfaceLayer::recompute_tops(const HeightField& hf, const StaticStore& st,
                                    const ColumnSet& dirty) {
  // a grain filed in column c reaches the columns whose centres are closer than r + cell/2 to
  // its centre, which is within the column (or its margin): at most `reach` columns away
  const int nx = hf.nx(), ny = hf.ny();
  const int reach = static_cast<int>(
      std::ceil((tops_r_max_ + 0.5 * hf.cell()) / hf.cell() - 0.5 + StaticStore::kMargin));
  if (scan_.columns() != dirty.columns()) scan_.resize(dirty.columns());
  scan_.clear();
  for (std::uint32_t c : dirty.list()) {
    tops_[c] = tops_L_[c];
    if (!tops_all_changed_) tops_changed_.add(c);
    const int i = static_cast<int>(c % nx), j = static_cast<int>(c / nx);
    for (int jj = std::max(j - reach, 0); jj <= std::min(j + reach, ny - 1); ++jj)
      for (int ii = std::max(i - reach, 0); ii <= std::min(i + reach, nx - 1); ++ii)
        scan_.add(static_cast<std::uint32_t>(jj * nx + ii));
  }
  // (each thread lists the hits of its share of the columns scanned, then the tops take them: a
  // maximum, the same for any thread count; on one thread the scan was 0.5 % of a surface run's
  // wall time, docs/performance.md, ninety-seventh)
  const std::vector<std::uint32_t>& scan = scan_.list();
  std::vector<std::vector<std::pair<std::uint32_t, Real>>> found;
#pragma omp parallel if (scan.size() >= kParallelMinColumns)
  {
#pragma omp single
    found.resize(static_cast<std::size_t>(omp_get_num_threads()));
    std::vector<std::pair<std::uint32_t, Real>> mine;
#pragma omp for schedule(dynamic, 16) nowait
    for (std::size_t k = 0; k < scan.size(); ++k)
      st.for_each_in_column(scan[k], [&](const StaticGrain& g) {
        hf.for_each_ray_hit(g.x, g.r, [&](std::size_t cc, Real, Real top) {
          if (dirty.contains(cc) && top > tops_[cc]) mine.emplace_back(cc, top);
        });
      });
    found[static_cast<std::size_t>(omp_get_thread_num())] = std::move(mine);
  }
  for (const auto& list : found)
    for (const auto& [cc, top] : list) tops_[cc] = std::max(tops_[cc], top);
}

Transitions InterfaceLayer::transfer(const HeightField& hf, Grains& hot, StaticStore& st,
                                     const std::vector<std::uint8_t>& contacts, bool list_changes,
                                     const std::vector<std::uint32_t>* moved) {
  Transitions out;
  TransitionCounts& n = out.counts;
  std::vector<StateChange>& changes = out.changes;
  const Real T = p_.thickness;
  const Real m = p_.margin;

  // 1. the hot grains: trap, dislodge, sleep. Each grain's fate depends on its own state and the
  // height field only, so the threads decide them; the changes are made in grain order below, so
  // the stores, the change list and the energy's sum do not depend on the threads.
  const std::size_t nh = hot.size();
  fate_.resize(nh);
#pragma omp parallel for schedule(static) if (nh >= kParallelMinGrains)
  for (std::size_t i = 0; i < nh; ++i) {
    fate_[i] = Fate::Stays;
    // (between updates only traps: they keep the pair list)
    if (!list_changes && hot.state[i] != GrainState::Active) continue;
    const Vec3& x = hot.x[i];
    const std::int64_t c = hf.column_of(x.x, x.y);
    if (c < 0) continue;  // outside the grid a grain is always simulated
    if (x.z < hf.terrain()[static_cast<std::size_t>(c)]) {  // below the column's level
      if (hot.state[i] != GrainState::Active) fate_[i] = Fate::Freed;
      continue;
    }
    const Real h = hf.static_top_at(x.x, x.y);
    if (hot.state[i] == GrainState::Active) {
      // (a slow grain at the top of a bounce, or one sliding over the bed, stays free)
      if (x.z < h &&
          (held(p_.seat, hot, i, contacts[i]) ||
           (hf.closed(static_cast<std::size_t>(c)) && at_rest(p_.seat, hot, i, contacts[i]))))
        fate_[i] = Fate::Trapped;
    } else if (x.z > h + m) {
      fate_[i] = Fate::Dislodged;
    } else if ((x.z < h - vertical_band(T, hf.slope()[static_cast<std::size_t>(c)]) - m ||
                hf.closed(static_cast<std::size_t>(c))) &&
               !(contacts[i] & DemSolver::kNearActive)) {
      // (an active grain within reach would sink into it: static grains push nothing; in a
      // closed column no grain moves, and the invariant wakes what one comes near)
      fate_[i] = Fate::Sleeps;
    }
  }
  std::vector<std::uint32_t> keep;
  keep.reserve(nh);
  for (std::uint32_t i = 0; i < nh; ++i) {
    switch (fate_[i]) {
      case Fate::Stays:
        break;
      case Fate::Freed:  // below its column's level it moves on its own
        hot.state[i] = GrainState::Active;
        changes.push_back({hot.id[i], GrainState::Interface, GrainState::Active});
        ++n.dislodged;
        break;
      case Fate::Trapped:
        // frozen where it is; its contacts with other frozen grains go inert at the next step,
        // while those with active grains keep their springs, so that the grains resting on it do
        // not lose their friction
        n.energy_trapped += 0.5 * (hot.m[i] * norm2(hot.v[i]) + norm2(hot.w[i]) / hot.inv_I[i]);
        hot.state[i] = GrainState::Interface;
        hot.v[i] = hot.w[i] = {};
        changes.push_back({hot.id[i], GrainState::Active, GrainState::Interface});
        ++n.trapped;
        break;
      case Fate::Dislodged:
        hot.state[i] = GrainState::Active;
        hot.v[i] = hot.w[i] = {};
        // (its pairs with interface grains enter the list)
        changes.push_back({hot.id[i], GrainState::Interface, GrainState::Active});
        ++n.dislodged;
        break;
      case Fate::Sleeps: {
        const Vec3& x = hot.x[i];
        const auto c = static_cast<std::uint32_t>(hf.column_of(x.x, x.y));
        const bool follow = tops_follow(st);
        // the tops follow the grain as stored (within the store's bound of where it slept)
        const StaticGrain g = st.grain(st.add(hot.id[i], x, hot.r[i], c));
        if (follow) {
          hf.for_each_ray_hit(g.x, g.r, [&](std::size_t cc, Real, Real top) {
            set_top(cc, std::max(tops_[cc], top));
          });
          tops_r_max_ = std::max(tops_r_max_, g.r);
          ++tops_of_;
        }
        changes.push_back({hot.id[i], GrainState::Interface, GrainState::Static});
        ++n.slept;
        continue;
      }
    }
    keep.push_back(i);
  }
  if (keep.size() != hot.size()) hot.permute(keep);
  if (!list_changes) return out;

  // 2. the static grains where h fell (and around: h is interpolated between column centres)
  const std::size_t nc = hf.columns();
  const std::vector<Real>& h_now = hf.static_top();
  const std::vector<Real>& L_now = hf.terrain();
  // (only the columns whose h or L changed can have fallen or risen: `moved`)
  bool all = !moved;
  if (h_seen_.size() != nc || L_seen_.size() != nc) {
    h_seen_ = L_seen_ = L_now;
    all = true;
  }
  if (fell_.columns() != nc) fell_.resize(nc);
  fell_.clear();
  const int nx = hf.nx(), ny = hf.ny();
  auto look = [&](std::size_t c) {
    const bool woke = h_now[c] < h_seen_[c] || L_now[c] > L_seen_[c];
    h_seen_[c] = h_now[c];
    L_seen_[c] = L_now[c];
    if (!woke) return;
    const int i = static_cast<int>(c % nx), j = static_cast<int>(c / nx);
    for (int jj = std::max(j - 1, 0); jj <= std::min(j + 1, ny - 1); ++jj)
      for (int ii = std::max(i - 1, 0); ii <= std::min(i + 1, nx - 1); ++ii)
        fell_.add(static_cast<std::uint32_t>(jj * nx + ii));
  };
  if (all)
    for (std::size_t c = 0; c < nc; ++c) look(c);
  else
    for (std::uint32_t c : *moved) look(c);
  if (fell_.empty()) return out;

  // (each thread lists what it finds; wake() sorts the lists' union, as below)
  std::vector<std::uint32_t> flagged;
  const std::vector<std::uint32_t>& fell = fell_.list();
#pragma omp parallel if (fell.size() >= kParallelMinColumns)
  {
    std::vector<std::uint32_t> mine;
#pragma omp for schedule(dynamic, 32) nowait
    for (std::size_t w = 0; w < fell.size(); ++w) {
      const std::uint32_t c = fell[w];
      const Real band = vertical_band(T, hf.slope()[c]);
      st.for_each_in_column(c, [&](const StaticGrain& g) {
        if (g.x.z > hf.static_top_at(g.x.x, g.x.y) - band || g.x.z < L_now[c])
          mine.push_back(g.slot);
      });
    }
#pragma omp critical
    flagged.insert(flagged.end(), mine.begin(), mine.end());
  }
  n.woken = wake(hf, hot, st, std::move(flagged), changes, p_.blows);
  return out;
}

Transitions InterfaceLayer::wake_within_reach(const HeightField& hf, Grains& hot, StaticStore& st,
                                              const std::vector<Real>& allow) {
  Transitions out;
  if (st.size() == 0) return out;
  const std::size_t nh = hot.size();
  Real reach = 0;
  for (std::size_t i = 0; i < nh; ++i)
    if (hot.state[i] == GrainState::Active) reach = std::max(reach, hot.r[i] + allow[i]);
  reach_.prepare(hf, st, reach);
  // (each thread lists what it finds; wake() sorts the lists' union, so the set and its order do
  // not depend on the threads)
  std::vector<std::uint32_t> flagged;
#pragma omp parallel if (nh >= kParallelMinGrains)
  {
    std::vector<std::uint32_t> mine;
#pragma omp for schedule(dynamic, 512) nowait
    for (std::size_t i = 0; i < nh; ++i) {
      if (hot.state[i] != GrainState::Active) continue;
      reach_.for_each_within(hf, st, hot.x[i], hot.r[i] + allow[i],
                             [&](std::uint32_t k) { mine.push_back(k); });
    }
#pragma omp critical
    flagged.insert(flagged.end(), mine.begin(), mine.end());
  }
  out.counts.woken_by_reach = wake(hf, hot, st, std::move(flagged), out.changes, false);
  return out;
}

std::int64_t InterfaceLayer::wake(const HeightField& hf, Grains& hot, StaticStore& st,
                                  std::vector<std::uint32_t> slots,
                                  std::vector<StateChange>& changes, bool above_h_free) {
  if (slots.empty()) return 0;
  // in slot order, each once: the hot store receives them in an order the threads do not decide
  std::sort(slots.begin(), slots.end());
  slots.erase(std::unique(slots.begin(), slots.end()), slots.end());
  const std::size_t nc = hf.columns();
  // the tops of the columns the woken grains reached are computed again from the grains that stay
  const bool follow = tops_follow(st) && tops_.size() == nc;
  if (dirty_.columns() != nc) dirty_.resize(nc);
  dirty_.clear();
  for (std::uint32_t k : slots) {
    const StaticGrain g = st.grain(k);
    if (follow)  // (a column's top is one of its hits: only the highest one's leaving lowers it)
      hf.for_each_ray_hit(g.x, g.r, [&](std::size_t c, Real, Real top) {
        if (top >= tops_[c]) dirty_.add(static_cast<std::uint32_t>(c));
      });
    hot.add(g.id, g.x, Vec3{}, g.r, p_.density);
    // INTERFACE, the band under h, or ACTIVE above it where h fell past it: frozen there until the
    // next update, it would be a floor under a blow that has already opened the bed. (One below
    // its column's level moves on its own; transfer() makes it ACTIVE next time.)
    const bool free = above_h_free && g.x.z > hf.static_top_at(g.x.x, g.x.y) + p_.margin;
    hot.state.back() = free ? GrainState::Active : GrainState::Interface;
    changes.push_back({g.id, GrainState::Static, hot.state.back()});
  }
  st.remove(slots);
  if (follow) {
    tops_of_ = st.size();
    recompute_tops(hf, st, dirty_);
  }
  return static_cast<std::int64_t>(slots.size());
}

}  // namespace sandflow
