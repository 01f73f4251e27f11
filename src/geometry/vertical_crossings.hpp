// Where a vertical line crosses a mesh: the heights that bound the solid intervals of a
// height-field column (a multi-valued terrain under and over a mesh obstacle).
//
// A line that passes exactly through a shared edge or vertex must be counted once, not twice or
// never, or the in/out parity of every interval above it flips. The point-in-triangle test
// therefore uses "simulation of simplicity": the line is taken at (x + e, y + e^2) for an
// infinitesimal e, and each edge's orientation test is evaluated with its end points in a fixed
// order, so two triangles sharing an edge always agree on which of them holds the line.
#pragma once

#include <vector>

#include "geometry/triangle_bvh.hpp"

namespace sandflow {

/// Sorted z of the crossings of the line {(x, y, z)} with the mesh. Triangles seen edge-on from
/// above (vertical walls) are not crossed; a closed mesh gives an even count.
std::vector<Real> vertical_crossings(const TriangleBvh& bvh, Real x, Real y);

}  // namespace sandflow
