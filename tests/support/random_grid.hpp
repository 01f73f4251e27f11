// A heightmap's grid of random heights: the roughest surface a grain can meet. Shared by the
// heightmap's tests and its benchmark (bench/bench_heightmap.cpp), which query the same grids.
#pragma once

#include <cstdint>

#include "core/rng.hpp"
#include "geometry/heightmap.hpp"

namespace sandflow::test {

/// Random heights in [0, amplitude] on an nx x ny grid, the same for the same seed.
inline HeightGrid random_grid(int nx, int ny, Real amplitude, std::uint64_t seed) {
  HeightGrid g;
  g.nx = nx;
  g.ny = ny;
  Rng rng(seed);
  for (int k = 0; k < nx * ny; ++k) g.z.push_back(rng.uniform(0.0, amplitude));
  return g;
}

/// The same on a side x side grid.
inline HeightGrid random_grid(int side, Real amplitude, std::uint64_t seed) {
  return random_grid(side, side, amplitude, seed);
}

}  // namespace sandflow::test
