// Neighbour search (docs/design.md §3): a uniform cell grid over the grains' extent builds Verlet
// half lists. Each grain i has an allowance a_i, how far it may move before the lists are rebuilt;
// a pair i < j is listed when closer than r_i + r_j + a_i + a_j, so no unlisted pair can touch
// before some grain has used up its allowance. With one allowance for all (half the skin) these
// are the usual Verlet lists; a larger allowance for the few fast grains (a falling stream) keeps
// them from forcing a rebuild every few steps. Contact history lives beside the list, one entry
// per pair slot, and is carried across rebuilds by grain id. The candidate contacts with the
// geometry, obstacles and boundary particles within reach, are listed beside the pairs at each
// rebuild, their history carried the same way. The sweep visits the near list, the slots of each
// row that can touch before a grain moves further than its near margin (DemSolver::build_near).
//
// How the forces of the pairs reach both grains without atomics, identically for any thread
// count, is told in dem_solver.cpp (DemSolver::sweep).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "core/vec3.hpp"
#include "dem/grains.hpp"
#include "geometry/shapes.hpp"

namespace sandflow {

/// PairList::touch flags: the pair touches (at the last step); its normal spring rests at delta0;
/// it slipped at the last step (its tangential force at the Coulomb limit).
constexpr std::uint8_t kTouching = 1, kPreloaded = 2, kSlipping = 4;

/// Verlet half list in compressed rows, with per-pair history and per-step results.
struct PairList {
  std::vector<std::uint32_t> start;      ///< n+1 offsets: slots of grain i are [start[i], start[i+1])
  std::vector<std::uint32_t> j;          ///< the other grain of each slot (j > i)
  std::vector<std::uint8_t> touch;       ///< 0, or kTouching with kPreloaded, kSlipping
  /// Overlap at which the normal spring rests, for a preloaded contact (one that a change of
  /// state opened between two grains already inside each other); it follows the grains apart [m]
  std::vector<Real> delta0;
  std::vector<Real> c_n;                 ///< normal damping of the pair, fixed by its masses [kg/s]
  std::vector<Vec3> xi;                  ///< tangential history per slot [m]
  std::vector<Vec3> psi;                 ///< rolling history per slot (empty without rolling) [m]
  // results of this step, kept only for the pairs that reach across threads (DemSolver::sweep)
  std::vector<Vec3> force;               ///< force on i [N]
  std::vector<Vec3> q;                   ///< n x F_t (torque = -arm * q) [N]
  std::vector<Vec3> t_roll;              ///< rolling torque on i (empty without rolling) [N m]
  /// The near list, the slots that may touch before it is made again (DemSolver::build_near):
  /// row i's are near[start[i]] .. near[start[i] + near_count[i]), ascending.
  std::vector<std::uint32_t> near;
  std::vector<std::uint32_t> near_count;

  std::size_t pairs() const { return j.size(); }
};

/// Candidate contacts between grains and obstacles, with their history.
struct WallList {
  std::vector<std::uint32_t> start;     ///< n+1 offsets
  std::vector<std::uint32_t> obstacle;  ///< obstacle index per slot
  std::vector<Vec3> xi, psi;            ///< history per slot
};

/// A uniform cell grid over a set of grains, cells in row-major (z, y, x) order. Its box is the
/// grains' bounding box, or, when that would need too many cells (over 32 a grain: a few grains
/// far away), the box holding the central 99 % of them: grains outside are clamped into the border
/// cells, which keeps every pair within one cell of each other (clamping never separates
/// neighbours) and only costs extra distance checks for the few outliers.
class CellGrid {
 public:
  /// Files grains by cell of side >= `min_cell` (the largest pair cutoff).
  void build(const std::vector<Vec3>& x, Real min_cell);
  /// Files only the grains `which` (indices into x).
  void build(const std::vector<Vec3>& x, std::span<const std::uint32_t> which, Real min_cell);

