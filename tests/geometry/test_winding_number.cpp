// The winding-number inside test against closed forms (solid angles of squares) and against the
// exact sum, on closed, open and non-manifold meshes; vertical crossings on a cube and a sphere,
// including lines through shared edges and vertices.
#include "geometry/winding_number.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "core/rng.hpp"
#include "geometry/mesh.hpp"
#include "geometry/vertical_crossings.hpp"
#include "mesh_test_shapes.hpp"

namespace sandflow {
namespace {

using test::box_mesh;
using test::icosphere;

// Solid angle of a square of side 1 seen from a point on its axis at distance d:
// Omega = 4 asin(a b / sqrt((a^2 + 4 d^2)(b^2 + 4 d^2))) with a = b = 1.
Real square_solid_angle(Real d) {
  return 4 * std::asin(1 / (1 + 4 * d * d));
}

TEST(MeshWinding, SolidAngleOfTheCubeFacesFromTheCentre) {
  // each face subtends 4 pi / 6 at the centre; the formula above must agree with that
  EXPECT_NEAR(square_solid_angle(0.5), 4 * kPi / 6, 1e-14);
  const TriangleMesh cube = box_mesh({0, 0, 0}, {1, 1, 1});
  EXPECT_NEAR(winding_number_exact(cube, {0.5, 0.5, 0.5}), 1, 1e-14);
  EXPECT_NEAR(winding_number_exact(cube, {2.5, 0.5, 0.5}), 0, 1e-14);
}

// A closed cube: 1 inside, 0 outside. The 12 triangles make two leaves, so points within
// beta r ~ 1.7 of the centre are summed exactly (error ~1e-15) and points farther use the
// expansion, whose error at that distance is a few 1e-3 at most (measured below); the inside
// decision has a margin of 0.5.
TEST(MeshWinding, ClosedCubeInsideAndOutside) {
  const TriangleMesh cube = box_mesh({0, 0, 0}, {1, 1, 1});
  const WindingNumber wn(cube);
  Rng rng(7);
  int inside = 0;
  for (int i = 0; i < 2000; ++i) {
    const Vec3 p{rng.uniform(-1, 2), rng.uniform(-1, 2), rng.uniform(-1, 2)};
    const bool in_cube = p.x > 0 && p.x < 1 && p.y > 0 && p.y < 1 && p.z > 0 && p.z < 1;
    EXPECT_NEAR(wn.at(p), in_cube ? 1 : 0, 1e-2) << p.x << " " << p.y << " " << p.z;
    EXPECT_EQ(wn.inside(p), in_cube);
    inside += in_cube;
  }
  EXPECT_GT(inside, 40);  // the sample did test the inside (1 point in 27: 74 expected)
}

// Largest |fast - exact| over random points from the centre to three radii out.
Real max_fast_error(const TriangleMesh& mesh, Real beta) {
  const WindingNumber wn(mesh, beta);
  Rng rng(11);
  Real max_error = 0;
  for (int i = 0; i < 1500; ++i) {
    const Vec3 p{rng.uniform(-3, 3), rng.uniform(-3, 3), rng.uniform(-3, 3)};
    max_error = std::max(max_error, std::fabs(wn.at(p) - winding_number_exact(mesh, p)));
  }
  return max_error;
}

// Fast against exact on an icosphere of 5,120 triangles. A far node's expansion drops terms
// second order in r / d relative to its solid angle (r / d < 1 / beta). The error is largest
// deep inside, where every node is far and the cap-shaped nodes are least flat: 0.044 measured
// at beta = 2 near the centre, so the tolerance is 0.06; the inside decision there has a margin
// of 0.5, and near the surface the near nodes are summed exactly. Doubling beta must shrink
// the error at least twofold (it shrinks about fourfold if the expansion is right).
TEST(MeshWinding, FastAgreesWithExactOnASphere) {
  const TriangleMesh sphere = icosphere(4);
  const Real error2 = max_fast_error(sphere, 2.0), error4 = max_fast_error(sphere, 4.0);
  EXPECT_LT(error2, 0.06);
  EXPECT_LT(error4, 0.5 * error2);
  std::printf(
      "fast vs exact winding number, icosphere(4): max |error| %.2e (beta 2), %.2e (beta 4)\n",
      error2, error4);
  const WindingNumber wn(sphere);
  const Real r_in = test::inner_radius(sphere);
  Rng rng(13);
  for (int i = 0; i < 1500; ++i) {
    const Vec3 p{rng.uniform(-3, 3), rng.uniform(-3, 3), rng.uniform(-3, 3)};
    const Real exact = winding_number_exact(sphere, p);
    const Real r = norm(p);
    if (r < r_in) {
      EXPECT_NEAR(exact, 1, 1e-10);
      EXPECT_TRUE(wn.inside(p));
    }
    if (r > 1) {
      EXPECT_NEAR(exact, 0, 1e-10);
      EXPECT_FALSE(wn.inside(p));
    }
  }
}

// The batch query gives the single-point values, in order.
TEST(MeshWinding, BatchEqualsSingle) {
  const WindingNumber wn(icosphere(3));
  std::vector<Vec3> points;
  Rng rng(3);
  for (int i = 0; i < 500; ++i)
    points.push_back({rng.uniform(-2, 2), rng.uniform(-2, 2), rng.uniform(-2, 2)});
  const std::vector<Real> w = wn.at(points);
  for (std::size_t i = 0; i < points.size(); ++i) EXPECT_EQ(w[i], wn.at(points[i]));
}

// A cube without its top face. On the axis x = y = 1/2 the closed cube gives 1 inside and 0
// outside, and the missing face would add +Omega / 4 pi seen from inside (-Omega / 4 pi from
// above), so the open mesh gives 1 - Omega / 4 pi inside and Omega / 4 pi above, Omega the
// square's solid angle at distance d = |z - 1|. Both tend to 1/2 at the hole, and the centre
// gives 5/6 (five faces of 4 pi / 6 each): inside stays inside away from the hole.
TEST(MeshWinding, OpenCubeGivesTheSolidAngleOfItsHole) {
  const TriangleMesh open = box_mesh({0, 0, 0}, {1, 1, 1}, /*skip top*/ 1);
  EXPECT_EQ(mesh_quality(open).boundary_edges, 4u);
  const WindingNumber wn(open);
  EXPECT_NEAR(wn.at({0.5, 0.5, 0.5}), 5.0 / 6.0, 1e-12);
  EXPECT_NEAR(wn.at({0.5, 0.5, 1.0}), 0.5, 1e-12);  // in the plane of the hole
  for (Real z : {0.05, 0.3, 0.7, 0.95, 0.999}) {
    const Real omega = square_solid_angle(1 - z);
    EXPECT_NEAR(wn.at({0.5, 0.5, z}), 1 - omega / (4 * kPi), 1e-12) << z;
    EXPECT_TRUE(wn.inside({0.5, 0.5, z})) << z;
  }
  for (Real z : {1.001, 1.2, 1.5}) {  // above the hole: near enough to be summed exactly
    EXPECT_NEAR(wn.at({0.5, 0.5, z}), square_solid_angle(z - 1) / (4 * kPi), 1e-12) << z;
    EXPECT_FALSE(wn.inside({0.5, 0.5, z})) << z;
  }
}

// Two cubes sharing one edge (4 triangles on it): each cube's inside is inside, the two empty
// quadrants around the shared edge are outside.
TEST(MeshWinding, NonManifoldTwoCubesSharingAnEdge) {
  TriangleMesh m;
  test::append_box(m, {0, 0, 0}, {1, 1, 1});
  test::append_box(m, {1, 1, 0}, {2, 2, 1});
  EXPECT_EQ(m.vertices.size(), 14u);  // the shared edge's two vertices are welded
  const MeshQuality q = mesh_quality(m);
  EXPECT_EQ(q.non_manifold_edges, 1u);
  EXPECT_EQ(q.boundary_edges, 0u);
  const WindingNumber wn(m);
  for (const Vec3& p :
       {Vec3{0.5, 0.5, 0.5}, Vec3{1.5, 1.5, 0.5}, Vec3{0.99, 0.99, 0.5}, Vec3{1.01, 1.01, 0.5}}) {
    EXPECT_NEAR(wn.at(p), 1, 1e-9);
    EXPECT_TRUE(wn.inside(p));
  }
  for (const Vec3& p : {Vec3{1.5, 0.5, 0.5}, Vec3{0.5, 1.5, 0.5}, Vec3{1.01, 0.99, 0.5}}) {
    EXPECT_NEAR(wn.at(p), 0, 1e-9);
    EXPECT_FALSE(wn.inside(p));
  }
}

// A vertical line through the unit cube crosses its bottom and top once each, also exactly on
// the quads' diagonals, edges and corners: the perturbed line (x + e, y + e^2) is inside for
// 0 <= x < 1 and 0 <= y < 1, outside otherwise, and never counted twice.
TEST(MeshCrossings, CubeIncludingEdgesAndCorners) {
  const WindingNumber wn(box_mesh({0, 0, 0}, {1, 1, 1}));
  const auto z = wn.vertical_crossings(0.3, 0.6);
  ASSERT_EQ(z.size(), 2u);
  EXPECT_EQ(z[0], 0);
  EXPECT_EQ(z[1], 1);
  for (Real x : {-0.5, 0.0, 0.25, 0.5, 0.75, 1.0, 1.5})
    for (Real y : {-0.5, 0.0, 0.25, 0.5, 0.75, 1.0, 1.5}) {
      const bool in = x >= 0 && x < 1 && y >= 0 && y < 1;
      const auto c = wn.vertical_crossings(x, y);
      ASSERT_EQ(c.size(), in ? 2u : 0u) << x << " " << y;
      if (in) {
        EXPECT_EQ(c[1] - c[0], 1);
      }
    }
}

// On an icosphere every crossing lies on the mesh, so between its inner radius and 1; lines
// through the mesh's own vertices (shared by 5 or 6 triangles) and random lines inside the
// silhouette cross exactly twice, lines outside the unit circle never.
TEST(MeshCrossings, SphereThroughVerticesAndAtRandom) {
  const TriangleMesh sphere = icosphere(3);
  const WindingNumber wn(sphere);
  const Real r_in = test::inner_radius(sphere);
  std::vector<std::array<Real, 2>> lines;
  for (const Vec3& v : sphere.vertices)
    if (v.x * v.x + v.y * v.y < 0.99 * r_in * r_in) lines.push_back({v.x, v.y});
  Rng rng(5);
  for (int i = 0; i < 500; ++i)
    lines.push_back({rng.uniform(-r_in, r_in), rng.uniform(-r_in, r_in)});
  int tested = 0;
  for (const auto& [x, y] : lines) {
    if (x * x + y * y >= r_in * r_in) continue;
    ++tested;
    const auto z = wn.vertical_crossings(x, y);
    ASSERT_EQ(z.size(), 2u) << x << " " << y;
    for (Real zi : z) {
      const Real r2 = x * x + y * y + zi * zi;
      EXPECT_GE(r2, r_in * r_in * (1 - 1e-12));
      EXPECT_LE(r2, 1 + 1e-12);
    }
    EXPECT_LT(z[0], 0);
    EXPECT_GT(z[1], 0);
  }
  EXPECT_GT(tested, 400);
  EXPECT_TRUE(wn.vertical_crossings(1.01, 0).empty());
  EXPECT_TRUE(wn.vertical_crossings(0.8, 0.8).empty());
}

}  // namespace
}  // namespace sandflow
