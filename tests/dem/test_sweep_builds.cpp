// The sweep's two builds (DemSolver::use_avx512): the AVX-512 one, which a processor that has it
// runs, must leave the grains bit for bit where the portable one leaves them, with and without
// rolling resistance, on one thread and on two.
#include <gtest/gtest.h>
#include <omp.h>

#include <cstring>
#include <memory>
#include <vector>

#include "core/rng.hpp"
#include "dem/dem_solver.hpp"

namespace sandflow {
namespace sweep_builds {  // (named: the unity build joins this file to others)

constexpr Real kR = 0.001, kDt = 1e-5;

DemParams params(bool rolling) {
  DemParams p;
  p.contact.k_n = 500;
  p.contact.beta = damping_beta(0.5);
  p.contact.k_t = p.contact.k_n * 2 / 7;
  p.contact.mu = 0.5;
  if (rolling) {
    p.contact.k_r = p.contact.k_t;
    p.contact.mu_r = 0.1;
    p.contact.mu_tw = 0.05;
  }
  p.skin = 0.4 * kR;
  p.skin_steps = 32;
  p.skin_max = 2 * kR;
  return p;
}

// 12 x 12 x 6 grains of three sizes on a lattice a little looser than touching, jittered, thrown
// down and sideways onto a floor: contacts open, slip, roll and end, and the lists are rebuilt.
Grains thrown_block() {
  Rng rng(11);
  Grains g;
  GrainId id = 0;
  for (int k = 0; k < 6; ++k)
    for (int j = 0; j < 12; ++j)
      for (int i = 0; i < 12; ++i) {
        const Vec3 x{i * 2.05 * kR, j * 2.05 * kR, (k + 0.6) * 2.05 * kR};
        const Vec3 jitter{rng.uniform(-0.02, 0.02), rng.uniform(-0.02, 0.02), 0};
        const Vec3 v{0.3 + rng.uniform(-0.1, 0.1), rng.uniform(-0.1, 0.1), -0.5};
        g.add(id, x + jitter * kR, v, kR * (0.9 + 0.1 * (id % 3)), 2500);
        ++id;
      }
  return g;
}

struct SweepRun {
  Grains grains;
  std::int64_t contacts = 0;
};

SweepRun run(bool rolling, bool avx512, int threads) {
  omp_set_num_threads(threads);
  DemSolver dem(params(rolling));
  dem.use_avx512(avx512);
  Geometry floor;
  floor.add(std::make_unique<HalfSpace>(Vec3{0, 0, 0}, Vec3{0, 0, 1}), 0.5, rolling ? 0.1 : 0.0,
            0.0, 0);
  SweepRun r{thrown_block()};
  Profile profile;
  for (int s = 0; s < 1500; ++s) {
    dem.step(r.grains, floor, kDt, profile);
    r.contacts += dem.counters().contacts;
  }
  omp_set_num_threads(omp_get_num_procs());
  return r;
}

bool same_bits(const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(Vec3)) == 0;
}

TEST(SweepBuilds, TheAvx512BuildLeavesTheGrainsWhereThePortableOneDoes) {
  if (!DemSolver::avx512_available())
    GTEST_SKIP() << "this processor has no AVX-512: only the portable build runs here";
  ASSERT_GE(thrown_block().size(), kParallelMinGrains) << "(two threads must share the sweep)";
  for (const bool rolling : {false, true})
    for (const int threads : {1, 2}) {
      const SweepRun portable = run(rolling, false, threads), wide = run(rolling, true, threads);
      ASSERT_GT(portable.contacts, 1000) << "the block must collide";
      EXPECT_EQ(wide.contacts, portable.contacts);
      EXPECT_TRUE(same_bits(wide.grains.x, portable.grains.x))
          << "positions, rolling " << rolling << ", threads " << threads;
      EXPECT_TRUE(same_bits(wide.grains.v, portable.grains.v))
          << "velocities, rolling " << rolling << ", threads " << threads;
      EXPECT_TRUE(same_bits(wide.grains.w, portable.grains.w))
          << "spins, rolling " << rolling << ", threads " << threads;
    }
}

}  // namespace sweep_builds
}  // namespace sandflow