  /// Calls f(j) for every grain j in the 27 cells around p.
  template <class F>
  void for_each_near(const Vec3& p, F&& f) const {
    for_each_within(p, 1, f);
  }
  /// Calls f(j) for every grain j filed after grain i (filed in this grid, at x_i) in the 27 cells
  /// around it: those later in its own cell, and those of the 13 cells that follow its own in the
  /// grid's order. Of two grains in cells next to each other, exactly one finds the other: a half
  /// of for_each_near's search, for the pairs that either grain may list.
  template <class F>
  void for_each_after(std::uint32_t i, const Vec3& x_i, F&& f) const;
  /// Calls f(j) for every grain j in the cells at most k cells away from p's along each axis.
  template <class F>
  void for_each_within(const Vec3& p, int k, F&& f) const;
  /// Calls f(j) for every grain j in the cells that the ball of radius `reach` around p meets:
  /// every grain closer than `reach` to p, and a few more. A fast grain's reach spans several
  /// cells; the ball holds about a third of the cube around it, so its search checks that many
  /// fewer candidates.
  template <class F>
  void for_each_in_ball(const Vec3& p, Real reach, F&& f) const;
  /// The same, without the 27 cells around p's own: the grains of the ball beyond those that
  /// for_each_after finds from either side.
  template <class F>
  void for_each_in_ball_beyond(const Vec3& p, Real reach, F&& f) const;

  Real cell_size() const { return cell_; }

 private:
  int coord(Real v, int axis) const {
    // (truncation is the floor here, c >= 0; std::floor is a dozen instructions without SSE4.1)
    const Real c = (v - lo_[axis]) * inv_cell_;
    return c < 0 ? 0 : (c >= dims_[axis] ? dims_[axis] - 1 : static_cast<int>(c));
  }
  /// How far p lies from the slab of cells c along an axis. The border cells reach to infinity:
  /// they hold the clamped grains outside the box, which must not be missed.
  Real slab_distance(Real v, int c, int axis) const {
    const Real below = c > 0 ? lo_[axis] + c * cell_ - v : 0;
    const Real above = c + 1 < dims_[axis] ? v - (lo_[axis] + (c + 1) * cell_) : 0;
    return below > 0 ? below : (above > 0 ? above : 0);
  }
  std::size_t index(int cx, int cy, int cz) const {
    return (static_cast<std::size_t>(cz) * dims_[1] + cy) * dims_[0] + cx;
  }

  /// Calls f(j) for every grain j in the cells x0..x1 of row (y, z) (none when x0 > x1): the
  /// cells along x are contiguous, and so are their grains.
  template <class F>
  void for_each_in_row(int x0, int x1, int y, int z, F&& f) const {
    if (x0 > x1) return;
    const std::uint32_t end = cell_start_[index(x1, y, z) + 1];
    for (std::uint32_t q = cell_start_[index(x0, y, z)]; q < end; ++q) f(items_[q]);
  }
  /// Calls row(x0, x1, y, z) for each row of cells whose cells x0..x1 the ball meets.
  template <class Row>
  void for_each_row_in_ball(const Vec3& p, Real reach, Row&& row) const;

  template <class Which>
  void file(const std::vector<Vec3>& all, std::size_t n, Which which, Real min_cell);

