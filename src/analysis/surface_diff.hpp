// Sameness of two runs (docs/design.md §9): their final sand surfaces H(x, y), measured from the grains
// by the height field's own thick rays, compared column by column (compare_surfaces) and as
// surfaces in space (surface_distance).
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

/// How far apart two sand surfaces lie in space, the measure that stays meaningful where sand
/// lies at several levels or ends at a cliff. Column by column, a heap whose edge falls a column
/// earlier in one run than in the other differs there by the height of the edge; as surfaces,
/// they differ by the column's width. Each surface is that of its columns as solid prisms: a
/// square top at H over each column, and the vertical faces where neighbouring columns' tops
/// differ. The distance is taken from the top centre of every column where either run has sand,
/// to the nearest point of the other surface, both ways.
struct SurfaceDistance {
  Real rms = 0;              ///< RMS of the distances, both ways pooled [m]
  Real max = 0;              ///< the largest [m]
  std::size_t samples = 0;   ///< distances taken
};
SurfaceDistance surface_distance(const HeightFieldParams& grid, const MeasuredSurface& a,
                                 const MeasuredSurface& b);

}  // namespace sandflow
