#include "geometry/triangle_bvh.hpp"

#include <algorithm>
#include <numeric>

namespace sandflow {

namespace {
Vec3 centre(const Aabb& b) {
  return (b.lo + b.hi) * 0.5;
}
}  // namespace

TriangleBvh::TriangleBvh(const TriangleMesh& mesh) {
  const auto n = static_cast<std::uint32_t>(mesh.triangles.size());
  std::vector<Aabb> boxes(n);
  for (std::uint32_t i = 0; i < n; ++i)
    for (std::uint32_t v : mesh.triangles[i]) boxes[i].grow(mesh.vertices[v]);
  mesh_index_.resize(n);
  std::iota(mesh_index_.begin(), mesh_index_.end(), 0u);
  nodes_.reserve(2 * (n / kLeafSize + 1));
  nodes_.emplace_back();
  if (n > 0) build(0, 0, n, boxes);
  // copy the corners in leaf order, so a leaf's triangles are contiguous in memory
  triangles_.resize(n);
  for (std::uint32_t i = 0; i < n; ++i) {
    const auto& t = mesh.triangles[mesh_index_[i]];
    triangles_[i] = {mesh.vertices[t[0]], mesh.vertices[t[1]], mesh.vertices[t[2]]};
  }
}

void TriangleBvh::build(std::uint32_t node, std::uint32_t first, std::uint32_t count,
                        const std::vector<Aabb>& boxes) {
  // bounds of the triangles (for queries) and of their box centres (for the split)
  Aabb box, centre_box;
  for (std::uint32_t i = first; i < first + count; ++i) {
    box.grow(boxes[mesh_index_[i]]);
    centre_box.grow(centre(boxes[mesh_index_[i]]));
  }
  nodes_[node].box = box;
  if (count <= kLeafSize) {
    nodes_[node].first = first;
    nodes_[node].count = count;
    return;
  }
  // median split on the longest axis of the centroids; ties broken by index for determinism
  const Vec3 extent = centre_box.hi - centre_box.lo;
  const int axis =
      extent.x >= extent.y && extent.x >= extent.z ? 0 : (extent.y >= extent.z ? 1 : 2);
  const std::uint32_t half = count / 2;
  auto begin = mesh_index_.begin() + first;
  std::nth_element(begin, begin + half, begin + count, [&](std::uint32_t a, std::uint32_t b) {
    const Real ca = centre(boxes[a])[axis], cb = centre(boxes[b])[axis];
    return ca < cb || (ca == cb && a < b);
  });
  const auto left = static_cast<std::uint32_t>(nodes_.size());
  nodes_.emplace_back();
  nodes_.emplace_back();
  nodes_[node].first = left;
  nodes_[node].count = 0;
  build(left, first, half, boxes);
  build(left + 1, first + half, count - half, boxes);
}

}  // namespace sandflow
