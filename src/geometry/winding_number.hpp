// The inside test of mesh obstacles: the generalised winding number (Jacobson et al. 2013),
//   w(q) = (1 / 4 pi) sum over triangles of the signed solid angle the triangle subtends at q,
// which is 1 inside and 0 outside a closed outward-oriented mesh, and degrades gracefully on
// open, non-manifold or self-intersecting meshes (a hole lowers w near it; inside stays
// w >= 1/2 away from it). Triangles are counter-clockwise seen from outside.
//
// Speed: the hierarchical approximation of Barill et al. 2018 ("Fast Winding Numbers for Soups
// and Clouds"). Each BVH node keeps the first two moments of its area-weighted normals about its
// area-weighted centre; a node whose bounding ball (radius r) is farther than beta * r from q
// contributes its second-order dipole expansion, nearer nodes are opened and their leaves
// summed exactly (van Oosterom & Strackee's solid angle). Error: each far node's truncation is
// second order in r / d < 1 / beta relative to its solid angle; at beta = 2 it is largest deep
// inside a mesh, where every node is far (0.04 at the centre of a 5,120-triangle sphere), and
// small near the surface, where the near nodes are exact, so the w >= 1/2 decision is safe.
// Measured: 200,000 points against an 81,920-triangle sphere in 0.36 s on 2 threads (beta 2;
// 0.72 s at beta 3), building the tree in 0.07 s.
#pragma once

#include <vector>

#include "geometry/mesh.hpp"
#include "geometry/triangle_bvh.hpp"

namespace sandflow {

class WindingNumber {
 public:
  /// beta: a node is approximated when farther than beta times its radius (>= 1; 2 is Barill's).
  explicit WindingNumber(const TriangleMesh& mesh, Real beta = 2.0);

  /// Generalised winding number at p (fast approximation).
  Real at(const Vec3& p) const;
  /// Winding numbers of many points, computed in parallel (OpenMP), in the points' order.
  std::vector<Real> at(const std::vector<Vec3>& points) const;
  bool inside(const Vec3& p) const { return at(p) >= 0.5; }

  /// Sorted heights where the vertical line through (x, y) crosses the mesh
  /// (vertical_crossings.hpp).
  std::vector<Real> vertical_crossings(Real x, Real y) const;

  const TriangleBvh& bvh() const { return bvh_; }

 private:
  /// The far-field expansion of one node.
  struct Moments {
    Vec3 centre;       ///< area-weighted centroid p~ [m]
    Real radius2 = 0;  ///< squared radius of a ball about p~ holding the node's triangles [m^2]
    Vec3 normal_sum;   ///< N = sum a_t n_t [m^2]
    Mat3 second;       ///< C = sum a_t n_t (c_t - p~)^T [m^3]
    Real area = 0;     ///< [m^2]
  };

  void compute_moments();
  Moments leaf_moments(const BvhNode& node) const;
  Moments merge(const Moments& a, const Moments& b) const;

  TriangleBvh bvh_;
  std::vector<Moments> moments_;  ///< one per bvh node
  Real beta2_;
};

/// Signed solid angle of triangle (a, b, c) seen from p [sr], in (-2 pi, 2 pi]; positive when p
/// is behind the triangle (on the side its counter-clockwise normal points away from).
Real solid_angle(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& p);

/// The exact winding number, summing every triangle: the reference the fast one is tested
/// against. O(triangles) per point.
Real winding_number_exact(const TriangleMesh& mesh, const Vec3& p);

}  // namespace sandflow
