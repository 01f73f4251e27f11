#include "analysis/surface_diff.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "dem/grains.hpp"

namespace sandflow {

namespace {
constexpr Real kNoSand = 1e-9;  ///< H - L above this: the column has sand [m]
}  // namespace

MeasuredSurface measure_surface(const HeightFieldParams& grid, const TerrainColumns& terrain,
                                const std::vector<Vec3>& x, const std::vector<Real>& r) {
  if (x.size() != r.size()) throw std::invalid_argument("measure_surface: x and r differ in size");
  Grains g;
  for (std::size_t i = 0; i < x.size(); ++i) g.add(static_cast<GrainId>(i), x[i], {}, r[i], 1.0);
  HeightField hf(grid, terrain);
  hf.measure(g, std::vector<Real>(hf.columns(), -std::numeric_limits<Real>::infinity()));
  return {hf.surface(), hf.terrain()};
}

SurfaceDiff compare_surfaces(const MeasuredSurface& a, const MeasuredSurface& b) {
  const std::size_t n = a.H.size();
  if (b.H.size() != n || a.L.size() != n || b.L.size() != n)
    throw std::invalid_argument("compare_surfaces: the surfaces have different grids");
  SurfaceDiff d;
  double sum = 0;
  for (std::size_t c = 0; c < n; ++c) {
    d.heap_height = std::max(d.heap_height, a.H[c] - a.L[c]);
    if (a.H[c] - a.L[c] <= kNoSand && b.H[c] - b.L[c] <= kNoSand) continue;
    sum += (a.H[c] - b.H[c]) * (a.H[c] - b.H[c]);
    ++d.columns;
  }
  d.rms = d.columns ? std::sqrt(sum / static_cast<double>(d.columns)) : 0;
  d.rms_rel = d.heap_height > 0 ? d.rms / d.heap_height : 0;
  return d;
}

namespace {

/// Distance from p to surface s near column (i, j): the top faces of the columns and the vertical
/// faces between them, searched outwards until no nearer point can lie further away. The column
/// under p bounds the answer by |p.z - H|, so the search ends within that many columns.
Real distance_to(const HeightFieldParams& g, const std::vector<Real>& H, int i, int j,
                 const Vec3& p) {
  const Real w = g.cell, half = 0.5 * g.cell;
  auto cx = [&](int ii) { return g.x0 + (ii + 0.5) * w; };
  auto cy = [&](int jj) { return g.y0 + (jj + 0.5) * w; };
  auto at = [&](int ii, int jj) { return H[static_cast<std::size_t>(jj) * g.nx + ii]; };
  // from p to the nearest point of [lo, hi] along one axis
  auto gap = [](Real v, Real lo, Real hi) { return v < lo ? lo - v : (v > hi ? v - hi : 0.0); };
  Real best = std::abs(p.z - at(i, j));
  for (int ring = 1;; ++ring) {
    // every point of a column `ring` away lies at least (ring - 1/2) cells away horizontally
    if ((ring - 0.5) * w >= best || ring > std::max(g.nx, g.ny)) break;
    for (int jj = j - ring; jj <= j + ring; ++jj)
      for (int ii = i - ring; ii <= i + ring; ++ii) {
        if (std::max(std::abs(ii - i), std::abs(jj - j)) != ring) continue;
        if (ii < 0 || jj < 0 || ii >= g.nx || jj >= g.ny) continue;
        const Real dx = gap(p.x, cx(ii) - half, cx(ii) + half);
        const Real dy = gap(p.y, cy(jj) - half, cy(jj) + half);
        const Real z = at(ii, jj);
        best = std::min(best, std::sqrt(dx * dx + dy * dy + (p.z - z) * (p.z - z)));
      }
  }
  // the vertical faces between the columns searched: the edge shared with the next column along
  // x and along y, spanning the two tops
  const int reach = static_cast<int>(std::ceil(best / w)) + 1;
  for (int jj = std::max(j - reach, 0); jj <= std::min(j + reach, g.ny - 1); ++jj)
    for (int ii = std::max(i - reach, 0); ii <= std::min(i + reach, g.nx - 1); ++ii) {
      const Real z = at(ii, jj);
      if (ii + 1 < g.nx) {
        const Real z2 = at(ii + 1, jj);
        const Real dx = p.x - (cx(ii) + half);
        const Real dy = gap(p.y, cy(jj) - half, cy(jj) + half);
        const Real dz = gap(p.z, std::min(z, z2), std::max(z, z2));
        best = std::min(best, std::sqrt(dx * dx + dy * dy + dz * dz));
      }
      if (jj + 1 < g.ny) {
        const Real z2 = at(ii, jj + 1);
        const Real dx = gap(p.x, cx(ii) - half, cx(ii) + half);
        const Real dy = p.y - (cy(jj) + half);
        const Real dz = gap(p.z, std::min(z, z2), std::max(z, z2));
        best = std::min(best, std::sqrt(dx * dx + dy * dy + dz * dz));
      }
    }
  return best;
}

}  // namespace

SurfaceDistance surface_distance(const HeightFieldParams& grid, const MeasuredSurface& a,
                                 const MeasuredSurface& b) {
  const std::size_t n = static_cast<std::size_t>(grid.nx) * grid.ny;
  if (a.H.size() != n || b.H.size() != n || a.L.size() != n || b.L.size() != n)
    throw std::invalid_argument("surface_distance: the surfaces are not on the grid");
  SurfaceDistance d;
  double sum = 0;
  for (int j = 0; j < grid.ny; ++j)
    for (int i = 0; i < grid.nx; ++i) {
      const std::size_t c = static_cast<std::size_t>(j) * grid.nx + i;
      if (a.H[c] - a.L[c] <= kNoSand && b.H[c] - b.L[c] <= kNoSand) continue;
      const Real x = grid.x0 + (i + 0.5) * grid.cell, y = grid.y0 + (j + 0.5) * grid.cell;
      for (const Real e : {distance_to(grid, b.H, i, j, {x, y, a.H[c]}),
                           distance_to(grid, a.H, i, j, {x, y, b.H[c]})}) {
        sum += e * e;
        d.max = std::max(d.max, e);
        ++d.samples;
      }
    }
  d.rms = d.samples ? std::sqrt(sum / static_cast<double>(d.samples)) : 0;
  return d;
}

}  // namespace sandflow
