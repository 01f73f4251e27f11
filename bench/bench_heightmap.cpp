// Heightmap obstacles: what a contact query costs on a smooth terrain and on rough ones.
//   bench_heightmap [queries]   (default 200,000, on all threads: OMP_NUM_THREADS)
// Four terrains over 1.6 m x 1.6 m, 1 cm grains (reach 1.1 cm, the largest diameter of
// scenes/terrain.toml): that scene's noise (wavelength 0.5 m, 0.15 m high), flat, noise of 5 cm
// wavelength 2 cm high, and random samples 1 cm high every 1.6 cm, 4 mm and 0.8 mm (a grid finer
// than the grains). Queries lie within reach above the surface, where grains touch it. Prints
// the build time, microseconds per query, and the queries that stopped at the cap (the worst
// spot's lower bound, docs/known-issues.md).
#include <omp.h>

#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "core/rng.hpp"
#include "core/timer.hpp"
#include "geometry/heightmap.hpp"
#include "support/random_grid.hpp"  // (tests/support: the grids the tests query)

using namespace sandflow;
using sandflow::test::random_grid;

namespace {

constexpr std::array<Real, 4> kExtent{-0.8, -0.8, 0.8, 0.8};
constexpr Real kReach = 0.011;

void run(const std::string& name, const HeightGrid& grid, std::size_t queries) {
  Stopwatch build;
  const SolidHeightmap h(grid, kExtent, 0.01, kReach);
  const double build_s = build.seconds();
  // points within reach above the surface, away from the edges (as grains resting on it or
  // landing)
  Rng rng(7);
  std::vector<Vec3> points(queries);
  for (Vec3& p : points) {
    p.x = rng.uniform(-0.7, 0.7);
    p.y = rng.uniform(-0.7, 0.7);
    p.z = h.height(p.x, p.y) + rng.uniform(0.0, kReach);
  }
  (void)h.closest(points[0]);
  Stopwatch query;
  Real sum = 0;
#pragma omp parallel for reduction(+ : sum) schedule(static)
  for (std::size_t k = 0; k < points.size(); ++k) sum += h.closest(points[k]).distance;
  const double query_s = query.seconds();
  std::printf(
      "%-30s %5d^2 samples  build %6.3f s  %7.3f us/query  capped %lld  (mean distance "
      "%.2f mm)\n",
      name.c_str(), grid.nx, build_s, 1e6 * query_s * omp_get_max_threads() / queries,
      static_cast<long long>(h.capped_queries()), 1e3 * sum / queries);
}

}  // namespace

int main(int argc, char** argv) {
  const std::size_t queries = argc > 1 ? std::strtoull(argv[1], nullptr, 10) : 200000;
  std::printf("%zu queries within %.0f mm above each terrain, %d threads (us/query: per thread)\n",
              queries, 1e3 * kReach, omp_get_max_threads());
  HeightGrid flat;
  flat.nx = flat.ny = 2;
  flat.z = {0, 0, 0, 0};
  run("flat", flat, queries);
  run("terrain scene (noise 0.5 m)", noise_heights(kExtent, 0.5, 3, 0.0, 0.15), queries);
  run("noise 5 cm, 2 cm high", noise_heights(kExtent, 0.05, 3, 0.0, 0.02), queries);
  run("random 1 cm every 1.6 cm", random_grid(101, 0.01, 17), queries);
  run("random 1 cm every 4 mm", random_grid(401, 0.01, 17), queries);
  run("random 1 cm every 0.8 mm", random_grid(2001, 0.01, 17), queries);
}
