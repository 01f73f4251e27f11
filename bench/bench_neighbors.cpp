// The pair list's build (src/dem/neighbor_list.cpp) on its own: a bed of equal grains packed at
// rest (geometry/bed_packing.hpp), sorted by cell as the solver sorts them, its list built again
// and again from the last one (the history carried, no grain moved to another slot).
//   bed    every grain ACTIVE, each allowed a tenth of a diameter (the default skin's half)
//   shell  the top three diameters ACTIVE, the two under them frozen (INTERFACE, no allowance),
//          a tenth of the ACTIVE grains allowed a diameter (a surface run's fast grains)
// Prints the pairs and the time per build (mean and best).
//
//   build/bench/bench_neighbors [--case bed|shell] [--grains N] [--builds K] [--check]
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numeric>
#include <string>
#include <vector>

#include "core/rng.hpp"
#include "dem/dem_solver.hpp"
#include "dem/grains.hpp"
#include "dem/neighbor_list.hpp"
#include "geometry/bed_packing.hpp"

using namespace sandflow;

namespace {

constexpr Real kD = 0.002;

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

int main(int argc, char** argv) {
  std::string which = "bed";
  double grains_wanted = 100'000;
  int builds = 50;
  bool check = false;
  for (int k = 1; k < argc; ++k) {
    const std::string a = argv[k];
    if (a == "--check") {
      check = true;
    } else if (k + 1 < argc && a == "--case") {
      which = argv[++k];
    } else if (k + 1 < argc && a == "--grains") {
      grains_wanted = std::strtod(argv[++k], nullptr);
    } else if (k + 1 < argc && a == "--builds") {
      builds = std::atoi(argv[++k]);
    } else {
      std::fprintf(stderr, "usage: %s [--case bed|shell] [--grains N] [--builds K] [--check]\n",
                   argv[0]);
      return 2;
    }
  }
  if ((which != "bed" && which != "shell") || !(grains_wanted >= 1000) || builds < 1) {
    std::fprintf(stderr,
                 "bench_neighbors: expected --case bed|shell, --grains >= 1000, --builds >= 1\n");
    return 2;
  }

  // a bed 20 diameters deep (the shell keeps its top five)
  const Real depth = 20 * kD;
  const Real side = std::sqrt(grains_wanted / (0.58 * depth / (M_PI / 6 * kD * kD * kD)));
  BedRegion region;
  region.x1 = region.y1 = side;
  region.floor = [](Real, Real) { return 0.0; };
  region.top = [&](Real, Real) { return depth; };
  region.r_lo = region.r_hi = kD / 2;
  region.threads = 2;
  const BedPacking bed = pack_bed(region);

  Grains grains;
  std::vector<Real> allow;
  Rng rng(7);
  for (std::size_t k = 0; k < bed.size(); ++k) {
    const Real below_top = depth - bed.x[k].z;
    if (which == "shell" && below_top > 5 * kD) continue;
    grains.add(static_cast<GrainId>(grains.size()), bed.x[k], {}, bed.r[k], 2500);
    const bool frozen = which == "shell" && below_top > 3 * kD;
    if (frozen) grains.state.back() = GrainState::Interface;
    const bool fast = which == "shell" && !frozen && rng.uniform(0.0, 1.0) < 0.1;
    allow.push_back(frozen ? 0.0 : (fast ? kD : 0.1 * kD));
  }
  const std::size_t n = grains.size();
  // in the solver's order (DemSolver::sort_by_cell, with the default skin: a fifth of a diameter)
  {
    const std::vector<std::uint32_t> perm = cell_order(grains, 0.2 * kD);
    grains.permute(perm);
    std::vector<Real> a(n);
    for (std::size_t i = 0; i < n; ++i) a[i] = allow[perm[i]];
    allow = std::move(a);
    for (std::size_t i = 0; i < n; ++i) grains.id[i] = static_cast<GrainId>(i);
  }

  PairGrids grid;
  PairList list, last;
  std::vector<std::uint32_t> slot_of_id(n);
  std::iota(slot_of_id.begin(), slot_of_id.end(), 0u);
  build_pair_list(grains, allow, false, grid, last, slot_of_id, list);  // (warm up)
  double best = 1e30, total = 0;
  for (int b = 0; b < builds; ++b) {
    std::swap(list, last);
    const auto t0 = std::chrono::steady_clock::now();
    build_pair_list(grains, allow, false, grid, last, slot_of_id, list);
    const double s = seconds_since(t0);
    best = std::min(best, s);
    total += s;
  }
  std::printf(
      "case=%s grains=%zu pairs=%zu pairs_per_grain=%.3f builds=%d ms_per_build=%.3f "
      "best_ms=%.3f\n",
      which.c_str(), n, list.pairs(), static_cast<double>(list.pairs()) / n, builds,
      1e3 * total / builds, 1e3 * best);
  if (check) {
    const std::string error = pair_list_error(grains, allow, list);
    std::printf("check: %s\n",
                error.empty() ? "every pair listed, rows well formed" : error.c_str());
    if (!error.empty()) return 1;
  }
  return 0;
}
