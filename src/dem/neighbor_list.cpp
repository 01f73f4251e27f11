#include "dem/neighbor_list.hpp"

#include <algorithm>
#include <bit>

namespace sandflow {

void CellGrid::build(const std::vector<Vec3>& x, Real cell) {
  cell_ = cell;
  inv_cell_ = 1.0 / cell;
  const std::size_t n = x.size();
  // about two buckets per grain keeps collisions rare
  const std::size_t buckets = std::bit_ceil(std::max<std::size_t>(64, 2 * n));
  mask_ = static_cast<std::uint32_t>(buckets - 1);

  std::vector<std::uint32_t> b(n);
  bucket_start_.assign(buckets + 1, 0);
  for (std::size_t i = 0; i < n; ++i) {
    b[i] = bucket(coord(x[i].x), coord(x[i].y), coord(x[i].z));
    ++bucket_start_[b[i] + 1];
  }
  for (std::size_t k = 0; k < buckets; ++k) bucket_start_[k + 1] += bucket_start_[k];
  items_.resize(n);
  std::vector<std::uint32_t> fill(bucket_start_.begin(), bucket_start_.end() - 1);
  for (std::size_t i = 0; i < n; ++i) items_[fill[b[i]]++] = static_cast<std::uint32_t>(i);
}

namespace {

// Finds slot of (a, b) in the old list, a < b in old numbering; kNoSlot when absent.
std::uint32_t find_old_slot(const PairList& old, std::uint32_t a, std::uint32_t b) {
  for (std::uint32_t s = old.start[a]; s < old.start[a + 1]; ++s)
    if (old.j[s] == b) return s;
  return kNoSlot;
}

}  // namespace

void build_pair_list(const Grains& grains, Real skin, bool rolling, CellGrid& grid,
                     const PairList& old, const std::vector<std::uint32_t>& old_slot_of_id,
                     PairList& out) {
  const std::size_t n = grains.size();
  const auto& x = grains.x;
  const auto& r = grains.r;
  Real r_max = 0;
  for (Real ri : r) r_max = std::max(r_max, ri);
  grid.build(x, 2 * r_max + skin);

  // A pair is listed when the grains are within reach and at least one of them can move.
  auto listed = [&](std::size_t i, std::uint32_t j) {
    if (j <= i) return false;
    if (grains.state[i] != GrainState::Active && grains.state[j] != GrainState::Active)
      return false;
    const Real cut = r[i] + r[j] + skin;
    return norm2(x[i] - x[j]) < cut * cut;
  };

  // pass 1: count, pass 2: fill, both in grain order so the list is the same for any thread count
  out.start.assign(n + 1, 0);
#pragma omp parallel for schedule(dynamic, 256) if (n >= kParallelMinGrains)
  for (std::size_t i = 0; i < n; ++i) {
    std::uint32_t c = 0;
    grid.for_each_near(x[i], [&](std::uint32_t j) { c += listed(i, j); });
    out.start[i + 1] = c;
  }
  for (std::size_t i = 0; i < n; ++i) out.start[i + 1] += out.start[i];
  const std::size_t slots = out.start[n];
  out.j.resize(slots);
#pragma omp parallel for schedule(dynamic, 256) if (n >= kParallelMinGrains)
  for (std::size_t i = 0; i < n; ++i) {
    std::uint32_t s = out.start[i];
    grid.for_each_near(x[i], [&](std::uint32_t j) {
      if (listed(i, j)) out.j[s++] = j;
    });
    // ascending j: a canonical order, independent of how the grid visits cells
    std::sort(out.j.begin() + out.start[i], out.j.begin() + out.start[i + 1]);
  }

  // history, carried over by grain id (the tangential one changes sign when the pair flips)
  out.xi.assign(slots, Vec3{});
  out.psi.assign(rolling ? slots : 0, Vec3{});
  const bool have_old = !old.start.empty();
  auto old_slot = [&](GrainId id) {
    return id < old_slot_of_id.size() ? old_slot_of_id[id] : kNoSlot;
  };
#pragma omp parallel for schedule(static) if (n >= kParallelMinGrains)
  for (std::size_t i = 0; i < n; ++i) {
    if (!have_old) continue;
    const std::uint32_t oi = old_slot(grains.id[i]);
    if (oi == kNoSlot) continue;
    for (std::uint32_t s = out.start[i]; s < out.start[i + 1]; ++s) {
      const std::uint32_t oj = old_slot(grains.id[out.j[s]]);
      if (oj == kNoSlot) continue;
      const bool flipped = oj < oi;
      const std::uint32_t os = flipped ? find_old_slot(old, oj, oi) : find_old_slot(old, oi, oj);
      if (os == kNoSlot) continue;
      out.xi[s] = flipped ? -old.xi[os] : old.xi[os];
      if (rolling && !old.psi.empty()) out.psi[s] = old.psi[os];
    }
  }

  out.force.assign(slots, Vec3{});
  out.torque_i.assign(slots, Vec3{});
  out.torque_j.assign(slots, Vec3{});

  // reverse index: for each grain, the slots where it is the second grain, in ascending order
  out.rev_start.assign(n + 1, 0);
  for (std::size_t s = 0; s < slots; ++s) ++out.rev_start[out.j[s] + 1];
  for (std::size_t i = 0; i < n; ++i) out.rev_start[i + 1] += out.rev_start[i];
  out.rev_slot.resize(slots);
  std::vector<std::uint32_t> fill(out.rev_start.begin(), out.rev_start.end() - 1);
  for (std::size_t s = 0; s < slots; ++s)
    out.rev_slot[fill[out.j[s]]++] = static_cast<std::uint32_t>(s);
}

std::vector<std::pair<std::uint32_t, std::uint32_t>> brute_force_pairs(const Grains& grains,
                                                                        Real skin) {
  std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
  const std::size_t n = grains.size();
  for (std::uint32_t i = 0; i < n; ++i)
    for (std::uint32_t j = i + 1; j < n; ++j) {
      if (grains.state[i] != GrainState::Active && grains.state[j] != GrainState::Active)
        continue;
      const Real cut = grains.r[i] + grains.r[j] + skin;
      if (norm2(grains.x[i] - grains.x[j]) < cut * cut) pairs.emplace_back(i, j);
    }
  return pairs;
}

}  // namespace sandflow
