#include "dem/neighbor_list.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <omp.h>

#include <fmt/format.h>

namespace sandflow {

void CellGrid::build(const std::vector<Vec3>& x, Real min_cell) {
  const auto every = [](std::size_t k) { return static_cast<std::uint32_t>(k); };
  file(x, x.size(), every, min_cell);
}

void CellGrid::build(const std::vector<Vec3>& x, std::span<const std::uint32_t> which,
                     Real min_cell) {
  const auto only = [which](std::size_t k) { return which[k]; };
  file(x, which.size(), only, min_cell);
}

template <class Which>
void CellGrid::file(const std::vector<Vec3>& all, std::size_t n, Which which, Real min_cell) {
  // (x(k): the k-th grain filed)
  auto x = [&](std::size_t k) -> const Vec3& { return all[which(k)]; };
  // (a surface run's simulated grains are a shell over the heap and a stream above it: with 4
  // cells a grain allowed, 98 % of the 20,000-grain floor's rebuilds trimmed the box, on one
  // thread, a tenth of the neighbour stage: docs/performance.md, eightieth)
  const std::size_t max_cells = std::max<std::size_t>(4096, 32 * n);
  Vec3 lo{0, 0, 0}, hi{0, 0, 0};
  if (n > 0) {
    Real lx = x(0).x, ly = x(0).y, lz = x(0).z, hx = lx, hy = ly, hz = lz;
    // (minima and maxima: the same for any thread count)
    const bool many = n >= kParallelMinGrains;
#pragma omp parallel for reduction(min : lx, ly, lz) reduction(max : hx, hy, hz) if (many)
    for (std::size_t i = 0; i < n; ++i) {
      const Vec3& p = x(i);
      lx = std::min(lx, p.x), ly = std::min(ly, p.y), lz = std::min(lz, p.z);
      hx = std::max(hx, p.x), hy = std::max(hy, p.y), hz = std::max(hz, p.z);
    }
    lo = {lx, ly, lz}, hi = {hx, hy, hz};
  }
  auto cells_for = [&](const Vec3& l, const Vec3& h, Real c) {
    double cells = 1;
    for (int a = 0; a < 3; ++a) cells *= std::floor((h[a] - l[a]) / c) + 1;
    return cells;
  };
  if (n > 100 && cells_for(lo, hi, min_cell) > static_cast<double>(max_cells)) {
    // a few far-away grains: grid the central 99 % and clamp the rest into the border cells; if
    // that box still needs coarser cells, trim up to a tenth on each side (the frozen grains
    // along a large bed's walls, metres from the grains that move, would otherwise make every
    // cell centimetres wide, and each grain search hundreds of candidates)
    std::vector<Real> axis(n);
    for (const std::size_t per : {200, 50, 20, 10}) {
      for (int a = 0; a < 3; ++a) {
        for (std::size_t i = 0; i < n; ++i) axis[i] = x(i)[a];
        const std::size_t k_lo = n / per, k_hi = n - 1 - n / per;
        std::nth_element(axis.begin(), axis.begin() + k_lo, axis.end());
        lo[a] = axis[k_lo];
        std::nth_element(axis.begin(), axis.begin() + k_hi, axis.end());
        hi[a] = axis[k_hi];
      }
      if (cells_for(lo, hi, min_cell) <= static_cast<double>(max_cells)) break;
    }
  }
  // coarser cells when even that box needs too many
  cell_ = min_cell;
  const Vec3 ext = hi - lo;
  const double volume = (ext.x + min_cell) * (ext.y + min_cell) * (ext.z + min_cell);
  if (cells_for(lo, hi, cell_) > static_cast<double>(max_cells))
    cell_ = std::max(min_cell, std::cbrt(volume / static_cast<double>(max_cells)) * 1.01);
  inv_cell_ = 1.0 / cell_;
  lo_ = lo;
  for (int a = 0; a < 3; ++a)
    dims_[a] = std::max(1, static_cast<int>(std::floor(ext[a] * inv_cell_)) + 1);

  // counting sort of the grains by cell
  const std::size_t cells = static_cast<std::size_t>(dims_[0]) * dims_[1] * dims_[2];
  std::vector<std::uint32_t> c(n);
#pragma omp parallel for schedule(static) if (n >= kParallelMinGrains)
  for (std::size_t i = 0; i < n; ++i)
    c[i] = static_cast<std::uint32_t>(index(coord(x(i).x, 0), coord(x(i).y, 1), coord(x(i).z, 2)));
  // (the cells' counts cleared and summed by the threads, block by block: a surface run's grids
  // hold up to 32 cells a grain, and on one thread the two passes over them were 0.3 % of its
  // wall time, docs/performance.md, ninety-seventh)
  const bool many = n >= kParallelMinGrains;
  cell_start_.resize(cells + 1);
#pragma omp parallel for schedule(static) if (many)
  for (std::size_t k = 0; k <= cells; ++k) cell_start_[k] = 0;
  for (std::size_t i = 0; i < n; ++i) ++cell_start_[c[i] + 1];
  std::vector<std::uint32_t> block_sum;
#pragma omp parallel if (many)
  {
    const std::size_t threads = static_cast<std::size_t>(omp_get_num_threads());
    const std::size_t t = static_cast<std::size_t>(omp_get_thread_num());
#pragma omp single
    block_sum.assign(threads + 1, 0);
    const std::size_t k0 = 1 + cells * t / threads, k1 = 1 + cells * (t + 1) / threads;
    std::uint32_t sum = 0;
    for (std::size_t k = k0; k < k1; ++k) sum = cell_start_[k] += sum;
    block_sum[t + 1] = sum;
#pragma omp barrier
    std::uint32_t before = 0;
    for (std::size_t b = 0; b <= t; ++b) before += block_sum[b];
    if (before > 0)
      for (std::size_t k = k0; k < k1; ++k) cell_start_[k] += before;
  }
  items_.resize(n);
  std::vector<std::uint32_t> fill(cell_start_.begin(), cell_start_.end() - 1);
  place_.resize(all.size());
  for (std::size_t i = 0; i < n; ++i) {
    place_[which(i)] = fill[c[i]];
    items_[fill[c[i]]++] = which(i);
  }
}

namespace {

// Finds slot of (a, b) in the old list, a < b in old numbering; kNoSlot when absent.
std::uint32_t find_old_slot(const PairList& old, std::uint32_t a, std::uint32_t b) {
  for (std::uint32_t s = old.start[a]; s < old.start[a + 1]; ++s)
    if (old.j[s] == b) return s;
  return kNoSlot;
}

}  // namespace

void build_pair_list(const Grains& grains, Real skin, bool rolling, PairGrids& grids,
                     const PairList& old, const std::vector<std::uint32_t>& old_slot_of_id,
                     PairList& out) {
  build_pair_list(grains, std::vector<Real>(grains.size(), skin / 2), rolling, grids, old,
                  old_slot_of_id, out);
}

void build_pair_list(const Grains& grains, const std::vector<Real>& allow, bool rolling,
                     PairGrids& grids, const PairList& old,
                     const std::vector<std::uint32_t>& old_slot_of_id, PairList& out) {
  const std::size_t n = grains.size();
  const auto& x = grains.x;
  const auto& r = grains.r;
  constexpr Real kNone = std::numeric_limits<Real>::infinity();
  Real r_max = 0, a_min_active = kNone;
  // (maxima and minima: the same for any thread count)
  const bool many = n >= kParallelMinGrains;
#pragma omp parallel for reduction(max : r_max) reduction(min : a_min_active) if (many)
  for (std::size_t i = 0; i < n; ++i) {
    r_max = std::max(r_max, r[i]);
    if (grains.state[i] == GrainState::Active) a_min_active = std::min(a_min_active, allow[i]);
  }
  // a frozen grain less mobile than every active one owns no pair (see below): it searches none
  auto searches = [&](std::size_t i) {
    return grains.state[i] == GrainState::Active || !(allow[i] < a_min_active);
  };
  Real a_min = kNone;
#pragma omp parallel for schedule(static) reduction(min : a_min) if (many)
  for (std::size_t i = 0; i < n; ++i)
    if (searches(i)) a_min = std::min(a_min, allow[i]);
  if (a_min == kNone) a_min = 0;
  // The grains that search in one grid, the frozen ones that search none in another (and the
  // largest allowance among those: none in a run, a frozen grain does not move). Cells fit the
  // pairs of the least mobile searching grains; one with a larger allowance looks further.
  std::vector<std::uint32_t> searching, frozen;
  Real a_max_frozen = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (searches(i)) {
      searching.push_back(static_cast<std::uint32_t>(i));
    } else {
      frozen.push_back(static_cast<std::uint32_t>(i));
      a_max_frozen = std::max(a_max_frozen, allow[i]);
    }
  }
  grids.searching.build(x, searching, 2 * r_max + 2 * a_min);
  grids.frozen.build(x, frozen, 2 * r_max + 2 * a_min);
  const Real inv_cell = 1.0 / grids.searching.cell_size();

