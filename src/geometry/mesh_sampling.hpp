// Mesh obstacles as fixed boundary particles (docs/design.md §6, "particle surfaces"): points placed
// on the surface densely enough that no grain can pass between them.
//
// Each triangle is cut into n^2 congruent copies of itself, n = ceil(longest edge / spacing), and
// the corners of the copies are the samples; samples closer than spacing / 8 to one already kept
// are dropped, which removes the copies made along shared edges and at shared vertices.
//
// Guarantee: every point of the surface lies within covering_radius(spacing) =
// spacing / sqrt(3) + spacing / 8 ~ 0.702 spacing (< spacing / sqrt(2)) of a sample. Proof:
// (1) a point p of a triangle with longest edge l is within l / sqrt(3) of one of its corners.
//     The distance to the nearest corner is largest either at the circumcentre, if it lies in the
//     triangle, or on the boundary (inside one corner's Voronoi cell the distance to that corner
//     is convex, so its maximum is on the cell's border; along a bisector it grows away from the
//     edge's midpoint). The circumcentre lies in the triangle only if the angle g opposite l is
//     at most 90 deg, and g >= 60 deg as the largest angle, so R = l / (2 sin g) <= l / sqrt(3);
//     on an edge the nearer end point is at most l / 2 away.
// (2) The n^2 copies have longest edge l / n <= spacing, so p is within spacing / sqrt(3) of a
//     generated point, and that point was kept or dropped for a kept one within spacing / 8.
//
// Choosing the spacing: a grain whose centre reaches the surface at p is then within
// covering_radius of a boundary particle's centre. With boundary particles of radius r_b,
//   spacing <= sqrt(2) r_b     gives covering_radius < r_b: no grain of any size can even touch
//                              the surface without overlapping a boundary particle;
//   spacing <= sqrt(2) (r_b + r_min) is the bare minimum for grains of radius >= r_min (the
//                              grain's centre cannot reach the surface without overlap).
// The first is the recommended one: the overlap at the surface is then at least r_min.
#pragma once

#include <cstddef>
#include <vector>

#include "geometry/mesh.hpp"

namespace sandflow {

/// Largest number of samples sample_surface makes before merging (for all of a scene's meshes
/// together: Geometry::from_config): 20 million, which World's merge thins to about 5 million
/// boundary particles (a flat square of 7.89 m at 1 cm grains: 4,986,289 kept, 0.45 GB and 12 s
/// in `run --check`). A mesh finer than the spacing gives 3 samples a triangle, so this refuses
/// more than about 6.7 million triangles at the grains' spacing: decimate it.
inline constexpr std::size_t kMaxSurfaceSamples = 20'000'000;
/// How far from the origin a sampled surface may reach, in spacings: 2^40, where a double still
/// tells neighbouring samples apart to a part in 4,000 of the spacing (and the merge grid's cell
/// indices stay far inside 64 bits).
inline constexpr Real kMaxMeshSpacingsFromOrigin = 1'099'511'627'776.0;

/// The distance within which every surface point has a sample (see above).
constexpr Real covering_radius(Real spacing) {
  return spacing * (0.57735026918962576 + 0.125);
}

/// Samples covering every triangle (edges and vertices included), in a deterministic order.
/// spacing must be positive and finite (std::invalid_argument); InputError when the mesh would
/// need more than kMaxSurfaceSamples points at that spacing (refused before allocating).
/// `merge` (default, when 0: spacing / 8) replaces spacing / 8 above: every surface point is then
/// within spacing / sqrt(3) + merge of a sample, and no two samples are closer than merge. A
/// large merge with a small spacing thins a mesh finer than the spacing (a scan's vertices).
std::vector<Vec3> sample_surface(const TriangleMesh& mesh, Real spacing, Real merge = 0);

/// The check sample_surface makes first, for callers that build costlier things from the mesh
/// before sampling it: the samples sampling at `spacing` makes before merging, or InputError when
/// that is more than `budget` (what the scene's other meshes left of kMaxSurfaceSamples).
Real check_surface_sample_count(const TriangleMesh& mesh, Real spacing,
                                Real budget = static_cast<Real>(kMaxSurfaceSamples));

}  // namespace sandflow
