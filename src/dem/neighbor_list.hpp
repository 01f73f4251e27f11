// Neighbour search (DESIGN.md §3): a uniform cell grid, hashed so that grains anywhere in space
// cost nothing extra, builds Verlet half lists (pairs i < j closer than r_i + r_j + skin) that
// stay valid until some grain has moved more than half the skin. Contact history lives beside
// the list, one entry per pair slot, and is carried across rebuilds by grain id.
//
// Forces are parallel without atomics: each pair slot receives its force from one thread, and
// each grain then gathers its slots in a fixed order (its own list, then the reverse index of the
// pairs where it is the second grain), so 1 and N threads give bit-identical results.
#pragma once

#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

#include "core/vec3.hpp"
#include "dem/grains.hpp"

namespace sandflow {

/// Verlet half list in compressed rows, with per-pair history and per-step results.
struct PairList {
  std::vector<std::uint32_t> start;      ///< n+1 offsets: slots of grain i are [start[i], start[i+1])
  std::vector<std::uint32_t> j;          ///< the other grain of each slot (j > i)
  std::vector<Vec3> xi;                  ///< tangential history per slot [m]
  std::vector<Vec3> psi;                 ///< rolling history per slot (empty without rolling) [m]
  std::vector<Vec3> force;               ///< force on i of each slot this step [N]
  std::vector<Vec3> torque_i, torque_j;  ///< [N m]
  std::vector<std::uint32_t> rev_start;  ///< n+1 offsets into rev_slot
  std::vector<std::uint32_t> rev_slot;   ///< slots where grain i is the second grain, ascending

  std::size_t pairs() const { return j.size(); }
};

/// Candidate contacts between grains and obstacles, with their history.
struct WallList {
  std::vector<std::uint32_t> start;     ///< n+1 offsets
  std::vector<std::uint32_t> obstacle;  ///< obstacle index per slot
  std::vector<Vec3> xi, psi;            ///< history per slot
};

/// The hashed cell grid over a set of grains.
class CellGrid {
 public:
  /// Files grains by cell of side `cell` (>= the largest pair cutoff).
  void build(const std::vector<Vec3>& x, Real cell);

  /// Calls f(j) for every grain j in the 27 cells around p (each grain once).
  template <class F>
  void for_each_near(const Vec3& p, F&& f) const;

  Real cell_size() const { return cell_; }

 private:
  std::uint32_t bucket(std::int64_t cx, std::int64_t cy, std::int64_t cz) const;
  std::int64_t coord(Real v) const { return static_cast<std::int64_t>(std::floor(v * inv_cell_)); }

  Real cell_ = 1, inv_cell_ = 1;
  std::uint32_t mask_ = 0;
  std::vector<std::uint32_t> bucket_start_;  ///< size buckets+1
  std::vector<std::uint32_t> items_;         ///< grain indices, grouped by bucket
};

/// Builds the half list of `grains` for the given skin, carrying history over from `old` (whose
/// slots refer to grains by the slot they had then; old_slot_of_id maps an id to that slot, or
/// kNoSlot). Uses `grid` as scratch.
void build_pair_list(const Grains& grains, Real skin, bool rolling, CellGrid& grid,
                     const PairList& old, const std::vector<std::uint32_t>& old_slot_of_id,
                     PairList& out);

/// The reference: all pairs i < j with |x_i - x_j| < r_i + r_j + skin, by brute force.
std::vector<std::pair<std::uint32_t, std::uint32_t>> brute_force_pairs(const Grains& grains,
                                                                        Real skin);

constexpr std::uint32_t kNoSlot = 0xffffffffu;

/// Below this many grains a loop runs on one thread: waking threads would cost more than the work.
constexpr std::size_t kParallelMinGrains = 4096;

// ---------------------------------------------------------------------------------------------
template <class F>
void CellGrid::for_each_near(const Vec3& p, F&& f) const {
  const std::int64_t cx = coord(p.x), cy = coord(p.y), cz = coord(p.z);
  std::uint32_t seen[27];
  int n_seen = 0;
  for (std::int64_t dz = -1; dz <= 1; ++dz)
    for (std::int64_t dy = -1; dy <= 1; ++dy)
      for (std::int64_t dx = -1; dx <= 1; ++dx) {
        const std::uint32_t b = bucket(cx + dx, cy + dy, cz + dz);
        // two cells may share a bucket: visit each bucket once
        bool dup = false;
        for (int k = 0; k < n_seen; ++k) dup |= (seen[k] == b);
        if (dup) continue;
        seen[n_seen++] = b;
        for (std::uint32_t k = bucket_start_[b]; k < bucket_start_[b + 1]; ++k) f(items_[k]);
      }
}

inline std::uint32_t CellGrid::bucket(std::int64_t cx, std::int64_t cy, std::int64_t cz) const {
  const auto h = static_cast<std::uint64_t>(cx) * 73856093ULL ^
                 static_cast<std::uint64_t>(cy) * 19349663ULL ^
                 static_cast<std::uint64_t>(cz) * 83492791ULL;
  return static_cast<std::uint32_t>(h & mask_);
}

}  // namespace sandflow