  // A pair is listed when the grains are within reach and at least one of them can move. Two
  // searching grains in cells next to each other are found by the grid's half search
  // (CellGrid::for_each_after), which every searching grain makes: half the candidates, none of
  // them another's, and every pair closer than a cell. A pair further apart (a fast grain's: the
  // allowances of half a surface run's searching grains are raised, docs/performance.md,
  // ninety-sixth) is found beyond those cells by the grain with the larger allowance, whose
  // search reaches r_i + r_max + 2 a_i: every partner with an allowance no larger than its own
  // (on a tie the lower index finds it).
  // (the search reads the arrays through local pointers, captured by value: through `grains`,
  // every candidate reloaded them, since any store may change a vector's pointer)
  const Vec3* const px = x.data();
  const Real* const pr = r.data();
  const Real* const pa = allow.data();
  const GrainState* const ps = grains.state.data();

  // One pass: each thread lists a contiguous range of grains into its own buffer; the buffers
  // are then joined in thread order, so the list is in grain order for any thread count. A pair
  // found by its higher-index grain goes to a side list and joins the lower one's row after.
  // The ranges are of about equal work: a grain searches about 14 cells (the half search), a
  // third of (2k + 1)^3 more when its reach is k = 2-3 cells (the fast grains of a stream, which
  // sit together in the storage order), and 27 more among the frozen grains.
  std::vector<std::uint32_t> own_count(n + 1, 0);
  std::vector<std::uint8_t> reach(n);
  std::uint64_t work = 0;
  const bool any_frozen = !frozen.empty();
  auto cells_searched = [&](std::size_t i) -> std::uint64_t {
    const std::uint64_t k = reach[i];
    const std::uint64_t among_frozen = any_frozen && ps[i] == GrainState::Active ? 27 : 0;
    return k == 0 ? 0
                  : (k == 1 ? 14 : 14 + (2 * k + 1) * (2 * k + 1) * (2 * k + 1) / 3) + among_frozen;
  };
#pragma omp parallel for schedule(static) reduction(+ : work) if (many)
  for (std::size_t i = 0; i < n; ++i) {
    const int k = std::max(1, static_cast<int>(std::ceil((r[i] + r_max + 2 * allow[i]) * inv_cell)));
    reach[i] = searches(i) ? static_cast<std::uint8_t>(std::min(k, 255)) : 0;  // 0: no search
    work += cells_searched(i);
  }
  std::vector<std::size_t> range_start;
  std::vector<std::vector<std::uint32_t>> buffers;
  std::vector<std::vector<std::pair<std::uint32_t, std::uint32_t>>> side_buffers;
#pragma omp parallel if (n >= kParallelMinGrains)
  {
#pragma omp single
    {
      const std::size_t threads = static_cast<std::size_t>(omp_get_num_threads());
      buffers.resize(threads);
      side_buffers.resize(threads);
      range_start.assign(threads + 1, n);
      range_start[0] = 0;
      std::uint64_t acc = 0;
      std::size_t t = 1;
      for (std::size_t i = 0; i < n && t < threads; ++i) {
        acc += cells_searched(i);
        while (t < threads && acc * threads >= work * t) range_start[t++] = i + 1;
      }
    }
    const std::size_t t = static_cast<std::size_t>(omp_get_thread_num());
    // each thread's buffers are its own until the end: two vectors side by side in `buffers`
    // share a cache line, and every push_back would pass it between the cores
    std::vector<std::uint32_t> buf;
    std::vector<std::pair<std::uint32_t, std::uint32_t>> side;
    for (std::size_t i = range_start[t]; i < range_start[t + 1]; ++i) {
      const std::size_t first = buf.size();
      const int k = reach[i];
      if (k == 0) continue;  // (own_count[i + 1] stays 0)
      const auto me = static_cast<std::uint32_t>(i);
      const Real a_i = pa[i], r_i = pr[i];
      const Vec3 x_i = px[i];
      const bool active_i = ps[i] == GrainState::Active;
      auto list = [&buf, &side, px, pr, pa, me, a_i, r_i, x_i](std::uint32_t j) {
        const Real cut = r_i + pr[j] + a_i + pa[j];
        if (!(norm2(x_i - px[j]) < cut * cut)) return;
        if (j > me)
          buf.push_back(j);
        else
          side.emplace_back(j, me);
      };
      auto near_partner = [&list, ps, active_i](std::uint32_t j) {
        if (active_i || ps[j] == GrainState::Active) list(j);
      };
      auto far_partner = [&list, pa, ps, me, a_i, active_i](std::uint32_t j) {
        const Real a_j = pa[j];
        if (!(a_i > a_j || (a_i == a_j && me < j))) return;
        if (active_i || ps[j] == GrainState::Active) list(j);
      };
      grids.searching.for_each_after(me, x_i, near_partner);
      // a longer reach than a cell: only the cells its ball meets beyond the 27
      const Real reach_i = r_i + r_max + 2 * a_i;
      if (reach_i > grids.searching.cell_size())
        grids.searching.for_each_in_ball_beyond(x_i, reach_i, far_partner);
      // every frozen grain that searches none is less mobile: an ACTIVE grain lists it, out to
      // the cut of a pair with the most mobile of them (with its own allowance for theirs, as
      // among the searching grains, a fast grain searched up to three times the volume:
      // docs/performance.md, ninety-fourth)
      if (any_frozen && active_i) {
        const Real frozen_reach = r_i + r_max + a_i + a_max_frozen;
        if (frozen_reach <= grids.frozen.cell_size())
          grids.frozen.for_each_within(x_i, 1, list);
        else
          grids.frozen.for_each_in_ball(x_i, frozen_reach, list);
      }
      // ascending j: a canonical order, independent of how the grid visits cells
      std::sort(buf.begin() + first, buf.end());
      own_count[i + 1] = static_cast<std::uint32_t>(buf.size() - first);
    }
    buffers[t] = std::move(buf);
    side_buffers[t] = std::move(side);
  }
  std::vector<std::uint32_t> own_start(std::move(own_count));
  for (std::size_t i = 0; i < n; ++i) own_start[i + 1] += own_start[i];
  std::vector<std::uint32_t> own(own_start[n]);
  // (each buffer holds the rows of its range of grains: it goes where the first of them starts)
#pragma omp parallel for schedule(static, 1) if (n >= kParallelMinGrains)
  for (std::size_t t = 0; t < buffers.size(); ++t)
    std::copy(buffers[t].begin(), buffers[t].end(), own.begin() + own_start[range_start[t]]);
  std::vector<std::pair<std::uint32_t, std::uint32_t>> side;
  for (const auto& sb : side_buffers) side.insert(side.end(), sb.begin(), sb.end());

