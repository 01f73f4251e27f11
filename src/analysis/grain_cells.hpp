// What the measurements from grains share (heap.cpp, crater.cpp): the usable grains, their mean
// diameter d, and the corner of a map of square cells of side d laid over them.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "core/vec3.hpp"

namespace sandflow {

/// The key of cell (i, j) in a hash map of cells (exact for |i|, |j| < 2^31).
inline std::uint64_t cell_key(std::int64_t i, std::int64_t j) {
  return (static_cast<std::uint64_t>(i) << 32) | static_cast<std::uint32_t>(j);
}

struct GrainCells {
  std::vector<std::size_t> use;  ///< the usable grains: finite centre, positive radius
  double d = 0;                  ///< their mean diameter: the cells' side [m]
  Vec3 lo, hi;                   ///< bounds of their centres [m]
  double x0 = 0, y0 = 0;         ///< corner of cell (0, 0) [m]
  std::string problem;           ///< why no map can be made ("" when one can)
};

/// The usable grains of `pos` and `radius` (same length) and the cells over them. Cells are
/// centred half a cell in, so grains on a lattice of spacing d fall mid-cell; a map wider than
/// 2^30 cells (keys stay exact below it) is refused, as are no grains.
inline GrainCells grain_cells(const std::vector<Vec3>& pos, const std::vector<Real>& radius) {
  constexpr double kMaxCellIndex = 1 << 30;
  GrainCells g;
  double sum_r = 0;
  for (std::size_t k = 0; k < pos.size(); ++k)
    if (is_finite(pos[k]) && std::isfinite(radius[k]) && radius[k] > 0) {
      g.use.push_back(k);
      sum_r += radius[k];
    }
  if (g.use.empty()) {
    g.problem = "no grains";
    return g;
  }
  g.d = 2.0 * sum_r / static_cast<double>(g.use.size());
  g.lo = g.hi = pos[g.use[0]];
  for (std::size_t k : g.use) {
    g.lo = min(g.lo, pos[k]);
    g.hi = max(g.hi, pos[k]);
  }
  g.x0 = g.lo.x - 0.5 * g.d;
  g.y0 = g.lo.y - 0.5 * g.d;
  if ((g.hi.x - g.x0) / g.d > kMaxCellIndex || (g.hi.y - g.y0) / g.d > kMaxCellIndex)
    g.problem = "grains spread over too many cells (stray grains far from the rest?)";
  return g;
}

}  // namespace sandflow
