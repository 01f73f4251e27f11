// Sameness of two runs (DESIGN.md §9): their final sand surfaces H(x, y), measured from the grains
// by the height field's own thick rays, compared column by column.
#pragma once

#include <vector>

#include "core/vec3.hpp"
#include "surface/height_field.hpp"

namespace sandflow {

/// A sand surface: H per column, and L, the top of the solid the column's sand rests on.
struct MeasuredSurface {
  std::vector<Real> H, L;
};

/// H per column of `grid` from every grain (same rays, airborne rule and levels as the height
/// field).
MeasuredSurface measure_surface(const HeightFieldParams& grid, const TerrainColumns& terrain,
                                const std::vector<Vec3>& x, const std::vector<Real>& r);

struct SurfaceDiff {
  Real rms = 0;          ///< RMS of H_a - H_b over the columns with sand in either [m]
  Real heap_height = 0;  ///< largest H_a - L [m]
  Real rms_rel = 0;      ///< rms / heap_height
  std::size_t columns = 0;  ///< columns compared
};

/// Compares surface b with the reference a, over the columns where either has sand. The heap
/// height is a's largest H - L.
SurfaceDiff compare_surfaces(const MeasuredSurface& a, const MeasuredSurface& b);

}  // namespace sandflow