  if (side.empty()) {
    out.start = std::move(own_start);
    out.j = std::move(own);
  } else {
    // rows = own pairs merged with the side pairs of the same grain, both ascending: the side
    // pairs come in ascending order of their finder b, so filing them by a (a stable counting
    // sort) leaves each row's ascending
    std::vector<std::uint32_t> side_start(n + 1, 0);
    for (const auto& [a, b] : side) ++side_start[a + 1];
    for (std::size_t i = 0; i < n; ++i) side_start[i + 1] += side_start[i];
    {
      std::vector<std::uint32_t> at(side_start.begin(), side_start.end() - 1);
      std::vector<std::pair<std::uint32_t, std::uint32_t>> filed(side.size());
      for (const auto& p : side) filed[at[p.first]++] = p;
      side = std::move(filed);
    }
    out.start.assign(n + 1, 0);
    for (std::size_t i = 0; i < n; ++i)
      out.start[i + 1] =
          out.start[i] + (side_start[i + 1] - side_start[i]) + (own_start[i + 1] - own_start[i]);
    out.j.resize(out.start[n]);
    // (each row from its own and its side pairs alone: the threads take shares of the rows)
#pragma omp parallel for schedule(static) if (n >= kParallelMinGrains)
    for (std::size_t i = 0; i < n; ++i) {
      auto dst = out.j.begin() + out.start[i];
      auto o = own.begin() + own_start[i], o_end = own.begin() + own_start[i + 1];
      for (std::uint32_t q = side_start[i]; q < side_start[i + 1]; ++q) {
        while (o != o_end && *o < side[q].second) *dst++ = *o++;
        *dst++ = side[q].second;
      }
      std::copy(o, o_end, dst);
    }
  }
  const std::size_t slots = out.j.size();

