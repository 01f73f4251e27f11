// Triangle meshes for obstacles (docs/design.md §6): the plain data every mesh reader produces, the
// placement a scene gives it, and the checks a scene reports ("open mesh").
//
// A mesh is a triangle soup with shared vertex indices; nothing here assumes it is closed,
// manifold or consistently oriented. The inside test (winding_number.hpp) and the surface
// sampling (mesh_sampling.hpp) are written to cope with such meshes.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/vec3.hpp"

namespace sandflow {

struct TriangleMesh {
  std::vector<Vec3> vertices;  ///< [m]
  std::vector<std::array<std::uint32_t, 3>>
      triangles;  ///< vertex indices, counter-clockwise seen from outside
};

/// Axis-aligned box.
struct Aabb {
  Vec3 lo{kInf, kInf, kInf};
  Vec3 hi{-kInf, -kInf, -kInf};

  static constexpr Real kInf = 1e300;
  void grow(const Vec3& p) {
    lo = min(lo, p);
    hi = max(hi, p);
  }
  void grow(const Aabb& b) {
    lo = min(lo, b.lo);
    hi = max(hi, b.hi);
  }
  bool empty() const { return lo.x > hi.x; }
};

/// Scales about the origin, rotates about x, then y, then z (degrees), then translates:
/// p -> R (scale p) + translation. scale must be positive and finite (std::invalid_argument).
void transform(TriangleMesh& mesh, Real scale, const Vec3& rotation_deg, const Vec3& translation);

/// Bounds of the vertices used by some triangle (empty Aabb for a mesh without triangles).
Aabb mesh_bounds(const TriangleMesh& mesh);

/// Counts that tell whether a mesh bounds a solid.
struct MeshQuality {
  std::size_t edges = 0;                 ///< distinct undirected edges
  std::size_t boundary_edges = 0;        ///< used by one triangle: the mesh has a hole
  std::size_t non_manifold_edges = 0;    ///< used by three or more triangles
  std::size_t degenerate_triangles = 0;  ///< repeated vertex or zero area
  bool closed() const { return boundary_edges == 0; }
  bool manifold() const { return non_manifold_edges == 0; }
};

MeshQuality mesh_quality(const TriangleMesh& mesh);

/// True when the triangle has a repeated vertex or (numerically) zero area.
bool is_degenerate(const TriangleMesh& mesh, std::size_t triangle);

/// A hash of the vertices and triangles, bit for bit: tells a mesh drawn later from the one a
/// run's grains met (the same file edited since gives another digest).
std::uint64_t mesh_digest(const TriangleMesh& mesh);

/// Area of a triangle [m^2].
Real triangle_area(const TriangleMesh& mesh, std::size_t triangle);

}  // namespace sandflow
