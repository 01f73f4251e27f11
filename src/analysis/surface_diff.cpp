#include "analysis/surface_diff.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "dem/grains.hpp"

namespace sandflow {

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
  constexpr Real kNoSand = 1e-9;
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

}  // namespace sandflow
