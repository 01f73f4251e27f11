// The bed generator (geometry/bed_packing.hpp): the packing fraction of its bulk, exact contacts
// (a brute-force check of every pair), grains inside the footprint, on the floor and under the
// top (flat, a heightmap floor, a sloped top), an obstacle respected, every grain stably supported
// (a bed dropped grain by grain and one with a slab laid from the periodic tile),
// the same bed for the same seed and for 1 and 2 threads, an exception of `blocked` passed on, and
// the grain limit.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <unordered_map>
#include <vector>

#include "geometry/bed_packing.hpp"

namespace sandflow {
namespace {

constexpr Real kBedD = 0.01;  // diameter of the equal grains [m]

BedRegion flat_bed(Real side_d, Real height_d) {
  BedRegion R;
  R.x0 = R.y0 = 0;
  R.x1 = R.y1 = side_d * kBedD;
  R.floor = [](Real, Real) { return 0.0; };
  R.top = [h = height_d * kBedD](Real, Real) { return h; };
  R.r_lo = R.r_hi = kBedD / 2;
  return R;
}

// The largest overlap of any two grains over the smaller diameter, pair by pair.
Real brute_overlap(const BedPacking& b) {
  Real worst = 0;
  for (std::size_t i = 0; i < b.size(); ++i)
    for (std::size_t j = i + 1; j < b.size(); ++j) {
      const Real s = b.r[i] + b.r[j];
      const Real d = norm(b.x[i] - b.x[j]);
      if (d < s) worst = std::max(worst, (s - d) / (2 * std::min(b.r[i], b.r[j])));
    }
  return worst;
}

TEST(BedPacking, BulkPackingFractionIsThatOfRandomDeposition) {
  // about 20,000 equal grains; random sequential deposition with rolling gives 0.58 (Visscher &
  // Bolsterli); a box 4 diameters inside the floor, the walls and the top, where they order it
  const BedPacking b = pack_bed(flat_bed(32, 20));
  ASSERT_GT(b.size(), 18000u);
  const Real m = 4 * kBedD;
  const Real phi =
      packing_fraction_in(b.x, b.r, {m, m, m}, {32 * kBedD - m, 32 * kBedD - m, 20 * kBedD - m});
  EXPECT_GT(phi, 0.56);
  EXPECT_LT(phi, 0.64);
  // and the helper agrees with the brute-force overlap on a part of it
  EXPECT_LT(largest_overlap(b.x, b.r), 1e-3);
}

TEST(BedPacking, ContactsAreExactTouches) {
  // equal grains and grains of three sizes; every pair checked
  for (Real spread : {0.0, 0.3}) {
    BedRegion R = flat_bed(14, 8);
    R.r_lo = kBedD / 2 * (1 - spread);
    R.r_hi = kBedD / 2 * (1 + spread);
    const BedPacking b = pack_bed(R);
    ASSERT_GT(b.size(), 1000u);
    EXPECT_LT(brute_overlap(b), 1e-3) << "spread " << spread;
    EXPECT_NEAR(largest_overlap(b.x, b.r), brute_overlap(b), 1e-12);
  }
}

TEST(BedPacking, GrainsStayInsideTheFootprintOnTheFloorAndUnderTheTop) {
  BedRegion R = flat_bed(12, 6);
  R.x0 = -0.03;  // (a footprint off the origin, not a whole number of cells wide)
  R.x1 = 0.0871;
  const BedPacking b = pack_bed(R);
  ASSERT_GT(b.size(), 300u);
  for (std::size_t i = 0; i < b.size(); ++i) {
    const Vec3& x = b.x[i];
    const Real r = b.r[i];
    EXPECT_GE(x.x - r, R.x0 - 1e-6 * kBedD);
    EXPECT_LE(x.x + r, R.x1 + 1e-6 * kBedD);
    EXPECT_GE(x.y - r, R.y0 - 1e-6 * kBedD);
    EXPECT_LE(x.y + r, R.y1 + 1e-6 * kBedD);
    EXPECT_GE(x.z - r, -1e-12);
    EXPECT_LE(x.z + r, 6 * kBedD + 1e-12);
  }
}

TEST(BedPacking, HeightmapFloorAndSlopedTopAreRespected) {
  // a wavy floor (amplitude one diameter, wavelength 12) and a top sloping 10 degrees
  BedRegion R = flat_bed(24, 0);
  const Real k = 2 * kPi / (12 * kBedD);
  auto floor = [k](Real x, Real y) { return kBedD * std::sin(k * x) * std::cos(0.7 * k * y); };
  auto top = [](Real x, Real) { return 7 * kBedD + std::tan(deg_to_rad(10)) * x; };
  R.floor = floor;
  R.top = top;
  const BedPacking b = pack_bed(R);
  ASSERT_GT(b.size(), 2000u);
  std::size_t on_floor = 0;
  for (std::size_t i = 0; i < b.size(); ++i) {
    const Vec3& x = b.x[i];
    const Real r = b.r[i];
    EXPECT_LE(x.z, top(x.x, x.y) - r + 1e-12);
    // no grain reaches into the true floor by more than 1 % of d (it is sampled every r_lo and
    // met through tangent planes: within r^2 / R_c, here about 0.5 %): the sphere against the
    // floor at points of its footprint
    Real lowest_gap = 1;
    for (int a = 0; a < 12; ++a)
      for (Real f : {0.0, 0.3, 0.6, 0.9}) {
        const Real px = x.x + f * r * std::cos(a * kPi / 6),
                   py = x.y + f * r * std::sin(a * kPi / 6);
        const Real rho2 = (px - x.x) * (px - x.x) + (py - x.y) * (py - x.y);
        lowest_gap = std::min(lowest_gap, x.z - std::sqrt(r * r - rho2) - floor(px, py));
      }
    EXPECT_GT(lowest_gap, -0.01 * kBedD) << "grain " << i;
    on_floor += lowest_gap < 0.02 * kBedD;
  }
  EXPECT_GT(on_floor, 200u);  // (the floor carries its layer)
}

TEST(BedPacking, AnObstacleIsRespectedAndBuriedWithGrainsAboveIt) {
  // a sphere of radius 4 d standing on the floor; the floor the bed rests on is its top where it
  // has one, and a grain intersecting it is refused
  BedRegion R = flat_bed(24, 12);
  const Vec3 s{12 * kBedD, 12 * kBedD, 3 * kBedD};
  const Real S = 4 * kBedD;
  R.floor = [s, S](Real x, Real y) {
    const Real rho2 = (x - s.x) * (x - s.x) + (y - s.y) * (y - s.y);
    return rho2 < S * S ? std::max(0.0, s.z + std::sqrt(S * S - rho2)) : 0.0;
  };
  R.blocked = [s, S](const Vec3& c, Real r) { return norm(c - s) < S + r; };
  const BedPacking b = pack_bed(R);
  ASSERT_GT(b.size(), 3000u);
  EXPECT_GT(b.blocked, 0);
  std::size_t above = 0;
  for (std::size_t i = 0; i < b.size(); ++i) {
    EXPECT_GE(norm(b.x[i] - s), S + b.r[i] - 1e-3 * kBedD) << "grain " << i;
    above += std::hypot(b.x[i].x - s.x, b.x[i].y - s.y) < S / 2 && b.x[i].z > s.z + S;
  }
  EXPECT_GT(above, 20u);  // the sand covers it, no hole left over it
}

// Grains neither on the floor (z = 0) nor held by three of their contacts (grains or walls of the
// footprint, touching within 1e-6 d) with gravity inside the cone of their normals: the rule the
// generator stops on. Neighbours through a grid of cells a largest diameter wide.
std::size_t count_unsupported(const BedPacking& b, const BedRegion& R) {
  const Real tol = 1e-6 * kBedD, cs = 2 * R.r_hi;
  auto key = [&](const Vec3& x, int dx, int dy, int dz) {
    const auto i = static_cast<std::int64_t>(std::floor((x.x - R.x0) / cs)) + dx;
    const auto j = static_cast<std::int64_t>(std::floor((x.y - R.y0) / cs)) + dy;
    const auto k = static_cast<std::int64_t>(std::floor(x.z / cs)) + dz;
    return (i * 100003 + j) * 1009 + k;
  };
  std::unordered_map<std::int64_t, std::vector<std::size_t>> grid;
  for (std::size_t i = 0; i < b.size(); ++i) grid[key(b.x[i], 0, 0, 0)].push_back(i);
  std::size_t unsupported = 0;
  for (std::size_t i = 0; i < b.size(); ++i) {
    const Vec3& x = b.x[i];
    const Real r = b.r[i];
    if (x.z - r < tol) continue;  // on the floor
    std::vector<Vec3> n;
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const auto it = grid.find(key(x, dx, dy, dz));
          if (it == grid.end()) continue;
          for (std::size_t j : it->second)
            if (j != i && std::abs(norm(x - b.x[j]) - r - b.r[j]) < tol)
              n.push_back((x - b.x[j]) / norm(x - b.x[j]));
        }
    if (x.x - r - R.x0 < tol) n.push_back({1, 0, 0});
    if (R.x1 - x.x - r < tol) n.push_back({-1, 0, 0});
    if (x.y - r - R.y0 < tol) n.push_back({0, 1, 0});
    if (R.y1 - x.y - r < tol) n.push_back({0, -1, 0});
    bool stable = false;
    for (std::size_t a = 0; a < n.size() && !stable; ++a)
      for (std::size_t c = a + 1; c < n.size() && !stable; ++c)
        for (std::size_t e = c + 1; e < n.size() && !stable; ++e) {
          const Real det = dot(n[a], cross(n[c], n[e]));
          if (std::abs(det) < 1e-9) continue;
          stable = cross(n[c], n[e]).z / det >= -1e-9 && cross(n[e], n[a]).z / det >= -1e-9 &&
                   cross(n[a], n[c]).z / det >= -1e-9;
        }
    unsupported += !stable;
  }
  return unsupported;
}

TEST(BedPacking, EveryGrainIsStablySupported) {
  const BedRegion R = flat_bed(12, 8);
  const BedPacking b = pack_bed(R);
  ASSERT_GT(b.size(), 500u);
  EXPECT_EQ(b.tiled, 0);  // (too small for the slab: dropped grain by grain)
  EXPECT_EQ(count_unsupported(b, R), 0u);
}

TEST(BedPacking, TheSlabFromAPeriodicTileIsADropBedAtRest) {
  // 80 d square, 11 d deep, radii from 0.4 d to 0.6 d: wide and deep enough for the slab (two
  // tiles of 32 columns of 1.2 d, 4 cells under a cut 2 cells below the top). Its grains, those
  // fallen into the bands its cut leaves along the walls and those dropped over it form one bed:
  // no overlap, every grain inside and at rest, the bulk packed as a bed dropped grain by grain is
  // (the same region 70 d wide, too narrow for the slab), and the same bed on 1 and 2 threads.
  BedRegion R = flat_bed(80, 11);
  R.r_lo = 0.4 * kBedD;
  R.r_hi = 0.6 * kBedD;
  const BedPacking b = pack_bed(R);
  ASSERT_GT(b.size(), 40000u);
  EXPECT_GT(b.tiled, static_cast<std::int64_t>(b.size() / 3));
  EXPECT_LT(largest_overlap(b.x, b.r), 1e-3);
  for (std::size_t i = 0; i < b.size(); ++i) {
    const Vec3& x = b.x[i];
    const Real r = b.r[i];
    ASSERT_TRUE(x.x - r >= -1e-6 * kBedD && x.x + r <= R.x1 + 1e-6 * kBedD &&
                x.y - r >= -1e-6 * kBedD && x.y + r <= R.y1 + 1e-6 * kBedD && x.z - r >= -1e-12 &&
                x.z + r <= 11 * kBedD + 1e-12)
        << "grain " << i << " of " << b.size();
  }
  EXPECT_EQ(count_unsupported(b, R), 0u);
  const Real m = 4 * kBedD;
  const Real phi =
      packing_fraction_in(b.x, b.r, {m, m, m}, {80 * kBedD - m, 80 * kBedD - m, 7 * kBedD});
  BedRegion narrow = R;
  narrow.x1 = narrow.y1 = 70 * kBedD;
  const BedPacking c = pack_bed(narrow);
  EXPECT_EQ(c.tiled, 0);
  const Real phi_dropped =
      packing_fraction_in(c.x, c.r, {m, m, m}, {70 * kBedD - m, 70 * kBedD - m, 7 * kBedD});
  EXPECT_NEAR(phi, phi_dropped, 0.006) << "slab " << phi << ", dropped " << phi_dropped;
  R.threads = 2;
  const BedPacking d = pack_bed(R);
  EXPECT_TRUE(d.x == b.x && d.r == b.r);
}

TEST(BedPacking, TheCopiesAlongAWallRestAsTheirTemplateAndPackAsADroppedBed) {
  // 224 d x 80 d, 10 d deep, equal grains: seven copies of the tile along each long wall, so the
  // cut's cone along it is settled once, in the middle copy, and laid shifted in the copies cut
  // the same way. Those grains must rest (every grain held), overlap nothing, and the band along
  // the wall must pack as in a bed dropped grain by grain (the same depth, too narrow for the
  // slab). Without the check that each copied grain's holders lie shifted too, grains float.
  BedRegion R = flat_bed(224, 10);
  R.y1 = 80 * kBedD;
  const BedPacking b = pack_bed(R);
  ASSERT_GT(b.tiled, static_cast<std::int64_t>(b.size() / 2));
  EXPECT_GT(b.copied, 5000);
  EXPECT_LT(largest_overlap(b.x, b.r), 1e-5);
  EXPECT_EQ(count_unsupported(b, R), 0u);
  // the bands 1 d to 12 d from the two walls along x, from 3 d over the floor up to 7 d
  const Real m = 3 * kBedD;
  auto band = [&](const BedPacking& p, const BedRegion& r) {
    return 0.5 * (packing_fraction_in(p.x, p.r, {m, kBedD, m}, {r.x1 - m, 12 * kBedD, 7 * kBedD}) +
                  packing_fraction_in(p.x, p.r, {m, r.y1 - 12 * kBedD, m},
                                      {r.x1 - m, r.y1 - kBedD, 7 * kBedD}));
  };
  BedRegion narrow = R;
  narrow.x1 = narrow.y1 = 60 * kBedD;
  const BedPacking c = pack_bed(narrow);
  ASSERT_EQ(c.tiled, 0);
  const Real phi = band(b, R), phi_dropped = band(c, narrow);
  EXPECT_NEAR(phi, phi_dropped, 0.01) << "slab " << phi << ", dropped " << phi_dropped;
}

TEST(BedPacking, TheSameSeedGivesTheSameBed) {
  BedRegion R = flat_bed(10, 6);
  R.r_lo = 0.4 * kBedD;
  const BedPacking a = pack_bed(R), b = pack_bed(R);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a.x[i], b.x[i]);
    EXPECT_EQ(a.r[i], b.r[i]);
  }
  R.seed = 2;
  const BedPacking c = pack_bed(R);
  EXPECT_FALSE(c.size() == a.size() && c.x == a.x);
}