  // history, carried over by grain id (the tangential one changes sign when the pair flips);
  // every slot is written, so the arrays need no clearing first
  out.xi.resize(slots);
  out.psi.resize(rolling ? slots : 0);
  out.touch.resize(slots);
  out.delta0.resize(slots);
  const std::size_t old_n = old.start.empty() ? 0 : old.start.size() - 1;
  auto old_slot = [&](GrainId id) {
    return id < old_slot_of_id.size() ? old_slot_of_id[id] : kNoSlot;
  };
  // the common case: no grain moved to another slot since the last build (new ones appended)
  bool same_slots = true;
  for (std::size_t i = 0; i < std::min(n, old_n) && same_slots; ++i)
    same_slots = old_slot(grains.id[i]) == i;
  const bool old_rolling = !old.psi.empty();
#pragma omp parallel for schedule(static) if (n >= kParallelMinGrains)
  for (std::size_t i = 0; i < n; ++i) {
    auto carry = [&](std::uint32_t s, std::uint32_t os, bool flipped) {
      out.xi[s] = os == kNoSlot ? Vec3{} : (flipped ? -old.xi[os] : old.xi[os]);
      if (rolling) out.psi[s] = os == kNoSlot || !old_rolling ? Vec3{} : old.psi[os];
      // a pair with history keeps its flags, so the next force pass clears them if it is apart
      out.touch[s] = os == kNoSlot ? 0 : old.touch[os];
      out.delta0[s] = os == kNoSlot || !(old.touch[os] & kPreloaded) ? 0 : old.delta0[os];
    };
    if (same_slots) {
      // both rows are sorted by j: walk them together
      std::uint32_t os = i < old_n ? old.start[i] : 0, oe = i < old_n ? old.start[i + 1] : 0;
      for (std::uint32_t s = out.start[i]; s < out.start[i + 1]; ++s) {
        while (os < oe && old.j[os] < out.j[s]) ++os;
        carry(s, os < oe && old.j[os] == out.j[s] ? os : kNoSlot, false);
      }
      continue;
    }
    const std::uint32_t oi = old_slot(grains.id[i]);
    for (std::uint32_t s = out.start[i]; s < out.start[i + 1]; ++s) {
      const std::uint32_t oj = oi == kNoSlot ? kNoSlot : old_slot(grains.id[out.j[s]]);
      if (oj == kNoSlot) {
        carry(s, kNoSlot, false);
        continue;
      }
      const bool flipped = oj < oi;
      carry(s, flipped ? find_old_slot(old, oj, oi) : find_old_slot(old, oi, oj), flipped);
    }
  }

