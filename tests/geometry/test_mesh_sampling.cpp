// Surface sampling: the covering bound proved in mesh_sampling.hpp holds at random surface
// points, shared edges and vertices are not sampled twice, and the output is deterministic.
#include "geometry/mesh_sampling.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "core/error.hpp"
#include "core/rng.hpp"
#include "mesh_test_shapes.hpp"

namespace sandflow {
namespace {

// A point uniformly distributed on the mesh (triangle by area, then barycentric).
Vec3 random_surface_point(const TriangleMesh& m, Rng& rng) {
  Real total = 0;
  for (std::size_t i = 0; i < m.triangles.size(); ++i) total += triangle_area(m, i);
  Real pick = rng.uniform(0, total);
  std::size_t t = 0;
  while (t + 1 < m.triangles.size() && pick > triangle_area(m, t)) pick -= triangle_area(m, t++);
  Real u = rng.uniform(), v = rng.uniform();
  if (u + v > 1) u = 1 - u, v = 1 - v;
  const auto& tri = m.triangles[t];
  const Vec3& a = m.vertices[tri[0]];
  return a + (m.vertices[tri[1]] - a) * u + (m.vertices[tri[2]] - a) * v;
}

Real nearest_distance(const std::vector<Vec3>& samples, const Vec3& p) {
  Real best = 1e300;
  for (const Vec3& s : samples) best = std::min(best, norm2(s - p));
  return std::sqrt(best);
}

// Largest distance from random surface points (and the mesh's vertices and edge midpoints,
// where the neighbours' samples meet) to the nearest sample.
Real largest_gap(const TriangleMesh& m, const std::vector<Vec3>& samples, int points) {
  Rng rng(17);
  Real gap = 0;
  for (int i = 0; i < points; ++i)
    gap = std::max(gap, nearest_distance(samples, random_surface_point(m, rng)));
  for (const auto& t : m.triangles)
    for (int k = 0; k < 3; ++k) {
      const Vec3 mid = (m.vertices[t[k]] + m.vertices[t[(k + 1) % 3]]) * 0.5;
      gap = std::max(
          {gap, nearest_distance(samples, mid), nearest_distance(samples, m.vertices[t[k]])});
    }
  return gap;
}

// The bound is a theorem (mesh_sampling.hpp), so it must hold for every point; 1e-12 relative
// covers rounding. A cube (right-angled triangles), a sphere (near-equilateral) and a sliver
// (an obtuse triangle 50 times longer than it is wide).
TEST(MeshSampling, EverySurfacePointIsWithinTheCoveringRadius) {
  TriangleMesh sliver;
  sliver.vertices = {{0, 0, 0}, {5, 0, 0}, {2.5, 0.1, 0.02}};
  sliver.triangles = {{0, 1, 2}};
  struct Case {
    const char* name;
    TriangleMesh mesh;
    Real spacing;
  };
  const Case cases[] = {{"cube", test::box_mesh({0, 0, 0}, {1, 1, 1}), 0.3},
                        {"sphere", test::icosphere(2), 0.1},
                        {"sliver", sliver, 0.2}};
  for (const Case& c : cases) {
    const auto samples = sample_surface(c.mesh, c.spacing);
    const Real gap = largest_gap(c.mesh, samples, 3000);
    EXPECT_LE(gap, covering_radius(c.spacing) * (1 + 1e-12)) << c.name;
    EXPECT_LT(covering_radius(c.spacing), c.spacing / std::sqrt(2.0));
    std::printf("%s: %zu samples at spacing %.2f, largest gap %.3f (bound %.3f)\n", c.name,
                samples.size(), c.spacing, gap, covering_radius(c.spacing));
  }
}

// No two samples closer than the merge tolerance spacing / 8: the points generated twice along
// shared edges and at shared vertices are gone. Checked by brute force.
TEST(MeshSampling, SharedEdgesAndVerticesAreNotDuplicated) {
  const Real spacing = 0.1;
  const auto samples = sample_surface(test::icosphere(2), spacing);
  for (std::size_t i = 0; i < samples.size(); ++i)
    for (std::size_t j = i + 1; j < samples.size(); ++j)
      ASSERT_GT(norm(samples[i] - samples[j]), spacing / 8) << i << " " << j;
}

// A unit sphere at spacing 0.05: an equilateral lattice of side s has 2 / (sqrt(3) s^2) points
// a unit area, 5,800 on the sphere's 4 pi. The count must be near that: above it (the copies'
// edges are at most s, so the lattice is at least as dense) and below 2.5 times it (duplicates
// along edges would add about one more point per edge sample of each triangle).
TEST(MeshSampling, UnitSphereCountIsNearTheLatticeDensity) {
  const TriangleMesh sphere = test::icosphere(4);  // 5,120 triangles, edges ~0.06
  const Real spacing = 0.05;
  const auto samples = sample_surface(sphere, spacing);
  Real area = 0;
  for (std::size_t i = 0; i < sphere.triangles.size(); ++i) area += triangle_area(sphere, i);
  const Real lattice = area * 2 / (std::sqrt(3.0) * spacing * spacing);
  std::printf("unit icosphere(4), spacing %.2f: %zu samples (equilateral lattice: %.0f)\n", spacing,
              samples.size(), lattice);
  EXPECT_GT(static_cast<Real>(samples.size()), lattice);
  EXPECT_LT(static_cast<Real>(samples.size()), 2.5 * lattice);
}

TEST(MeshSampling, DeterministicAndChecked) {
  const TriangleMesh cube = test::box_mesh({0, 0, 0}, {1, 1, 1});
  EXPECT_EQ(sample_surface(cube, 0.2), sample_surface(cube, 0.2));
  EXPECT_THROW(sample_surface(cube, 0.0), std::invalid_argument);
  EXPECT_THROW(sample_surface(cube, std::nan("")), std::invalid_argument);
  // 1e-5 m on a unit cube: ~10^11 points, refused before allocating
  EXPECT_THROW(sample_surface(cube, 1e-5), InputError);
}

}  // namespace
}  // namespace sandflow