  Vec3 lo_;
  Real cell_ = 1, inv_cell_ = 1;
  int dims_[3] = {1, 1, 1};
  std::vector<std::uint32_t> cell_start_;  ///< cells+1 offsets into items_
  std::vector<std::uint32_t> items_;       ///< grain indices, grouped by cell
  std::vector<std::uint32_t> place_;       ///< where each filed grain is in items_
};

/// build_pair_list's scratch: the grains that search for pairs, and the frozen ones that do not.
struct PairGrids {
  CellGrid searching, frozen;
};

/// Builds the half list of `grains` for the allowances `allow` (one per grain, >= 0), carrying
/// history over from `old` (whose slots refer to grains by the slot they had then;
/// old_slot_of_id maps an id to that slot, or kNoSlot). Uses `grids` as scratch.
void build_pair_list(const Grains& grains, const std::vector<Real>& allow, bool rolling,
                     PairGrids& grids, const PairList& old,
                     const std::vector<std::uint32_t>& old_slot_of_id, PairList& out);
/// The same with one skin for all grains (allowance skin / 2 each).
void build_pair_list(const Grains& grains, Real skin, bool rolling, PairGrids& grids,
                     const PairList& old, const std::vector<std::uint32_t>& old_slot_of_id,
                     PairList& out);

/// Builds the wall candidates of `grains`: per grain, the obstacles of `geometry` closer than
/// r_i + 2 a_i (twice its allowance: an obstacle does not move, the margin is spare), in obstacle
/// order, with their history carried over from `old` by grain id (old_slot_of_id as above).
void build_wall_list(const Grains& grains, const std::vector<Real>& allow, const Geometry& geometry,
                     const WallList& old, const std::vector<std::uint32_t>& old_slot_of_id,
                     WallList& out);
/// Builds the boundary candidates of `grains`: per ACTIVE grain, the boundary particles (of
/// radius `radius`, centred at `centres`, filed in `grid`) closer than r_i + radius + 2 a_i,
/// ascending, with their history carried over from `old` by grain id. Without particles the rows
/// are empty (and the history arrays are left as they are).
void build_boundary_list(const Grains& grains, const std::vector<Real>& allow,
                         const std::vector<Vec3>& centres, Real radius, const CellGrid& grid,
                         const WallList& old, const std::vector<std::uint32_t>& old_slot_of_id,
                         WallList& out);

/// The reference: all pairs i < j with |x_i - x_j| < r_i + r_j + a_i + a_j (at least one of them
/// ACTIVE), by brute force.
std::vector<std::pair<std::uint32_t, std::uint32_t>> brute_force_pairs(
    const Grains& grains, const std::vector<Real>& allow);
/// The same with one skin for all grains.
std::vector<std::pair<std::uint32_t, std::uint32_t>> brute_force_pairs(const Grains& grains,
                                                                        Real skin);

/// The pairs of brute_force_pairs (in another order), found without a grid: the grains sorted
/// along x, each tested against those that follow it within its reach along x. O(n log n + the
/// pairs within reach along x): the assertions after each rebuild can afford it.
std::vector<std::pair<std::uint32_t, std::uint32_t>> swept_pairs(const Grains& grains,
                                                                 const std::vector<Real>& allow);

/// The half list against the reference, for assertions after a rebuild: its rows well formed
/// (n + 1 offsets, each row's partners ascending and above the row's grain) and every pair of
/// swept_pairs(grains, allow) in it. A pair within rounding of its cut (1e-9 of it) may be
/// listed or not: the list's owner adds the allowances in its own order. Returns the first fault,
/// or "" when there is none.
std::string pair_list_error(const Grains& grains, const std::vector<Real>& allow,
                            const PairList& pairs);

constexpr std::uint32_t kNoSlot = 0xffffffffu;

/// Below this many grains a loop runs on one thread: waking threads would cost more than the work.
/// Measured (docs/performance.md): 128 to 1,024 run alike; 4,096 left the second thread idle
/// while a surface run simulated a few thousand grains.
constexpr std::size_t kParallelMinGrains = 512;

// ---------------------------------------------------------------------------------------------
template <class F>
void CellGrid::for_each_within(const Vec3& p, int k, F&& f) const {
  const int cx = coord(p.x, 0), cy = coord(p.y, 1), cz = coord(p.z, 2);
  const int x0 = cx > k ? cx - k : 0, x1 = cx + k < dims_[0] ? cx + k : dims_[0] - 1;
  for (int z = cz - k; z <= cz + k; ++z) {
    if (z < 0 || z >= dims_[2]) continue;
    for (int y = cy - k; y <= cy + k; ++y) {
      if (y < 0 || y >= dims_[1]) continue;
      for_each_in_row(x0, x1, y, z, f);
    }
  }
}

template <class F>
void CellGrid::for_each_after(std::uint32_t i, const Vec3& x_i, F&& f) const {
  const int cx = coord(x_i.x, 0), cy = coord(x_i.y, 1), cz = coord(x_i.z, 2);
  const int x0 = cx > 0 ? cx - 1 : 0, x1 = cx + 1 < dims_[0] ? cx + 1 : dims_[0] - 1;
  auto row = [&](std::uint32_t from, int y, int z) {
    const std::uint32_t end = cell_start_[index(x1, y, z) + 1];
    for (std::uint32_t q = from; q < end; ++q) f(items_[q]);
  };
  // its own row from i on (its cell's later grains and the next cell), the row after it, and
  // the three rows of the next layer
  row(place_[i] + 1, cy, cz);
  if (cy + 1 < dims_[1]) row(cell_start_[index(x0, cy + 1, cz)], cy + 1, cz);
  if (cz + 1 < dims_[2])
    for (int y = cy > 0 ? cy - 1 : 0; y <= cy + 1 && y < dims_[1]; ++y)
      row(cell_start_[index(x0, y, cz + 1)], y, cz + 1);
}

template <class F>
void CellGrid::for_each_in_ball(const Vec3& p, Real reach, F&& f) const {
  for_each_row_in_ball(p, reach,
                       [&](int x0, int x1, int y, int z) { for_each_in_row(x0, x1, y, z, f); });
}

template <class F>
void CellGrid::for_each_in_ball_beyond(const Vec3& p, Real reach, F&& f) const {
  const int cx = coord(p.x, 0), cy = coord(p.y, 1), cz = coord(p.z, 2);
  // (most fast grains reach a little over a cell: their ball meets no cell beyond the 27 unless
  // it meets one two cells away along some axis)
  const Real r2 = reach * reach * (1 + 1e-9);  // (as for_each_row_in_ball's)
  auto met = [&](int cell, int axis) {
    const Real d = slab_distance(p[axis], cell, axis);
    return d * d < r2;
  };
  const int c[3] = {cx, cy, cz};
  bool beyond = false;
  for (int axis = 0; axis < 3 && !beyond; ++axis)
    beyond = (c[axis] >= 2 && met(c[axis] - 2, axis)) ||
             (c[axis] + 2 < dims_[axis] && met(c[axis] + 2, axis));
  if (!beyond) return;
  for_each_row_in_ball(p, reach, [&](int x0, int x1, int y, int z) {
    if (std::abs(y - cy) > 1 || std::abs(z - cz) > 1) return for_each_in_row(x0, x1, y, z, f);
    for_each_in_row(x0, std::min(x1, cx - 2), y, z, f);  // (the parts beside the 27 cells)
    for_each_in_row(std::max(x0, cx + 2), x1, y, z, f);
  });
}

template <class Row>
void CellGrid::for_each_row_in_ball(const Vec3& p, Real reach, Row&& row) const {
  const Real r2 = reach * reach * (1 + 1e-9);  // (a margin for the rounding of the distances)
  const int z1 = coord(p.z + reach, 2), y0 = coord(p.y - reach, 1), y1 = coord(p.y + reach, 1);
  for (int z = coord(p.z - reach, 2); z <= z1; ++z) {
    const Real dz = slab_distance(p.z, z, 2);
    if (dz * dz >= r2) continue;
    for (int y = y0; y <= y1; ++y) {
      const Real dy = slab_distance(p.y, y, 1);
      const Real left = r2 - dz * dz - dy * dy;
      if (left <= 0) continue;
      // (the row's cells along x that the ball meets are contiguous)
      const Real w = std::sqrt(left);
      row(coord(p.x - w, 0), coord(p.x + w, 0), y, z);
    }
  }
}

}  // namespace sandflow
