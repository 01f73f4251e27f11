#include "geometry/mesh.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

#include "core/hash.hpp"

namespace sandflow {

void transform(TriangleMesh& mesh, Real scale, const Vec3& rotation_deg, const Vec3& translation) {
  if (!(scale > 0) || !std::isfinite(scale))
    throw std::invalid_argument("transform: scale must be positive and finite");
  const Mat3 rot = rotation_xyz_deg(rotation_deg);
  for (Vec3& v : mesh.vertices) v = rot * (v * scale) + translation;
}

Aabb mesh_bounds(const TriangleMesh& mesh) {
  Aabb box;
  for (const auto& t : mesh.triangles)
    for (std::uint32_t i : t) box.grow(mesh.vertices[i]);
  return box;
}

std::uint64_t mesh_digest(const TriangleMesh& mesh) {
  Hasher h;
  h.add(mesh.vertices.size());
  for (const Vec3& v : mesh.vertices) h.add(v);
  h.add(mesh.triangles.size());
  for (const auto& t : mesh.triangles) h.add(t);
  return h.value();
}

Real triangle_area(const TriangleMesh& mesh, std::size_t triangle) {
  const auto& t = mesh.triangles[triangle];
  const Vec3& a = mesh.vertices[t[0]];
  return 0.5 * norm(cross(mesh.vertices[t[1]] - a, mesh.vertices[t[2]] - a));
}

bool is_degenerate(const TriangleMesh& mesh, std::size_t triangle) {
  const auto& t = mesh.triangles[triangle];
  if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) return true;
  // zero area relative to the longest edge squared: collinear within rounding
  const Vec3 &a = mesh.vertices[t[0]], &b = mesh.vertices[t[1]], &c = mesh.vertices[t[2]];
  const Real longest2 = std::max({norm2(b - a), norm2(c - b), norm2(a - c)});
  return norm(cross(b - a, c - a)) <= 1e-12 * longest2;
}

MeshQuality mesh_quality(const TriangleMesh& mesh) {
  MeshQuality q;
  // every undirected edge of every triangle, sorted so that the uses of one edge are adjacent
  std::vector<std::pair<std::uint32_t, std::uint32_t>> edges;
  edges.reserve(3 * mesh.triangles.size());
  for (std::size_t i = 0; i < mesh.triangles.size(); ++i) {
    if (is_degenerate(mesh, i)) {
      ++q.degenerate_triangles;
      continue;
    }
    const auto& t = mesh.triangles[i];
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = t[k], b = t[(k + 1) % 3];
      edges.emplace_back(std::min(a, b), std::max(a, b));
    }
  }
  std::sort(edges.begin(), edges.end());
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i;
    while (j < edges.size() && edges[j] == edges[i]) ++j;
    ++q.edges;
    if (j - i == 1) ++q.boundary_edges;
    if (j - i >= 3) ++q.non_manifold_edges;
    i = j;
  }
  return q;
}

}  // namespace sandflow
