// The distance between two sand surfaces (analysis/surface_diff.hpp): zero for the same surface,
// the offset for a surface raised evenly, and a column's width, not a shelf's height, where the
// edge of a shelf of sand falls a column earlier in one run than in the other.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "analysis/surface_diff.hpp"

namespace sandflow {
namespace {

constexpr int kN = 20;
constexpr Real kCell = 0.01;

HeightFieldParams grid() {
  HeightFieldParams p;
  p.cell = kCell;
  p.nx = p.ny = kN;
  return p;
}

// sand to `H(i, j)` over a floor at 0
template <class F>
MeasuredSurface surface(F&& H) {
  MeasuredSurface s;
  for (int j = 0; j < kN; ++j)
    for (int i = 0; i < kN; ++i) {
      s.H.push_back(H(i, j));
      s.L.push_back(0.0);
    }
  return s;
}

TEST(SurfaceDistance, ZeroForTheSameSurfaceAndTheOffsetForOneRaisedEvenly) {
  auto heap = [](int i, int j) { return 0.1 - 0.008 * std::hypot(i - 9.5, j - 9.5); };
  const MeasuredSurface a = surface(heap);
  EXPECT_EQ(surface_distance(grid(), a, a).rms, 0.0);
  // a plateau of sand raised by 3 mm everywhere: 3 mm apart wherever the top is flat
  auto flat = [](int, int) { return 0.05; };
  auto raised = [](int, int) { return 0.053; };
  const SurfaceDistance d = surface_distance(grid(), surface(flat), surface(raised));
  EXPECT_NEAR(d.rms, 0.003, 1e-12);
  EXPECT_EQ(d.samples, 2u * kN * kN);
}

TEST(SurfaceDistance, AShelfWhoseEdgeMovesByAColumnIsAColumnAway) {
  // sand 0.2 m deep on a shelf over the columns i < 10 in one run, i < 11 in the other; a thin
  // layer on the floor elsewhere. Column by column the one column differs by 0.19 m.
  auto a = surface([](int i, int) { return i < 10 ? 0.2 : 0.01; });
  auto b = surface([](int i, int) { return i < 11 ? 0.2 : 0.01; });
  const SurfaceDiff columns = compare_surfaces(a, b);
  EXPECT_NEAR(columns.rms, 0.19 / std::sqrt(kN), 1e-9);  // one column in kN differs by 0.19 m
  const SurfaceDistance d = surface_distance(grid(), a, b);
  // from the top of column 10 in b to a's cliff: half a column; from a's floor there to b's
  // cliff: half a column; everywhere else zero
  EXPECT_NEAR(d.max, 0.5 * kCell, 1e-12);
  EXPECT_NEAR(d.rms, 0.5 * kCell * std::sqrt(2.0 * kN / (2.0 * kN * kN)), 1e-12);
  EXPECT_LT(d.rms, 0.1 * columns.rms);
}

TEST(SurfaceDistance, FindsTheNearestPointFarAway) {
  // a single column of sand 5 cm high beside nothing: the point on its top is 5 cm from the floor
  // of the other surface straight below, nearer to nothing else
  auto a = surface([](int i, int j) { return i == 5 && j == 5 ? 0.05 : 0.0; });
  auto b = surface([](int, int) { return 0.0; });
  const SurfaceDistance d = surface_distance(grid(), a, b);
  EXPECT_NEAR(d.max, 0.05, 1e-12);
  EXPECT_EQ(d.samples, 2u);  // the one column with sand, both ways
  // and from the floor of b under the column to a's surface: its faces are half a column away
  EXPECT_NEAR(d.rms, std::sqrt((0.05 * 0.05 + 0.005 * 0.005) / 2), 1e-12);
}

}  // namespace
}  // namespace sandflow
