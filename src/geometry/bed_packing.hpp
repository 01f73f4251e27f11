// A packed bed of grains at rest, built without a DEM run (docs/design.md §7, issue 26): random
// sequential gravitational deposition with rolling, "drop and roll" (Visscher & Bolsterli 1972,
// Jodrey & Tory 1979). Each grain is dropped at a random (x, y) of the footprint, falls vertically
// to its first contact (a grain or the floor), then rolls down in steepest descent: over one sphere
// until it touches a second, in the groove of two until it touches a third, and stops where it is
// stably supported (gravity inside the cone of its three contact normals: for three spheres, its
// centre's projection inside their triangle) or where it touches the floor. The footprint's four
// sides are vertical walls, which support a grain like a sphere does (a grain in the groove of a
// sphere and a wall). It leaves one support when the other two would have to pull (the normal
// force of a contact turns negative), and falls again off a sphere's equator. Every motion is an
// arc of a circle, and every event along it (a new contact, a lift-off, the equator) the first
// root of a cos t + b sin t = c: the contacts are exact touches, up to rounding.
//
// A drop that would come to rest with its centre above top - r, or that `blocked` refuses (an
// obstacle there), is discarded. The footprint is cut into square cells of the grid's width
// (2 r_hi); drops are made at random points of the cells still open, and a cell closes after
// `patience` discarded drops in a row made in it (while every cell is open, the drops are uniform
// over the footprint). Why this fills the top everywhere: a drop that lands in a cell and rolls to
// rest below top - r proves a hole was left; one that cannot means the surface under it is full
// up to a grain below the top. A hole covering half a cell survives 3 drops made in it with
// probability 0.5^3 = 12.5 %, but the drops made around it roll into it too, and a grain fitting
// a smaller hole would rest within a grain of the top anyway. Measured (2026-11-26, a 40 d x 40 d
// bed 10 d deep, equal grains): patience 4, 8 and 16 give 16,438, 16,446 and 16,443 grains, the
// same bulk packing fraction (0.583), and every 2 d x 2 d patch of the top has a grain reaching
// within 0.62 d of it (median 0.11 d), while 16 makes 1.8 times the drops of 4. Again
// (2026-11-27, a 60 d x 60 d bed 22 d deep): patience 2, 3, 4 and 6 give 84,745, 84,730, 84,745
// and 84,751 grains, every patch within 0.60-0.65 d (median 0.11-0.12 d, 99 % within 0.49-0.53
// d); on the 1 M bench the same, 0.67-0.74 d. The top is full, not ragged, already at 2; the
// default, 3, keeps a margin of one.
// A cell where the top lies below the floor + 2 r_lo at every sample never opens.
//
// The order of the drops: in rounds. Each round cuts the footprint into tiles of 16 x 16 cells,
// shifted at random (no seam stays), coloured as a 2 x 2 checkerboard; colour after colour (in a
// random order), each tile with an open cell makes as many drops as it has open cells, from its
// own random stream. A drop far from another commutes with it: a grain comes to rest more than
// 2 d from where it was dropped in one drop of 600, more than 3 d in one of 30,000, none 4 d in
// 136,000 (2026-11-27); one that would read cells more than 7 beyond its tile is not made (none
// of the 1.2 million drops of the 1 M bench). Tiles of a colour are a tile apart, so their
// drops read and write disjoint cells: they run on `threads` threads at once, and the bed (its
// grains and their order: ids are reserved per tile in tile order) depends on the seed only, not
// on the threads. One tile's drops at a time also keep the grid they touch in the cache. The
// bed is as random as with one global order (2026-11-27, 300,000 grains, two seeds each): the
// same coordination (6.00), Steinhardt Q6 of the bulk 0.009-0.012 globally and 0.304 averaged
// over grains (0.575 in a crystal), contact normals even in azimuth, and slabs 2 d wide across
// the bulk vary by 0.003-0.004 in packing fraction (0.005-0.008 with the generator of 2026-11-26:
// one global order, and 2 % of its drops lost at a lift-off).
//
// The slab: where the floor is flat and the footprint at least two tiles wide (kSlabTile = 32
// columns), the bulk from the floor up to a cut two cells under the lowest top (when that leaves
// at least four cells) is not dropped grain by grain but laid from a tile: a 32 x 32-column square
// packed once by the same drops, periodic in x and y (the grains within reach of a side seen
// across it in ghost columns of their images), copied over the footprint at a random offset.
// A grain of a copy is laid when it lies under the cut, inside the footprint and not in an
// obstacle, and every grain that held it in the tile is laid: what is laid rests as it did. What
// the cut takes away (the grains crossing a wall) leaves a cone above it, up to about 30 d wide
// along the walls of a 20 d bed, of grains that lost a grain holding them. Those fall, from the
// lowest up, each from where it lay in the tile, and roll to rest in the hole under them (one
// whose place a grain fallen before it has taken is left out). Along a wall, the copies cut the
// same way as the one in the middle of their row or column take its fallen grains shifted, where
// the grains holding each lie shifted the same way and nothing is in its place: they rest as
// there (two thirds of the cone of the 1 M bench). Then the rest of the bed is dropped as before,
// with the top over the cut. The slab's grains repeat every 32 columns; its bulk packs as the
// dropped bed does (0.5829 against 0.5825 in the test). Mirror-image copies of a tile packed
// between walls, whose sides would match with nothing removed, ran twice as fast but packed the
// bulk at 0.572 against 0.582 (planes packed as at a wall every 32 d), so they are not used
// (docs/performance.md, 2026-11-27, seventh). The cone's grains were dropped at random points
// before, its holes found by chance layer after layer: on the 1 M bench 566,000 drops made the
// cone and the top, now 64,000 grains fall by themselves, 157,000 are copied and 221,000 drops
// make the top, 1.5 times as fast (docs/performance.md, 2026-11-27, ninth).
//
// Speed (docs/performance.md, 2026-11-27): a uniform grid of cells 2 r_hi wide, filed column by
// column (z fastest), with each column's highest filled cell, so that a fall scans only the top
// of 3 x 3 columns; an arc scans the cells of its bounding box widened by a contact's reach, a
// cell's three slots tested at once in floats and the grains in the box then tested without
// branches (whether one is in is a coin toss, which a branch predicts badly); the events'
// angles as cosines and sines, without trigonometry; the next drop's cells asked for ahead.
//
// The floor and the top are sampled on a grid of spacing r_lo, r_lo / 2 where the floor is not flat
// (bilinear between samples;
// at most 2^22 samples each, coarser on a larger footprint). A grain rests on the floor where its
// centre is r sqrt(1 + |grad f|^2) above the bilinear floor (a tangent plane: exact on planes, a
// hollow of curvature radius R_c is met within about r^2 / R_c); where the floor is steeper than
// 45 degrees (a step, an obstacle's flank), on the highest of its points r / 4 apart under the
// grain (within r / 32). A grain that touches the floor stops there.
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include "core/vec3.hpp"