  // per-step results: written before they are read, by the pass that computes the pair
  out.force.resize(slots);
  out.q.resize(slots);
  out.t_roll.resize(rolling ? slots : 0);
  out.c_n.resize(slots);
}

namespace {

// Fills the rows of a wall or boundary list (start, obstacle) in one pass: row(i, buf) appends
// grain i's entries, ascending, to buf. Each thread's rows go into its own buffer, joined in
// thread order: the rows' order, for any thread count.
template <class Row>
void fill_rows(std::size_t n, WallList& out, Row&& row) {
  out.start.assign(n + 1, 0);
  std::vector<std::vector<std::uint32_t>> buffers;
#pragma omp parallel if (n >= kParallelMinGrains)
  {
#pragma omp single
    buffers.resize(static_cast<std::size_t>(omp_get_num_threads()));
    std::vector<std::uint32_t> buf;  // (the thread's own until the end: see build_pair_list)
#pragma omp for schedule(static) nowait
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t first = buf.size();
      row(i, buf);
      out.start[i + 1] = static_cast<std::uint32_t>(buf.size() - first);
    }
    buffers[static_cast<std::size_t>(omp_get_thread_num())] = std::move(buf);
  }
  for (std::size_t i = 0; i < n; ++i) out.start[i + 1] += out.start[i];
  out.obstacle.clear();
  for (const auto& buf : buffers) out.obstacle.insert(out.obstacle.end(), buf.begin(), buf.end());
}

