// A bounding-volume hierarchy over the triangles of a mesh, shared by the winding-number inside
// test and the vertical ray casts. Built once per obstacle; queries never modify it, so any
// number of threads may query it at once.
//
// Median split on the longest axis of the triangles' box centres: simple, deterministic (ties are
// broken by triangle index) and good enough for meshes that are built once and queried often.
#pragma once

#include <cstdint>
#include <vector>

#include "geometry/mesh.hpp"

namespace sandflow {

struct BvhNode {
  Aabb box;
  std::uint32_t first = 0;  ///< leaf: first triangle (in bvh order); inner: left child
  std::uint32_t count = 0;  ///< leaf: number of triangles; 0 for an inner node
  bool leaf() const { return count > 0; }
  std::uint32_t left() const { return first; }
  std::uint32_t right() const { return first + 1; }
};

/// A triangle's corners, copied out of the mesh in the order the tree visits them.
struct TriangleCorners {
  Vec3 a, b, c;
};

class TriangleBvh {
 public:
  static constexpr std::uint32_t kLeafSize = 8;

  explicit TriangleBvh(const TriangleMesh& mesh);

  const std::vector<BvhNode>& nodes() const { return nodes_; }
  /// Corners of triangle `i` in bvh order (leaves index this array).
  const std::vector<TriangleCorners>& triangles() const { return triangles_; }
  /// Mesh index of the triangle at bvh position `i`.
  const std::vector<std::uint32_t>& mesh_index() const { return mesh_index_; }

 private:
  void build(std::uint32_t node, std::uint32_t first, std::uint32_t count,
             const std::vector<Aabb>& boxes);

  std::vector<BvhNode> nodes_;  ///< nodes_[0] is the root; children are stored as pairs
  std::vector<std::uint32_t> mesh_index_;
  std::vector<TriangleCorners> triangles_;
};

}  // namespace sandflow
