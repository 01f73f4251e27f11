// The bed generator (src/geometry/bed_packing.hpp) on --threads threads (default 1): a flat bed
// of equal grains (or of radii spread by --spread) on a flat floor, sized for about --grains
// grains (cells closing after --patience discarded drops, default the generator's). Prints grains,
// seconds, grains per second, the packing fraction of the bulk (a box 5 diameters inside the
// floor, the walls and the top) and the largest overlap over a diameter. Not a test: timings go
// to docs/performance.md.
//
//   bench_bed_packing [--grains N] [--spread S] [--seed K] [--depth D] [--threads T]
//                     [--patience P]
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <string>

#include "geometry/bed_packing.hpp"

using namespace sandflow;

int main(int argc, char** argv) {
  double grains = 1e6, spread = 0, depth_d = 22;
  int threads = 1, patience = BedRegion{}.patience;
  std::uint64_t seed = 1;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string k = argv[i];
    const double v = std::atof(argv[i + 1]);
    if (k == "--grains")
      grains = v;
    else if (k == "--spread")
      spread = v;
    else if (k == "--seed")
      seed = static_cast<std::uint64_t>(v);
    else if (k == "--depth")
      depth_d = v;
    else if (k == "--threads")
      threads = static_cast<int>(v);
    else if (k == "--patience")
      patience = static_cast<int>(v);
    else {
      std::fprintf(stderr,
                   "usage: bench_bed_packing [--grains N] [--spread S] [--seed K] [--depth D] "
                   "[--threads T] [--patience P]\n");
      return 2;
    }
  }
  const double d = 0.01;
  // the footprint holding `grains` at a packing fraction of 0.58, depth_d diameters deep
  const double grain_volume = kPi / 6 * d * d * d * (1 + spread * spread);
  const double height = depth_d * d;
  const double side = std::sqrt(grains * grain_volume / 0.58 / height);
  BedRegion region;
  region.x0 = region.y0 = 0;
  region.x1 = region.y1 = side;
  region.floor = [](Real, Real) { return 0.0; };
  region.top = [height](Real, Real) { return height; };
  region.r_lo = 0.5 * d * (1 - spread);
  region.r_hi = 0.5 * d * (1 + spread);
  region.seed = seed;
  region.threads = threads;
  region.patience = patience;

  // a small warm-up bed (page faults, caches), then the timed one
  {
    BedRegion warm = region;
    warm.x1 = warm.y1 = 20 * d;
    (void)pack_bed(warm);
  }
  const auto t0 = std::chrono::steady_clock::now();
  const std::clock_t c0 = std::clock();
  const BedPacking bed = pack_bed(region);
  const double cpu = static_cast<double>(std::clock() - c0) / CLOCKS_PER_SEC;
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const double m = 5 * d;
  const double phi = packing_fraction_in(bed.x, bed.r, {m, m, m}, {side - m, side - m, height - m});
  const double overlap = largest_overlap(bed.x, bed.r);
  std::printf(
      "footprint %.3f x %.3f m, top %.3f m, d = %.3f m, spread %.2f, seed %llu, threads %d, "
      "patience %d\n",
      side, side, height, d, spread, static_cast<unsigned long long>(seed), threads, patience);
  // (the machines are shared: the CPU time of the threads, summed, is printed beside the wall
  // time)
  std::printf(
      "grains=%zu tiled=%lld settled=%lld copied=%lld drops=%lld discarded=%lld seconds=%.3f "
      "cpu_seconds=%.3f "
      "grains_per_s=%.0f grains_per_cpu_s=%.0f\n",
      bed.size(), static_cast<long long>(bed.tiled), static_cast<long long>(bed.settled),
      static_cast<long long>(bed.copied), static_cast<long long>(bed.drops),
      static_cast<long long>(bed.discarded), seconds, cpu,
      static_cast<double>(bed.size()) / seconds, static_cast<double>(bed.size()) / cpu);
  std::printf("bulk_packing_fraction=%.4f largest_overlap_over_d=%.3g\n", phi, overlap);
  return 0;
}