TEST(BedPacking, OneAndTwoThreadsGiveTheSameBed) {
  // 40 d x 40 d: tiles of 16 columns, several of each colour a phase, so two threads share them
  BedRegion R = flat_bed(40, 6);
  R.r_lo = 0.4 * kBedD;
  const BedPacking a = pack_bed(R);
  R.threads = 2;
  const BedPacking b = pack_bed(R);
  ASSERT_GT(a.size(), 5000u);
  ASSERT_EQ(a.size(), b.size());
  EXPECT_EQ(a.drops, b.drops);
  EXPECT_TRUE(a.x == b.x && a.r == b.r);
}

TEST(BedPacking, AnExceptionOfBlockedReachesTheCaller) {
  // thrown on a tile's thread, it is kept and thrown again once the tiles of its phase are done
  for (int threads : {1, 2}) {
    BedRegion R = flat_bed(40, 4);
    R.threads = threads;
    R.blocked = [](const Vec3& c, Real) -> bool {
      if (c.z > 2 * kBedD) throw std::runtime_error("blocked failed");
      return false;
    };
    EXPECT_THROW(pack_bed(R), std::runtime_error) << threads << " threads";
  }
}

TEST(BedPacking, RefusesARegionBeyondItsLimitAndMalformedInput) {
  BedRegion R = flat_bed(100, 100);
  const Real estimate = estimate_bed_grains(R);
  // 100^3 d^3 at 0.60 over a grain volume of pi/6 d^3
  EXPECT_NEAR(estimate, 1e6 * 0.60 / (kPi / 6), 0.02 * estimate);
  R.max_grains = 1000;
  EXPECT_THROW(pack_bed(R), std::length_error);
  BedRegion empty = flat_bed(10, 5);
  empty.x1 = empty.x0;
  EXPECT_THROW(pack_bed(empty), std::invalid_argument);
  BedRegion nan_floor = flat_bed(10, 5);
  nan_floor.floor = [](Real, Real) { return std::nan(""); };
  EXPECT_THROW(pack_bed(nan_floor), std::invalid_argument);
  // a top below the floor everywhere holds nothing
  BedRegion sunk = flat_bed(10, 5);
  sunk.top = [](Real, Real) { return -0.1; };
  EXPECT_EQ(pack_bed(sunk).size(), 0u);
}

}  // namespace
}  // namespace sandflow
