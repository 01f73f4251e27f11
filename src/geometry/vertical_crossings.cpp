#include "geometry/vertical_crossings.hpp"

#include <algorithm>

namespace sandflow {

namespace {

struct EdgeSide {
  Real exact;  ///< twice the signed area of (a, b, p) in the xy plane
  bool left;   ///< p (perturbed) is on the left of a -> b
};

// Orientation of p relative to the edge a -> b, projected on xy. The edge is evaluated from its
// lexicographically smaller end, so both triangles sharing it compute bit-identical values; an
// exact zero is decided by the perturbation p + (e, e^2): first by the e term, then by e^2.
EdgeSide edge_side(const Vec3& a, const Vec3& b, Real x, Real y) {
  const bool swap = b.x < a.x || (b.x == a.x && b.y < a.y);
  const Vec3& s = swap ? b : a;
  const Vec3& e = swap ? a : b;
  const Real v = (e.x - s.x) * (y - s.y) - (e.y - s.y) * (x - s.x);
  Real sign = v;
  if (sign == 0) sign = -(e.y - s.y);
  if (sign == 0) sign = e.x - s.x;  // zero only for an edge that is a point in xy
  return {swap ? -v : v, (sign > 0) != swap};
}

// Adds the height at which the line crosses the triangle, if it does.
void cross_triangle(const TriangleCorners& t, Real x, Real y, std::vector<Real>& out) {
  const EdgeSide ab = edge_side(t.a, t.b, x, y);
  const EdgeSide bc = edge_side(t.b, t.c, x, y);
  const EdgeSide ca = edge_side(t.c, t.a, x, y);
  if (ab.left != bc.left || bc.left != ca.left) return;
  // barycentric weights: the area opposite each corner
  const Real wa = bc.exact, wb = ca.exact, wc = ab.exact;
  const Real sum = wa + wb + wc;
  if (sum == 0) return;  // seen edge-on: a vertical triangle
  out.push_back((wa * t.a.z + wb * t.b.z + wc * t.c.z) / sum);
}

bool holds_xy(const Aabb& box, Real x, Real y) {
  return box.lo.x <= x && x <= box.hi.x && box.lo.y <= y && y <= box.hi.y;
}

}  // namespace

std::vector<Real> vertical_crossings(const TriangleBvh& bvh, Real x, Real y) {
  std::vector<Real> z;
  if (bvh.triangles().empty()) return z;
  const auto& nodes = bvh.nodes();
  std::uint32_t stack[128];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const BvhNode& node = nodes[stack[--top]];
    if (!holds_xy(node.box, x, y)) continue;
    if (node.leaf()) {
      for (std::uint32_t i = node.first; i < node.first + node.count; ++i)
        cross_triangle(bvh.triangles()[i], x, y, z);
    } else {
      stack[top++] = node.left();
      stack[top++] = node.right();
    }
  }
  std::sort(z.begin(), z.end());
  return z;
}

}  // namespace sandflow