// The history of each entry of out's rows, carried over from old's by grain id (both rows
// ascending); an entry without one starts from none.
void carry_history(const Grains& grains, const WallList& old,
                   const std::vector<std::uint32_t>& old_slot_of_id, WallList& out) {
  const std::size_t n = grains.size(), slots = out.obstacle.size();
  out.xi.assign(slots, Vec3{});
  out.psi.assign(slots, Vec3{});
#pragma omp parallel for schedule(static) if (n >= kParallelMinGrains)
  for (std::size_t i = 0; i < n; ++i) {
    const GrainId id = grains.id[i];
    const std::uint32_t oi =
        old.start.empty() || id >= old_slot_of_id.size() ? kNoSlot : old_slot_of_id[id];
    if (oi == kNoSlot || oi + 1 >= old.start.size()) continue;
    std::uint32_t os = old.start[oi];
    const std::uint32_t oe = old.start[oi + 1];
    for (std::uint32_t s = out.start[i]; s < out.start[i + 1]; ++s) {
      while (os < oe && old.obstacle[os] < out.obstacle[s]) ++os;
      if (os < oe && old.obstacle[os] == out.obstacle[s]) {
        out.xi[s] = old.xi[os];
        out.psi[s] = old.psi[os];
      }
    }
  }
}

}  // namespace

void build_wall_list(const Grains& grains, const std::vector<Real>& allow, const Geometry& geometry,
                     const WallList& old, const std::vector<std::uint32_t>& old_slot_of_id,
                     WallList& out) {
  // obstacles within reach of each grain (twice its allowance: an obstacle does not move, the
  // margin is spare), in obstacle order, each distance asked once
  const std::size_t n_obs = geometry.size();
  fill_rows(grains.size(), out, [&](std::size_t i, std::vector<std::uint32_t>& row) {
    for (std::uint32_t k = 0; k < n_obs; ++k)
      if (geometry.obstacles()[k].solid->closest(grains.x[i]).distance < grains.r[i] + 2 * allow[i])
        row.push_back(k);
  });
  carry_history(grains, old, old_slot_of_id, out);
}

void build_boundary_list(const Grains& grains, const std::vector<Real>& allow,
                         const std::vector<Vec3>& centres, Real radius, const CellGrid& grid,
                         const WallList& old, const std::vector<std::uint32_t>& old_slot_of_id,
                         WallList& out) {
  if (centres.empty()) {
    out.start.assign(grains.size() + 1, 0);
    out.obstacle.clear();
    return;
  }
  fill_rows(grains.size(), out, [&](std::size_t i, std::vector<std::uint32_t>& row) {
    if (grains.state[i] != GrainState::Active) return;
    const Real reach = grains.r[i] + radius + 2 * allow[i];  // (a particle does not move: spare)
    const std::size_t first = row.size();
    grid.for_each_in_ball(grains.x[i], reach, [&](std::uint32_t b) {
      if (norm2(grains.x[i] - centres[b]) < reach * reach) row.push_back(b);
    });
    std::sort(row.begin() + static_cast<std::ptrdiff_t>(first), row.end());
  });
  carry_history(grains, old, old_slot_of_id, out);
}

