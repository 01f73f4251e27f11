#include "analysis/surface_diff.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "dem/grains.hpp"

namespace sandflow {

std::vector<Real> measure_surface(const HeightFieldParams& grid, const std::vector<Real>& terrain,
                                  const std::vector<Vec3>& x, const std::vector<Real>& r) {
  if (x.size() != r.size()) throw std::invalid_argument("measure_surface: x and r differ in size");
  Grains g;
  for (std::size_t i = 0; i < x.size(); ++i) g.add(static_cast<GrainId>(i), x[i], {}, r[i], 1.0);
  HeightField hf(grid, terrain);
  hf.measure(g, terrain);
  return hf.surface();
}

SurfaceDiff compare_surfaces(const std::vector<Real>& a, const std::vector<Real>& b,
                             const std::vector<Real>& terrain) {
  if (a.size() != b.size() || a.size() != terrain.size())
    throw std::invalid_argument("compare_surfaces: the surfaces have different grids");
  SurfaceDiff d;
  constexpr Real kNoSand = 1e-9;
  double sum = 0;
  for (std::size_t c = 0; c < a.size(); ++c) {
    d.heap_height = std::max(d.heap_height, a[c] - terrain[c]);
    if (a[c] - terrain[c] <= kNoSand && b[c] - terrain[c] <= kNoSand) continue;
    sum += (a[c] - b[c]) * (a[c] - b[c]);
    ++d.columns;
  }
  d.rms = d.columns ? std::sqrt(sum / static_cast<double>(d.columns)) : 0;
  d.rms_rel = d.heap_height > 0 ? d.rms / d.heap_height : 0;
  return d;
}

}  // namespace sandflow
