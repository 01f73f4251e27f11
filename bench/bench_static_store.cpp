// The static store (src/dem/grains.hpp) on its own: N grains of 1 cm put to sleep over a grid of
// columns a diameter wide, 20 to a column, then rounds of waking and sleeping again. Prints the
// bytes per grain (the store's allocated bytes), the largest round-trip error, the time to fill
// the store in two orders (column after column, as a bed generator might; and in random columns,
// as a pour's grains fall asleep), and the time per sleep and wake once it is full.
//
//   build/bench/bench_static_store [--grains N] [--per-column K]
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "core/rng.hpp"
#include "dem/grains.hpp"

using namespace sandflow;

namespace {

constexpr Real kD = 0.01;

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

struct Grain {
  Vec3 x;
  Real r;
  std::uint32_t column;
};

}  // namespace

int main(int argc, char** argv) {
  std::size_t n = 1'000'000;
  double per_column = 20;
  for (int k = 1; k + 1 < argc; k += 2) {
    const std::string a = argv[k];
    if (a == "--grains")
      n = std::strtoull(argv[k + 1], nullptr, 10);
    else if (a == "--per-column")
      per_column = std::strtod(argv[k + 1], nullptr);
  }
  const auto nx =
      static_cast<std::uint32_t>(std::ceil(std::sqrt(static_cast<double>(n) / per_column)));
  StaticFrame f;
  f.x0 = f.y0 = 0;
  f.cell = kD;
  f.nx = f.ny = nx;
  f.z_lo = -1 - 4;  // a domain [-1, 3] m widened by its height, as World makes it
  f.z_hi = 3 + 4;
  f.r_lo = 0.5 * kD * 0.9;
  f.r_hi = 0.5 * kD * 1.1;

  // the grains, column by column, stacked a diameter apart
  Rng rng(1);
  std::vector<Grain> bed;
  bed.reserve(n);
  const std::size_t nc = f.columns();
  for (std::size_t k = 0; k < n; ++k) {
    const auto c = static_cast<std::uint32_t>(k % nc);
    bed.push_back(
        {{kD * ((c % nx) + rng.uniform(0.0, 1.0)), kD * ((c / nx) + rng.uniform(0.0, 1.0)),
          (static_cast<Real>(k / nc) + 0.5) * kD},
         0.5 * kD * (1 + 0.1 * rng.uniform(-1.0, 1.0)),
         c});
  }
  std::stable_sort(bed.begin(), bed.end(),
                   [](const Grain& a, const Grain& b) { return a.column < b.column; });

  // 1. filled column after column
  auto t0 = std::chrono::steady_clock::now();
  StaticStore in_order(f);
  for (std::size_t k = 0; k < n; ++k)
    in_order.add(static_cast<GrainId>(k), bed[k].x, bed[k].r, bed[k].column);
  const double t_order = seconds_since(t0);
  const double bytes_order =
      static_cast<double>(in_order.allocated_bytes()) / static_cast<double>(n);

  // 2. filled in random columns
  std::vector<std::uint32_t> shuffled(n);
  for (std::size_t k = 0; k < n; ++k) shuffled[k] = static_cast<std::uint32_t>(k);
  for (std::size_t k = n; k-- > 1;)
    std::swap(
        shuffled[k],
        shuffled[static_cast<std::size_t>(rng.uniform(0.0, static_cast<Real>(k) + 1 - 1e-9))]);
  t0 = std::chrono::steady_clock::now();
  StaticStore st(f);
  for (std::uint32_t k : shuffled) st.add(k, bed[k].x, bed[k].r, bed[k].column);
  const double t_random = seconds_since(t0);
  const double bytes_random = static_cast<double>(st.allocated_bytes()) / static_cast<double>(n);

  // the round trip
  Real worst_x = 0, worst_r = 0;
  st.for_each([&](const StaticGrain& g) {
    worst_x = std::max(worst_x, norm(g.x - bed[g.id].x));
    worst_r = std::max(worst_r, std::abs(g.r - bed[g.id].r));
  });

  // 3. rounds: 1,000 grains of a patch wake, then sleep again
  std::vector<std::uint32_t> slots;
  std::vector<StaticGrain> woken;
  double worst_bytes = bytes_random;
  std::size_t changes = 0;
  t0 = std::chrono::steady_clock::now();
  for (int round = 0; round < 200; ++round) {
    slots.clear();
    woken.clear();
    const auto from =
        static_cast<std::uint32_t>(rng.uniform(0.0, static_cast<Real>(st.slot_count() - 4000)));
    for (std::uint32_t k = from; k < from + 4000 && woken.size() < 1000; ++k)
      if (st.holds(k)) {
        slots.push_back(k);
        woken.push_back(st.grain(k));
      }
    st.remove(slots);
    for (const StaticGrain& g : woken) st.add(g.id, g.x, g.r, g.column);
    changes += 2 * woken.size();
    worst_bytes = std::max(
        worst_bytes, static_cast<double>(st.allocated_bytes()) / static_cast<double>(st.size()));
  }
  const double t_churn = seconds_since(t0);

  std::printf(
      "grains %zu, columns %zu (%.1f a column), frame: %u x %u columns of %.3g m, z over %.3g m\n",
      n, nc, static_cast<double>(n) / static_cast<double>(nc), nx, nx, f.cell, f.z_hi - f.z_lo);
  std::printf("fill column by column   %.3f s (%.0f grains/s), %.2f bytes a grain\n", t_order,
              static_cast<double>(n) / t_order, bytes_order);
  std::printf("fill in random columns  %.3f s (%.0f grains/s), %.2f bytes a grain\n", t_random,
              static_cast<double>(n) / t_random, bytes_random);
  std::printf(
      "wake and sleep again    %zu changes in %.3f s (%.2f us each, with the patch's reads), "
      "%.2f bytes a grain at most\n",
      changes, t_churn, 1e6 * t_churn / static_cast<double>(changes), worst_bytes);
  std::printf(
      "round trip              centre %.3g d (bound %.3g d), radius %.3g d (bound %.3g d)\n",
      worst_x / kD, f.position_error() / kD, worst_r / kD, f.radius_error() / kD);
  const std::string e = st.check();
  std::printf("bytes_per_static=%.2f\n", worst_bytes);
  return e.empty() ? 0 : (std::fprintf(stderr, "store check: %s\n", e.c_str()), 1);
}