std::vector<std::pair<std::uint32_t, std::uint32_t>> brute_force_pairs(
    const Grains& grains, const std::vector<Real>& allow) {
  std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
  const std::size_t n = grains.size();
  for (std::uint32_t i = 0; i < n; ++i)
    for (std::uint32_t j = i + 1; j < n; ++j) {
      if (grains.state[i] != GrainState::Active && grains.state[j] != GrainState::Active)
        continue;
      const Real cut = grains.r[i] + grains.r[j] + allow[i] + allow[j];
      if (norm2(grains.x[i] - grains.x[j]) < cut * cut) pairs.emplace_back(i, j);
    }
  return pairs;
}

std::vector<std::pair<std::uint32_t, std::uint32_t>> brute_force_pairs(const Grains& grains,
                                                                        Real skin) {
  return brute_force_pairs(grains, std::vector<Real>(grains.size(), skin / 2));
}

std::vector<std::pair<std::uint32_t, std::uint32_t>> swept_pairs(const Grains& grains,
                                                                 const std::vector<Real>& allow) {
  const std::size_t n = grains.size();
  std::vector<std::uint32_t> by_x(n);
  // the largest r + a: no partner of i lies further along x than r_i + a_i + it
  Real reach_max = 0;
  for (std::uint32_t i = 0; i < n; ++i) {
    by_x[i] = i;
    reach_max = std::max(reach_max, grains.r[i] + allow[i]);
  }
  std::sort(by_x.begin(), by_x.end(), [&](std::uint32_t a, std::uint32_t b) {
    return grains.x[a].x < grains.x[b].x || (grains.x[a].x == grains.x[b].x && a < b);
  });
  std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
  for (std::size_t p = 0; p < n; ++p) {
    const std::uint32_t i = by_x[p];
    const Real x_end = grains.x[i].x + grains.r[i] + allow[i] + reach_max;
    for (std::size_t q = p + 1; q < n && grains.x[by_x[q]].x <= x_end; ++q) {
      const std::uint32_t j = by_x[q];
      if (grains.state[i] != GrainState::Active && grains.state[j] != GrainState::Active) continue;
      const Real cut = grains.r[i] + grains.r[j] + allow[i] + allow[j];
      if (norm2(grains.x[i] - grains.x[j]) < cut * cut)
        pairs.emplace_back(std::min(i, j), std::max(i, j));
    }
  }
  return pairs;
}

std::string pair_list_error(const Grains& grains, const std::vector<Real>& allow,
                            const PairList& pairs) {
  const std::size_t n = grains.size();
  if (pairs.start.size() != n + 1 || pairs.start[0] != 0 || pairs.start[n] != pairs.j.size())
    return fmt::format("the list has {} offsets for {} grains, or they do not span its {} slots",
                       pairs.start.size(), n, pairs.j.size());
  for (std::size_t i = 0; i < n; ++i) {
    if (pairs.start[i] > pairs.start[i + 1])
      return fmt::format("the row of slot {} ends before it starts", i);
    for (std::uint32_t s = pairs.start[i]; s < pairs.start[i + 1]; ++s)
      if (pairs.j[s] <= i || pairs.j[s] >= n ||
          (s > pairs.start[i] && pairs.j[s] <= pairs.j[s - 1]))
        return fmt::format(
            "the row of slot {} (grain {}) lists slot {}: not above it, not a "
            "grain, or out of order",
            i, grains.id[i], pairs.j[s]);
  }
  for (const auto& [i, j] : swept_pairs(grains, allow)) {
    const auto row_begin = pairs.j.begin() + pairs.start[i];
    const auto row_end = pairs.j.begin() + pairs.start[i + 1];
    if (std::binary_search(row_begin, row_end, j)) continue;
    const Real dist = norm(grains.x[i] - grains.x[j]);
    const Real cut = grains.r[i] + grains.r[j] + allow[i] + allow[j];
    if (dist >= cut * (1 - 1e-9)) continue;  // (at the cut: rounding decides)
    return fmt::format(
        "grains {} and {} (slots {}, {}) are {:.6g} m apart, within reach "
        "({:.6g} m; touching below {:.6g} m), but not in the list",
        grains.id[i], grains.id[j], i, j, dist, cut, grains.r[i] + grains.r[j]);
  }
  return {};
}

}  // namespace sandflow
