// Meshes built in code for the geometry tests: boxes (welded when they touch) and icospheres.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <map>
#include <utility>
#include <vector>

#include "geometry/mesh.hpp"

namespace sandflow::test {

/// Index of a vertex at exactly p, added when there is none (so touching boxes share vertices).
inline std::uint32_t weld(TriangleMesh& m, const Vec3& p) {
  for (std::uint32_t i = 0; i < m.vertices.size(); ++i)
    if (m.vertices[i] == p) return i;
  m.vertices.push_back(p);
  return static_cast<std::uint32_t>(m.vertices.size() - 1);
}

/// Appends the closed box [lo, hi], outward counter-clockwise, each face split along the same
/// diagonal as the quads of tests/data/meshes/cube.*; `skip_face` (0..5, -1 none) leaves one
/// out: 0 bottom, 1 top, 2 front (y = lo), 3 back, 4 left (x = lo), 5 right.
inline void append_box(TriangleMesh& m, const Vec3& lo, const Vec3& hi, int skip_face = -1) {
  std::uint32_t v[8];
  for (int i = 0; i < 8; ++i) {
    const int bx = (i == 1 || i == 2 || i == 5 || i == 6),
              by = (i == 2 || i == 3 || i == 6 || i == 7);
    v[i] = weld(m, {bx ? hi.x : lo.x, by ? hi.y : lo.y, i >= 4 ? hi.z : lo.z});
  }
  static constexpr int kFaces[6][4] = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4},
                                       {2, 3, 7, 6}, {0, 4, 7, 3}, {1, 2, 6, 5}};
  for (int f = 0; f < 6; ++f) {
    if (f == skip_face) continue;
    const int* q = kFaces[f];
    m.triangles.push_back({v[q[0]], v[q[1]], v[q[2]]});
    m.triangles.push_back({v[q[0]], v[q[2]], v[q[3]]});
  }
}

inline TriangleMesh box_mesh(const Vec3& lo, const Vec3& hi, int skip_face = -1) {
  TriangleMesh m;
  append_box(m, lo, hi, skip_face);
  return m;
}

/// Unit icosphere: an icosahedron subdivided `levels` times (20 * 4^levels triangles), every
/// vertex on the unit sphere, outward counter-clockwise.
inline TriangleMesh icosphere(int levels) {
  const Real t = (1 + std::sqrt(5.0)) / 2;
  TriangleMesh m;
  for (const Vec3& p : {Vec3{-1, t, 0}, Vec3{1, t, 0}, Vec3{-1, -t, 0}, Vec3{1, -t, 0},
                        Vec3{0, -1, t}, Vec3{0, 1, t}, Vec3{0, -1, -t}, Vec3{0, 1, -t},
                        Vec3{t, 0, -1}, Vec3{t, 0, 1}, Vec3{-t, 0, -1}, Vec3{-t, 0, 1}})
    m.vertices.push_back(p / norm(p));
  m.triangles = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                 {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                 {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                 {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (int level = 0; level < levels; ++level) {
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> midpoints;
    auto midpoint = [&](std::uint32_t a, std::uint32_t b) {
      const auto key = std::minmax(a, b);
      const auto it = midpoints.find(key);
      if (it != midpoints.end()) return it->second;
      const Vec3 p = m.vertices[a] + m.vertices[b];
      m.vertices.push_back(p / norm(p));
      const auto index = static_cast<std::uint32_t>(m.vertices.size() - 1);
      midpoints[key] = index;
      return index;
    };
    std::vector<std::array<std::uint32_t, 3>> finer;
    for (const auto& tri : m.triangles) {
      const std::uint32_t ab = midpoint(tri[0], tri[1]), bc = midpoint(tri[1], tri[2]),
                          ca = midpoint(tri[2], tri[0]);
      finer.push_back({tri[0], ab, ca});
      finer.push_back({tri[1], bc, ab});
      finer.push_back({tri[2], ca, bc});
      finer.push_back({ab, bc, ca});
    }
    m.triangles = std::move(finer);
  }
  return m;
}

/// Smallest distance from the origin to a triangle's plane: the mesh lies between this radius
/// and 1 (vertices on the unit sphere, flat faces).
inline Real inner_radius(const TriangleMesh& m) {
  Real r = 1;
  for (const auto& t : m.triangles) {
    const Vec3 &a = m.vertices[t[0]], &b = m.vertices[t[1]], &c = m.vertices[t[2]];
    const Vec3 n = cross(b - a, c - a);
    r = std::min(r, std::fabs(dot(n, a)) / norm(n));
  }
  return r;
}

}  // namespace sandflow::test
