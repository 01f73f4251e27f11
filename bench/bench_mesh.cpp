// Mesh obstacles: the cost of the inside test and of surface sampling on a sphere-like mesh.
//   bench_mesh [levels]   icosphere of 20 * 4^levels triangles (default 6: 81,920)
// Prints the tree build time, 200,000 winding-number queries (all threads, OMP_NUM_THREADS),
// the largest error against the exact sum at 200 of them, and sample counts at a few spacings.
#include <omp.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <vector>

#include "core/rng.hpp"
#include "core/timer.hpp"
#include "geometry/mesh_sampling.hpp"
#include "geometry/winding_number.hpp"

using namespace sandflow;

namespace {

TriangleMesh icosphere(int levels) {
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
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> mid;
    auto midpoint = [&](std::uint32_t a, std::uint32_t b) {
      const auto key = std::minmax(a, b);
      if (auto it = mid.find(key); it != mid.end()) return it->second;
      const Vec3 p = m.vertices[a] + m.vertices[b];
      m.vertices.push_back(p / norm(p));
      return mid[key] = static_cast<std::uint32_t>(m.vertices.size() - 1);
    };
    std::vector<std::array<std::uint32_t, 3>> finer;
    for (const auto& f : m.triangles) {
      const auto ab = midpoint(f[0], f[1]), bc = midpoint(f[1], f[2]), ca = midpoint(f[2], f[0]);
      finer.insert(finer.end(), {{f[0], ab, ca}, {f[1], bc, ab}, {f[2], ca, bc}, {ab, bc, ca}});
    }
    m.triangles = std::move(finer);
  }
  return m;
}

}  // namespace

int main(int argc, char** argv) {
  const int levels = argc > 1 ? std::atoi(argv[1]) : 6;
  const TriangleMesh sphere = icosphere(levels);
  std::printf("icosphere: %zu triangles, %d threads\n", sphere.triangles.size(),
              omp_get_max_threads());
  Rng rng(2);
  std::vector<Vec3> points(200000);
  for (Vec3& p : points)
    p = {rng.uniform(-1.5, 1.5), rng.uniform(-1.5, 1.5), rng.uniform(-1.5, 1.5)};
  for (Real beta : {2.0, 3.0}) {
    Stopwatch build;
    const WindingNumber wn(sphere, beta);
    const double build_s = build.seconds();
    (void)wn.at(std::vector<Vec3>(points.begin(), points.begin() + 1000));  // warm up
    Stopwatch query;
    const std::vector<Real> w = wn.at(points);
    const double query_s = query.seconds();
    Real max_error = 0;
    for (std::size_t i = 0; i < 200; ++i)
      max_error = std::max(max_error,
                           std::fabs(w[i * 997] - winding_number_exact(sphere, points[i * 997])));
    std::printf("beta %.0f: build %.3f s, %zu queries %.3f s (%.2f us each), max error %.1e\n",
                beta, build_s, points.size(), query_s,
                1e6 * query_s / static_cast<double>(points.size()), max_error);
  }
  for (Real spacing : {0.1, 0.05, 0.02}) {
    Stopwatch s;
    const auto samples = sample_surface(sphere, spacing);
    std::printf("sampling at spacing %.2f: %zu points (%.3f s)\n", spacing, samples.size(),
                s.seconds());
  }
}