namespace sandflow {

/// The region a bed fills and its grains.
struct BedRegion {
  Real x0 = 0, y0 = 0, x1 = 1, y1 = 1;  ///< the footprint: grains lie wholly inside it [m]
  /// The solid top the bed rests on at (x, y) [m]; finite everywhere on the footprint.
  std::function<Real(Real, Real)> floor;
  /// The bed's upper surface at (x, y) [m]: grain centres stay at or below top - r.
  std::function<Real(Real, Real)> top;
  /// Optional: true when a grain centred at c with radius r would intersect an obstacle.
  std::function<bool(const Vec3&, Real)> blocked;
  Real r_lo = 0.005, r_hi = 0.005;  ///< radii uniform in [r_lo, r_hi] [m]
  std::uint64_t seed = 1;
  int patience = 3;  ///< discarded drops in a row that close a cell (see above); a drop refused
                     ///< by `blocked` counts an eighth
  /// Refused (std::length_error) before any grain is placed when the region's volume would hold
  /// more grains than this (estimate_bed_grains).
  Real max_grains = 2147483647.0;
  /// Threads packing tiles at once (at least 1): the bed is the same for any number.
  int threads = 1;
};

struct BedPacking {
  std::vector<Vec3> x;         ///< centres [m]
  std::vector<Real> r;         ///< radii [m]
  std::int64_t drops = 0;      ///< grains dropped, kept or not
  std::int64_t discarded = 0;  ///< of them: came to rest above the top, or did not settle
  std::int64_t blocked = 0;    ///< of them: refused by `blocked`
  std::int64_t tiled = 0;      ///< grains laid from the periodic tile (not dropped)
  std::int64_t settled = 0;    ///< of them: fell from where they lay in the tile (see above)
  std::int64_t copied = 0;     ///< of those: laid as their template's grain, shifted
  std::size_t size() const { return x.size(); }
};

/// Grains the region holds at a packing fraction of 0.60, from its sampled floor and top: what
/// max_grains is checked against.
Real estimate_bed_grains(const BedRegion& region);

/// Packs the region (see the top of this file). Throws std::invalid_argument on a malformed
/// region (empty footprint, r_lo > r_hi, a non-finite floor or top, no floor or top function),
/// std::length_error past max_grains.
BedPacking pack_bed(const BedRegion& region);

// ---- Measurements of a packing (tests, bench) -------------------------------------------------

/// Volume of the grains whose centres lie in [lo, hi], over the box's volume: the packing fraction
/// of a box well inside a bed (the grains straddling its sides count in or out by their centres,
/// which is unbiased on average).
Real packing_fraction_in(const std::vector<Vec3>& x, const std::vector<Real>& r, const Vec3& lo,
                         const Vec3& hi);

/// The largest overlap r_i + r_j - |x_i - x_j| of any two grains, over the smaller diameter (0 when
/// none overlap), found through a grid of cells 2 max(r) wide.
Real largest_overlap(const std::vector<Vec3>& x, const std::vector<Real>& r);

}  // namespace sandflow
