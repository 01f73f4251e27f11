// The hashed grid and Verlet lists against brute force.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <set>
#include <string>

#include "core/rng.hpp"
#include "dem/dem_solver.hpp"
#include "dem/neighbor_list.hpp"

namespace sandflow {
namespace {

Grains random_grains(int n, std::uint64_t seed, Real box) {
  Rng rng(seed);
  Grains g;
  for (int i = 0; i < n; ++i)
    g.add(i, {rng.uniform(0, box), rng.uniform(0, box), rng.uniform(0, box)}, {},
          rng.uniform(0.004, 0.006), 2600);
  return g;
}

/// Damped frictional grains (beta 0.3, mu 0.5) in no gravity, with a skin of 2 mm.
DemParams frictional_without_gravity(Real k_n, Real k_t) {
  DemParams p;
  p.contact.k_n = k_n;
  p.contact.k_t = k_t;
  p.contact.beta = 0.3;
  p.contact.mu = 0.5;
  p.gravity = {0, 0, 0};
  p.skin = 0.002;
  return p;
}

std::vector<std::pair<std::uint32_t, std::uint32_t>> listed_pairs(const PairList& pl) {
  std::vector<std::pair<std::uint32_t, std::uint32_t>> out;
  for (std::uint32_t i = 0; i + 1 < pl.start.size(); ++i)
    for (std::uint32_t s = pl.start[i]; s < pl.start[i + 1]; ++s) out.emplace_back(i, pl.j[s]);
  std::sort(out.begin(), out.end());
  return out;
}

// Lists the pairs of g for the allowances `allow` into pl (grid as scratch) and checks them
// against brute force; there must be many, or the check proves little.
void expect_brute_force_pairs(const Grains& g, const std::vector<Real>& allow, PairGrids& grid,
                              PairList& pl, std::uint64_t seed) {
  PairList none;
  build_pair_list(g, allow, true, grid, none, {}, pl);
  auto expected = brute_force_pairs(g, allow);
  std::sort(expected.begin(), expected.end());
  ASSERT_GT(expected.size(), 1000u);
  EXPECT_EQ(listed_pairs(pl), expected) << "seed " << seed;
}

TEST(NeighbourList, SamePairsAsBruteForce) {
  for (std::uint64_t seed : {1, 2, 3}) {
    Grains g = random_grains(3000, seed, 0.15);
    // a far-away grain and a dense cluster: the hashed grid must not care
    g.add(5000, {1e3, -2e3, 5e2}, {}, 0.005, 2600);
    for (int k = 0; k < 50; ++k) g.add(6000 + k, {0.5 + 0.001 * k, 0.5, 0.5}, {}, 0.005, 2600);
    const Real skin = 0.002;
    PairGrids grid;
    PairList pl, none;
    build_pair_list(g, skin, true, grid, none, {}, pl);
    auto expected = brute_force_pairs(g, skin);
    std::sort(expected.begin(), expected.end());
    ASSERT_FALSE(expected.empty());
    EXPECT_EQ(listed_pairs(pl), expected) << "seed " << seed;
  }
}

// A large bed's frozen grains along its walls, metres from the grains that move (7 % of them):
// the grid keeps its finest cells over the cluster, so that each grain searches a few
// candidates, not hundreds, and still lists exactly the brute-force pairs (those along the walls
// too, clamped into the border cells)
TEST(CellGrid, GrainsAlongFarWallsKeepTheCellsFine) {
  Grains g = random_grains(2000, 7, 0.15);
  for (int k = 0; k < 140; ++k) {  // 35 to a wall of an 8 m sandbox, in touching pairs
    const Real t = -3.9 + 0.2 * (k / 8) + 0.009 * ((k / 4) % 2);
    const std::array<Vec3, 4> at{Vec3{t, -4, 0.05}, Vec3{t, 4, 0.05}, Vec3{-4, t, 0.05},
                                 Vec3{4, t, 0.05}};
    g.add(10000 + k, at[static_cast<std::size_t>(k % 4)], {}, 0.005, 2600);
  }
  PairGrids grid;
  PairList pl;
  // (each grain may move half a 2 mm skin)
  expect_brute_force_pairs(g, std::vector<Real>(g.size(), 0.001), grid, pl, 7);
  // the finest cells: the largest diameter and the skin (1.4 cm)
  EXPECT_LE(grid.searching.cell_size(), 0.014) << grid.searching.cell_size();
}

// The assertions' reference after each rebuild (a sweep along x) against brute force: the same
// pairs, with frozen grains, large allowances of a few, grains at one x and one far away
TEST(NeighbourList, TheSweptPairsAreTheBruteForcePairs) {
  for (std::uint64_t seed : {8, 9}) {
    Grains g = random_grains(2000, seed, 0.1);
    g.add(5000, {1e3, -2e3, 5e2}, {}, 0.005, 2600);
    for (int k = 0; k < 40; ++k) g.add(6000 + k, {0.05, 0.001 * k, 0.05}, {}, 0.005, 2600);
    for (std::size_t i = 0; i < g.size(); i += 3) g.state[i] = GrainState::Interface;
    Rng rng(seed);
    std::vector<Real> allow(g.size(), 0.001);
    for (std::size_t i = 0; i < g.size(); i += 11) allow[i] = rng.uniform(0.001, 0.012);
    auto expected = brute_force_pairs(g, allow);
    auto swept = swept_pairs(g, allow);
    std::sort(expected.begin(), expected.end());
    std::sort(swept.begin(), swept.end());
    ASSERT_GT(expected.size(), 1000u);
    EXPECT_EQ(swept, expected) << "seed " << seed;
  }
}

// A few grains with large allowances (a fast stream) look further than the grid's cells: their
// pairs, found from their side whatever the index order, must be exactly the brute-force ones.
TEST(NeighbourList, LargerAllowancesOfAFewGrainsGiveTheBruteForcePairs) {
  for (std::uint64_t seed : {4, 5}) {
    Grains g = random_grains(3000, seed, 0.12);
    g.add(5000, {1e3, -2e3, 5e2}, {}, 0.005, 2600);  // a far-away grain: clamped cells
    for (std::size_t i = 0; i < g.size(); i += 3) g.state[i] = GrainState::Interface;
    Rng rng(seed);
    std::vector<Real> allow(g.size(), 0.001);
    for (std::size_t i = 0; i < g.size(); i += 7) allow[i] = rng.uniform(0.001, 0.012);
    allow[17] = allow[18] = 0.004;  // equal large allowances: found once, by the lower index
    PairGrids grid;
    PairList pl;
    expect_brute_force_pairs(g, allow, grid, pl, seed);
    for (std::size_t i = 0; i + 1 < pl.start.size(); ++i)  // rows ascending, as the sweep needs
      EXPECT_TRUE(std::is_sorted(pl.j.begin() + pl.start[i], pl.j.begin() + pl.start[i + 1]));
  }
}

// The ball query of a fast grain's search: every grain closer than the reach is visited, also
// among grains clamped into the border cells (a cluster far outside the central 99 % of the
// grains, which lie close to each other and to nothing else), and fewer than the cube holds.
TEST(CellGrid, ABallQueryVisitsEveryGrainWithinReach) {
  for (std::uint64_t seed : {11, 12}) {
    Grains g = random_grains(3000, seed, 0.15);
    Rng rng(seed);
    for (int k = 0; k < 10; ++k)  // (10 of 3,010: beyond the central 99 %)
      g.add(7000 + k, {40 + rng.uniform(0, 0.03), -30 + rng.uniform(0, 0.03), 0.07}, {}, 0.005, 2600);
    CellGrid grid;
    grid.build(g.x, 0.013);
    ASSERT_LT(grid.cell_size(), 0.02);  // the outliers are clamped, not covered by coarse cells
    std::size_t in_ball = 0, in_cube = 0;
    for (int q = 0; q < 400; ++q) {
      const Vec3 p = q % 10 == 0 ? g.x[3000 + q / 10 % 10]
                                 : Vec3{rng.uniform(-0.01, 0.16), rng.uniform(-0.01, 0.16),
                                        rng.uniform(-0.01, 0.16)};
      const Real reach = rng.uniform(0.001, 0.04);
      std::set<std::uint32_t> seen;
      grid.for_each_in_ball(p, reach, [&](std::uint32_t j) { seen.insert(j); });
      for (std::uint32_t j = 0; j < g.size(); ++j) {
        if (norm(g.x[j] - p) < reach) {
          EXPECT_TRUE(seen.count(j)) << "seed " << seed << ", query " << q;
        }
      }
      const int k = static_cast<int>(std::ceil(reach / grid.cell_size()));
      in_ball += seen.size();
      grid.for_each_within(p, k, [&](std::uint32_t) { ++in_cube; });
    }
    EXPECT_LT(in_ball, in_cube * 3 / 4) << "seed " << seed;
  }
}

// A fast grain's search beyond the 27 cells around it (those the half search covers): with them,
// every grain within reach, also in the border cells and for reaches just over a cell (where
// most balls meet nothing beyond), and none of the 27 cells' grains twice.
TEST(CellGrid, TheBallBeyondTheNearCellsHoldsTheRestOfTheBall) {
  for (std::uint64_t seed : {13, 14}) {
    Grains g = random_grains(3000, seed, 0.15);
    Rng rng(seed);
    for (int k = 0; k < 10; ++k)  // (clamped into the border cells)
      g.add(7000 + k, {40 + rng.uniform(0, 0.03), -30 + rng.uniform(0, 0.03), 0.07}, {}, 0.005,
            2600);
    CellGrid grid;
    grid.build(g.x, 0.013);
    std::size_t beyond_total = 0;
    for (int q = 0; q < 400; ++q) {
      const Vec3 p = q % 10 == 0 ? g.x[3000 + q / 10 % 10]
                                 : Vec3{rng.uniform(-0.01, 0.16), rng.uniform(-0.01, 0.16),
                                        rng.uniform(-0.01, 0.16)};
      const Real reach = grid.cell_size() * (q % 2 ? rng.uniform(1.0, 1.1) : rng.uniform(1, 3));
      std::set<std::uint32_t> near, beyond;
      grid.for_each_within(p, 1, [&](std::uint32_t j) { near.insert(j); });
      grid.for_each_in_ball_beyond(p, reach, [&](std::uint32_t j) {
        EXPECT_FALSE(near.count(j)) << "seed " << seed << ", query " << q;
        EXPECT_TRUE(beyond.insert(j).second) << "seed " << seed << ", query " << q;
      });
      beyond_total += beyond.size();
      for (std::uint32_t j = 0; j < g.size(); ++j)
        if (norm(g.x[j] - p) < reach) {
          EXPECT_TRUE(near.count(j) || beyond.count(j)) << "seed " << seed << ", query " << q;
        }
    }
    EXPECT_GT(beyond_total, 1000u) << "seed " << seed;  // (or the check proves little)
  }
}

// The check that follows every rebuild in a build with assertions (pair_list_error): silent on
// the grid's list, and it names the pair a broken list misses and a row out of order.
TEST(NeighbourList, TheRebuildCheckNamesAMissingPairAndABadRow) {
  Grains g = random_grains(500, 8, 0.08);
  for (std::size_t i = 0; i < g.size(); i += 4) g.state[i] = GrainState::Interface;
  std::vector<Real> allow(g.size(), 0.001);
  for (std::size_t i = 0; i < g.size(); i += 4) allow[i] = 0;  // as the solver: frozen, none
  PairGrids grid;
  PairList pl, none;
  build_pair_list(g, allow, false, grid, none, {}, pl);
  EXPECT_EQ(pair_list_error(g, allow, pl), "");

  // a touching pair dropped from its row
  std::uint32_t a = 0, s = 0;
  while (s == pl.start[a + 1] || norm(g.x[a] - g.x[pl.j[s]]) >= g.r[a] + g.r[pl.j[s]]) {
    if (s == pl.start[a + 1])
      ++a;
    else
      ++s;
  }
  const std::uint32_t b = pl.j[s];
  PairList missing = pl;
  missing.j.erase(missing.j.begin() + s);
  for (std::size_t i = a + 1; i < missing.start.size(); ++i) --missing.start[i];
  const std::string e = pair_list_error(g, allow, missing);
  EXPECT_NE(e.find("grains " + std::to_string(g.id[a]) + " and " + std::to_string(g.id[b])),
            std::string::npos)
      << e;

  // a row out of order
  PairList swapped = pl;
  std::uint32_t c = 0;
  while (pl.start[c + 1] - pl.start[c] < 2) ++c;
  std::swap(swapped.j[pl.start[c]], swapped.j[pl.start[c] + 1]);
  EXPECT_NE(pair_list_error(g, allow, swapped).find("out of order"), std::string::npos);
}

TEST(NeighbourList, FrozenPairsAreNotListed) {
  Grains g = random_grains(500, 7, 0.08);
  for (std::size_t i = 0; i < g.size(); i += 2) g.state[i] = GrainState::Interface;
  PairGrids grid;
  PairList pl, none;
  build_pair_list(g, 0.002, false, grid, none, {}, pl);
  auto expected = brute_force_pairs(g, 0.002);
  std::sort(expected.begin(), expected.end());
  EXPECT_EQ(listed_pairs(pl), expected);
  for (auto [i, j] : expected)
    EXPECT_TRUE(g.state[i] == GrainState::Active || g.state[j] == GrainState::Active);
}

// The solver gives frozen grains no allowance: they search for nothing (every pair of theirs is
// an active grain's), and the cells fit the active grains. A frozen grain with an allowance above
// the least active one's still searches. The pairs must be the brute-force ones all the same.
/// 3,000 random grains, three in five frozen with the allowance `frozen`, the others `slow`,
/// every eleventh (ACTIVE) drawn in [slow, fast]; the grains into g, their allowances returned.
std::vector<Real> frozen_slow_and_fast(Grains& g, std::uint64_t seed, Real frozen, Real slow,
                                       Real fast) {
  g = random_grains(3000, seed, 0.12);
  Rng rng(seed);
  std::vector<Real> allow(g.size());
  for (std::size_t i = 0; i < g.size(); ++i) {
    const bool is_frozen = i % 5 < 3;
    if (is_frozen) g.state[i] = GrainState::Interface;
    allow[i] = is_frozen ? frozen : (i % 11 == 0 ? rng.uniform(slow, fast) : slow);
  }
  return allow;
}

TEST(NeighbourList, FrozenGrainsWithoutAllowanceLoseNoPair) {
  for (std::uint64_t seed : {8, 9}) {
    Grains g;
    std::vector<Real> allow = frozen_slow_and_fast(g, seed, 0.0, 0.001, 0.012);
    allow[30] = 0.002;  // frozen, more mobile than the least active grain: it searches
    allow[31] = 0.0005;  // frozen, less mobile: it does not
    PairGrids grid;
    PairList pl;
    expect_brute_force_pairs(g, allow, grid, pl, seed);
    // sized for the active grains
    EXPECT_LT(grid.searching.cell_size(), 2 * 0.006 + 2 * 0.001 + 1e-12);
  }
}

// Frozen grains that may move a little (allowances under the least ACTIVE one's: they search
// none) and fast ACTIVE grains: an ACTIVE grain's search of the frozen grains must reach the cut
// of a pair with the most mobile of them, not only with its own allowance.
TEST(NeighbourList, FrozenGrainsThatMayMoveAreFoundOutToTheirCut) {
  for (std::uint64_t seed : {13, 14}) {
    Grains g;
    const std::vector<Real> allow = frozen_slow_and_fast(g, seed, 0.0039, 0.004, 0.02);
    PairGrids grid;
    PairList pl;
    expect_brute_force_pairs(g, allow, grid, pl, seed);
  }
}

// Three ways a pair is found: two of the least allowance by the grid's half search, one grain
// more mobile than the other by that one, and two of one larger allowance by the lower index.
// Many ties of each kind, ACTIVE and frozen grains among them, and the list is the brute-force
// one; so it is where a few far grains stretch the grid (clamped into its border cells).
TEST(NeighbourList, PairsOfEqualAllowancesAreFoundOnce) {
  for (std::uint64_t seed : {11, 12}) {
    Grains g = random_grains(3000, seed, 0.12);
    for (int k = 0; k < 4; ++k) g.add(7000 + k, {50.0 * k, -20.0, 3.0 * k}, {}, 0.005, 2600);
    std::vector<Real> allow(g.size(), 0.001);
    for (std::size_t i = 0; i < g.size(); ++i) {
      if (i % 7 == 0) allow[i] = 0.004;  // a fast stream's grains, all alike
      if (i % 13 == 0) {                 // frozen: without allowance, or as the least active
        g.state[i] = GrainState::Interface;
        allow[i] = i % 2 ? 0.0 : 0.001;
      }
    }
    PairGrids grid;
    PairList pl;
    expect_brute_force_pairs(g, allow, grid, pl, seed);
  }
}

// The half search: of two grains in cells next to each other (or in one cell), exactly one
// finds the other, and neither finds itself.
TEST(CellGrid, TheHalfSearchFindsEachNeighbourOnce) {
  const Grains g = random_grains(2000, 5, 0.1);
  for (const Real cell : {0.012, 0.03}) {
    CellGrid grid;
    grid.build(g.x, cell);
    std::vector<std::vector<std::uint32_t>> found(g.size());
    for (std::uint32_t i = 0; i < g.size(); ++i)
      grid.for_each_after(i, g.x[i], [&](std::uint32_t j) { found[i].push_back(j); });
    std::size_t pairs = 0;
    for (std::uint32_t i = 0; i < g.size(); ++i)
      for (std::uint32_t j = i + 1; j < g.size(); ++j) {
        const int by_i = static_cast<int>(std::count(found[i].begin(), found[i].end(), j));
        const int by_j = static_cast<int>(std::count(found[j].begin(), found[j].end(), i));
        if (norm(g.x[i] - g.x[j]) < grid.cell_size()) {
          ASSERT_EQ(by_i + by_j, 1) << "grains " << i << " and " << j << ", cells of " << cell;
          ++pairs;
        } else {
          ASSERT_LE(by_i + by_j, 1);
        }
      }
    EXPECT_GT(pairs, 2000u);
    for (std::uint32_t i = 0; i < g.size(); ++i)
      EXPECT_EQ(std::count(found[i].begin(), found[i].end(), i), 0);
  }
}

TEST(NeighbourList, TheSortPutsTheAxisTheGrainsSpreadFurthestAlongOutermost) {
  // a layer 40 grains long in y, 8 wide in x, 3 deep in z, stored in reverse lattice order: after
  // the first rebuild (which sorts) the storage runs along y, so that the threads' ranges are
  // slabs across y and meet across the smallest faces
  const Real d = 0.01, skin = 0.2 * d;
  Grains g;
  GrainId id = 0;
  for (int k = 0; k < 3; ++k)
    for (int b = 0; b < 40; ++b)
      for (int a = 0; a < 8; ++a)
        g.add(id++, {a * 1.03 * d, b * 1.03 * d, k * 1.03 * d}, {}, d / 2, 2600);
  std::vector<std::uint32_t> reverse(g.size());
  for (std::uint32_t k = 0; k < reverse.size(); ++k)
    reverse[k] = static_cast<std::uint32_t>(reverse.size() - 1 - k);
  g.permute(reverse);
  DemParams p;
  p.gravity = {0, 0, 0};
  p.skin = skin;
  p.sort_every = 1;
  DemSolver dem(p);
  Profile prof;
  dem.step(g, Geometry{}, 0.0, prof);  // (no motion: the cells are those of the lattice)
  auto cell = [&](std::size_t i, int axis) {
    return static_cast<int>(std::floor(g.x[i][axis] / (d + skin)));  // (none on a cell edge)
  };
  for (std::size_t i = 1; i < g.size(); ++i) {
    const std::array<int, 3> prev{cell(i - 1, 1), cell(i - 1, 0), cell(i - 1, 2)};
    const std::array<int, 3> here{cell(i, 1), cell(i, 0), cell(i, 2)};
    ASSERT_LE(prev, here) << "slot " << i << ": not in (y, x, z) cell order";
  }
}

/// No gravity, a 2 mm skin, fast grains allowed their way in 32 steps up to 2 cm, and the grains
/// kept in their slots (allow[k] is grain k's).
DemParams allowances_up_to_2_cm() {
  DemParams p;
  p.gravity = {0, 0, 0};
  p.skin = 0.002;
  p.skin_steps = 32;
  p.skin_max = 0.02;
  p.sort_every = 0;
  p.contact.k_n = 1e4;
  return p;
}

TEST(NeighbourList, AGrainAFasterPartnerCanReachGetsThePartnersAllowance) {
  // B flies at 3 m/s towards A, 2 mm away; C lies 10 mm behind B, listed, but further than the
  // two close in skin_steps steps (9.6 mm); D lies 0.5 mm from A, listed with no fast grain; E is
  // frozen beside B
  const Real r = 0.005, dt = 1e-4, v = 3.0;
  const DemParams p = allowances_up_to_2_cm();
  Grains g;
  g.add(0, {0, 0, 0}, {}, r, 2600);                          // A
  g.add(1, {2 * r + 0.002, 0, 0}, {-v, 0, 0}, r, 2600);      // B
  g.add(2, {4 * r + 0.012, 0, 0}, {}, r, 2600);              // C
  g.add(3, {-2 * r - 0.0005, 0, 0}, {}, r, 2600);            // D
  g.add(4, {2 * r + 0.002, 2 * r + 0.001, 0}, {}, r, 2600);  // E
  g.state[4] = GrainState::Interface;
  DemSolver dem(p);
  std::vector<Real> allow;
  const Real a_min = p.skin / 2, a_fast = v * dt * p.skin_steps;
  // before any list there are no partners: each grain's own speed
  dem.allowances(g, dt, allow);
  EXPECT_DOUBLE_EQ(allow[0], a_min);
  EXPECT_DOUBLE_EQ(allow[1], a_fast);
  Profile prof;
  dem.step(g, Geometry{}, dt, prof);  // lists them; B moves 0.3 mm
  const auto pairs = listed_pairs(dem.pairs());
  for (const std::pair<std::uint32_t, std::uint32_t>& ab :
       {std::pair{0u, 1u}, {1u, 2u}, {0u, 3u}, {1u, 4u}})
    ASSERT_TRUE(std::find(pairs.begin(), pairs.end(), ab) != pairs.end())
        << ab.first << " and " << ab.second << " are not listed";
  dem.allowances(g, dt, allow);
  EXPECT_DOUBLE_EQ(allow[0], a_fast) << "A, struck by B within the horizon";
  EXPECT_DOUBLE_EQ(allow[1], a_fast);
  EXPECT_DOUBLE_EQ(allow[2], a_min) << "C, further than B goes in skin_steps steps";
  EXPECT_DOUBLE_EQ(allow[3], a_min) << "D, beside A but not B";
  EXPECT_EQ(allow[4], 0) << "E, frozen";
}

TEST(NeighbourList, AllowancesKeptForTheRebuildAreTakenOnlyWhileTheyHold) {
  // B flies at 3 m/s past E, frozen 1 mm beside it; F rests 4 mm beyond E. The invariant of the
  // layers reads the allowances for the coming rebuild (E, frozen: none); then E is dislodged.
  // The rebuild must give E the allowance of B, which can reach it, and so list E with F (a kept
  // 0 for E would leave that pair out); a grain woken into the interface after the reading
  // changes no other grain's allowance, and the list stays complete.
  const Real r = 0.005, dt = 1e-4, v = 3.0;
  const DemParams p = allowances_up_to_2_cm();
  Grains g;
  g.add(0, {0, 0, 0}, {-v, 0, 0}, r, 2600);      // B
  g.add(1, {0, 2 * r + 0.001, 0}, {}, r, 2600);  // E
  g.add(2, {0, 4 * r + 0.005, 0}, {}, r, 2600);  // F
  g.state[1] = GrainState::Interface;
  DemSolver dem(p);
  Profile prof;
  dem.step(g, Geometry{}, dt, prof);
  auto listed = [&](std::uint32_t a, std::uint32_t b) {
    const auto pairs = listed_pairs(dem.pairs());
    return std::find(pairs.begin(), pairs.end(), std::pair{a, b}) != pairs.end();
  };
  ASSERT_TRUE(listed(0, 1));
  ASSERT_FALSE(listed(1, 2)) << "E, frozen, and F, slow, are 4 mm apart";

  EXPECT_EQ(dem.allowances_for_rebuild(g, dt)[1], 0) << "E, frozen";
  g.state[1] = GrainState::Active;
  const StateChange dislodged{1, GrainState::Interface, GrainState::Active};
  dem.apply({&dislodged, 1});
  dem.update_lists(g, Geometry{}, dt);
  EXPECT_TRUE(listed(1, 2)) << "E, dislodged, takes B's allowance";

  // a grain woken into the interface beside F after the reading: the kept allowances hold
  dem.allowances_for_rebuild(g, dt);
  g.add(3, {2 * r + 0.0005, 4 * r + 0.005, 0}, {}, r, 2600);
  g.state[3] = GrainState::Interface;
  const StateChange woken{3, GrainState::Static, GrainState::Interface};
  dem.apply({&woken, 1});
  dem.update_lists(g, Geometry{}, dt);
  std::vector<Real> fresh;
  dem.allowances(g, dt, fresh);
  EXPECT_EQ(pair_list_error(g, fresh, dem.pairs()), "");
  EXPECT_TRUE(listed(1, 2));
  EXPECT_TRUE(listed(2, 3)) << "F and the woken grain, 0.5 mm apart";
}

TEST(NeighbourList, HistorySurvivesARebuildWithResorting) {
  // a compressed random packing, so that many contacts carry tangential history
  Grains g = random_grains(2000, 11, 0.08);
  DemParams p = frictional_without_gravity(1e4, 3e3);
  p.sort_every = 1;  // every rebuild re-sorts
  DemSolver dem(p);
  Geometry none;
  Profile prof;
  Rng rng(5);
  for (auto& v : g.v) v = {rng.uniform(-0.1, 0.1), rng.uniform(-0.1, 0.1), rng.uniform(-0.1, 0.1)};
  dem.step(g, none, 1e-5, prof);
  // freeze the grains and let the history settle into the current tangent planes
  for (auto& v : g.v) v = {};
  for (auto& w : g.w) w = {};
  dem.step(g, none, 0.0, prof);
  // remember xi by (id, id)
  std::map<std::pair<GrainId, GrainId>, Vec3> before;
  const PairList& a = dem.pairs();
  for (std::uint32_t i = 0; i + 1 < a.start.size(); ++i)
    for (std::uint32_t s = a.start[i]; s < a.start[i + 1]; ++s)
      if (norm2(a.xi[s]) > 0) before[{g.id[i], g.id[a.j[s]]}] = a.xi[s];
  ASSERT_GT(before.size(), 10u);
  // reverse the storage order, force a rebuild with re-sorting, and look the history up again
  std::vector<std::uint32_t> perm(g.size());
  for (std::uint32_t k = 0; k < perm.size(); ++k) perm[k] = static_cast<std::uint32_t>(perm.size() - 1 - k);
  g.permute(perm);
  dem.invalidate();
  const Real dt = 0;  // no motion: the history must come back unchanged (up to sign when flipped)
  dem.step(g, none, dt, prof);
  const PairList& b = dem.pairs();
  int found = 0;
  for (std::uint32_t i = 0; i + 1 < b.start.size(); ++i)
    for (std::uint32_t s = b.start[i]; s < b.start[i + 1]; ++s) {
      const GrainId u = g.id[i], w = g.id[b.j[s]];
      if (auto it = before.find({u, w}); it != before.end()) {
        EXPECT_NEAR(norm(b.xi[s] - it->second), 0, 1e-12 * norm(it->second));
        ++found;
      } else if (auto it2 = before.find({w, u}); it2 != before.end()) {
        EXPECT_NEAR(norm(b.xi[s] + it2->second), 0, 1e-12 * norm(it2->second));
        ++found;
      }
    }
  EXPECT_EQ(found, static_cast<int>(before.size()));
}

TEST(NeighbourList, TheNearListHoldsEveryTouchingPairAtEveryStep) {
  // a loose gas of slow grains (a jittered lattice, 1 to 5 mm apart, at up to 0.2 m/s in each
  // direction, no gravity), whose pairs keep meeting and parting: before each step's sweep every
  // pair that overlaps must be in its row's near list, and the near list must be much shorter
  // than the Verlet rows (or it proves little)
  Rng rng(3);
  Grains g;
  GrainId id = 0;
  for (int a = 0; a < 12; ++a)
    for (int b = 0; b < 12; ++b)
      for (int c = 0; c < 10; ++c)
        g.add(
            id++,
            Vec3{a * 0.013, b * 0.013, c * 0.013} +
                Vec3{rng.uniform(-5e-4, 5e-4), rng.uniform(-5e-4, 5e-4), rng.uniform(-5e-4, 5e-4)},
            {rng.uniform(-0.2, 0.2), rng.uniform(-0.2, 0.2), rng.uniform(-0.2, 0.2)},
            rng.uniform(0.004, 0.0055), 2600);
  DemParams p = frictional_without_gravity(1e3, 300);
  p.skin_steps = 32;
  p.skin_max = 0.005;
  DemSolver dem(p);
  const Geometry none;
  const Real dt = 2e-5;
  std::int64_t touching = 0, near = 0, listed = 0;
  for (int step = 0; step < 1500; ++step) {
    dem.update_lists(g, none, dt);
    const PairList& pl = dem.pairs();
    for (std::uint32_t i = 0; i + 1 < pl.start.size(); ++i) {
      const std::uint32_t* row = pl.near.data() + pl.start[i];
      near += pl.near_count[i];
      listed += pl.start[i + 1] - pl.start[i];
      for (std::uint32_t s = pl.start[i]; s < pl.start[i + 1]; ++s) {
        const std::uint32_t j = pl.j[s];
        const Real rsum = g.r[i] + g.r[j];
        if (norm2(g.x[i] - g.x[j]) >= rsum * rsum) continue;
        ++touching;
        ASSERT_TRUE(std::binary_search(row, row + pl.near_count[i], s))
            << "step " << step << ": grains " << i << " and " << j
            << " overlap but are not in the near list";
      }
    }
    dem.advance(g, none, dt);
  }
  EXPECT_GT(touching, 1000);
  EXPECT_LT(near, listed / 2) << "the near list is not shorter than the Verlet rows";
  EXPECT_GT(dem.counters().rebuilds, 1);
}

}  // namespace
}  // namespace sandflow
