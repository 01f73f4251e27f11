#include "geometry/winding_number.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "geometry/vertical_crossings.hpp"

namespace sandflow {

namespace {

constexpr Real kFourPi = 4 * kPi;

Mat3 zero_matrix() {
  Mat3 m;
  for (auto& row : m.m)
    for (Real& v : row) v = 0;
  return m;
}

// m += u v^T
void add_outer(Mat3& m, const Vec3& u, const Vec3& v, Real scale) {
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) m.m[i][j] += scale * u[i] * v[j];
}

// The second-order far field of a node at q: with r = p~ - q and d = |r|,
//   Omega ~ (N.r + tr C) / d^3 - 3 r^T C r / d^5
// from expanding n.(x - q) / |x - q|^3 about p~ to first order in x - p~ and integrating.
Real far_solid_angle(const Vec3& centre, const Vec3& normal_sum, const Mat3& c, const Vec3& q) {
  const Vec3 r = centre - q;
  const Real d2 = norm2(r);
  const Real inv_d3 = 1 / (d2 * std::sqrt(d2));
  const Vec3 cr = c * r;
  const Real trace = c.m[0][0] + c.m[1][1] + c.m[2][2];
  return (dot(normal_sum, r) + trace) * inv_d3 - 3 * dot(r, cr) * inv_d3 / d2;
}

}  // namespace

Real solid_angle(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& p) {
  // van Oosterom & Strackee (1983): tan(Omega / 2) = det[a b c] / (|a||b||c| + ...)
  const Vec3 u = a - p, v = b - p, w = c - p;
  const Real lu = norm(u), lv = norm(v), lw = norm(w);
  const Real det = dot(u, cross(v, w));
  const Real den = lu * lv * lw + dot(u, v) * lw + dot(v, w) * lu + dot(w, u) * lv;
  return 2 * std::atan2(det, den);
}

Real winding_number_exact(const TriangleMesh& mesh, const Vec3& p) {
  Real sum = 0;
  for (const auto& t : mesh.triangles)
    sum += solid_angle(mesh.vertices[t[0]], mesh.vertices[t[1]], mesh.vertices[t[2]], p);
  return sum / kFourPi;
}

WindingNumber::WindingNumber(const TriangleMesh& mesh, Real beta)
    : bvh_(mesh), beta2_(beta * beta) {
  if (!(beta >= 1)) throw std::invalid_argument("WindingNumber: beta must be >= 1");
  compute_moments();
}

WindingNumber::Moments WindingNumber::leaf_moments(const BvhNode& node) const {
  Moments m;
  m.second = zero_matrix();
  const auto& tris = bvh_.triangles();
  Vec3 weighted;
  for (std::uint32_t i = node.first; i < node.first + node.count; ++i) {
    const TriangleCorners& t = tris[i];
    const Vec3 area_normal = cross(t.b - t.a, t.c - t.a) * 0.5;  // a_t n_t
    const Real area = norm(area_normal);
    m.normal_sum += area_normal;
    m.area += area;
    weighted += (t.a + t.b + t.c) * (area / 3);
  }
  m.centre = m.area > 0 ? weighted / m.area : (node.box.lo + node.box.hi) * 0.5;
  for (std::uint32_t i = node.first; i < node.first + node.count; ++i) {
    const TriangleCorners& t = tris[i];
    add_outer(m.second, cross(t.b - t.a, t.c - t.a) * 0.5, (t.a + t.b + t.c) / 3 - m.centre, 1);
    for (const Vec3& v : {t.a, t.b, t.c}) m.radius2 = std::max(m.radius2, norm2(v - m.centre));
  }
  return m;
}

// Moments of a parent from its children's: C moves to the new centre by N_child (p~_child - p~)^T.
WindingNumber::Moments WindingNumber::merge(const Moments& a, const Moments& b) const {
  Moments m;
  m.area = a.area + b.area;
  m.normal_sum = a.normal_sum + b.normal_sum;
  m.centre =
      m.area > 0 ? (a.centre * a.area + b.centre * b.area) / m.area : (a.centre + b.centre) * 0.5;
  m.second = zero_matrix();
  for (const Moments* child : {&a, &b}) {
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) m.second.m[i][j] += child->second.m[i][j];
    add_outer(m.second, child->normal_sum, child->centre - m.centre, 1);
    const Real reach = norm(child->centre - m.centre) + std::sqrt(child->radius2);
    m.radius2 = std::max(m.radius2, reach * reach);
  }
  return m;
}

void WindingNumber::compute_moments() {
  const auto& nodes = bvh_.nodes();
  moments_.resize(nodes.size());
  // children are stored after their parent: a reverse sweep sees children first
  for (std::size_t k = nodes.size(); k-- > 0;) {
    const BvhNode& node = nodes[k];
    if (bvh_.triangles().empty()) break;
    moments_[k] =
        node.leaf() ? leaf_moments(node) : merge(moments_[node.left()], moments_[node.right()]);
  }
}

Real WindingNumber::at(const Vec3& p) const {
  if (bvh_.triangles().empty()) return 0;
  const auto& nodes = bvh_.nodes();
  const auto& tris = bvh_.triangles();
  std::uint32_t stack[128];
  int top = 0;
  stack[top++] = 0;
  Real omega = 0;
  while (top > 0) {
    const std::uint32_t k = stack[--top];
    const Moments& m = moments_[k];
    // far enough: the node's expansion; near: open it
    if (norm2(m.centre - p) > beta2_ * m.radius2) {
      omega += far_solid_angle(m.centre, m.normal_sum, m.second, p);
      continue;
    }
    const BvhNode& node = nodes[k];
    if (node.leaf()) {
      for (std::uint32_t i = node.first; i < node.first + node.count; ++i)
        omega += solid_angle(tris[i].a, tris[i].b, tris[i].c, p);
    } else {
      stack[top++] = node.left();
      stack[top++] = node.right();
    }
  }
  return omega / kFourPi;
}

std::vector<Real> WindingNumber::at(const std::vector<Vec3>& points) const {
  std::vector<Real> w(points.size());
  const auto n = static_cast<std::ptrdiff_t>(points.size());
#pragma omp parallel for schedule(dynamic, 512)
  for (std::ptrdiff_t i = 0; i < n; ++i)
    w[static_cast<std::size_t>(i)] = at(points[static_cast<std::size_t>(i)]);
  return w;
}

std::vector<Real> WindingNumber::vertical_crossings(Real x, Real y) const {
  return sandflow::vertical_crossings(bvh_, x, y);
}

}  // namespace sandflow
