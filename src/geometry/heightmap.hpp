// A terrain: the solid below a surface z = f(x, y) over a rectangle, down to a flat bottom, with
// vertical sides at the rectangle's edges (grains that leave the rectangle fall off the edge).
//
// f is bilinear between the grid samples. Bilinear rather than bicubic: it never overshoots the
// samples (the surface stays within [lowest, highest sample], so the bottom below the lowest
// sample is always under it), it is cheap, and the largest slope over any rectangle inside a cell
// is at one of the rectangle's corners (the gradient is an affine function of (x, y) within a
// cell, so its length is convex), which makes the conservative distance below exact to compute.
//
// The signed distance. The exact distance to a height field is expensive; the local-plane
// estimate d_lp = (z - f) / sqrt(1 + |grad f|^2), with the normal (-f_x, -f_y, 1) / sqrt(...),
// is cheap and accurate to second order, but it can overestimate (above a valley, beside a peak),
// and sphere tracing by an overestimate can step through a surface. So closest() returns a bound
// that never exceeds the true distance D, and agrees with d_lp to second order:
//
//   Let delta = |z - f(c)| be the vertical gap at c = (x, y). Some surface point lies within
//   D_up <= delta of p (the foot of d_lp, evaluated on the surface, or the point straight above or
//   below), so the nearest point q of the surface lies horizontally within D_up of c. Let L be the
//   largest slope |grad f| over the square of half-side D_up around c. Along the segment from c to
//   q_xy, f rises by at most L rho (rho = |q_xy - c|), so D^2 >= rho^2 + (delta - L rho)^2 >=
//   delta^2 / (1 + L^2). Hence d = delta / sqrt(1 + L^2) <= D.
//
// Error bound: L - |grad f(c)| is the variation of the slope over a window of half-side D_up, at
// most about (D_up + h) / R_c for a terrain whose slope changes by 1 over a length R_c (its radius
// of curvature, for gentle slopes) sampled with spacing h (a bilinear surface has creases at the
// cell edges of that order). So 0 <= D - d <= delta (L - g) g / (1 + g^2)^(3/2) + O(delta^2 / R_c)
// ~ delta (delta + h) / R_c: second order in (grain size + cell size) / radius of curvature. For a
// grain of radius 5 mm on the terrain of tests/geometry/test_heightmap.cpp that is a few percent
// of the gap, measured there against brute force.
//
// Within reach. A grain's contact needs the distance itself, not a bound: where the slope varies
// within a grain (rough or steep terrains, finely sampled), L far exceeds |grad f(c)| and d is a
// fraction of D, so grains would rest on nothing. So when d is below the reach given at
// construction (the largest grain's diameter) and falls short of the distance to a known point of
// the surface (the foot above) by more than kExactTolerance of it, closest() refines it by branch
// and bound over the cells within that distance: blocks of cells bounded by the boxes of their
// heights (a pyramid of block ranges), then parts of cells, each bounded by its box, by the slab
// of its bilinear patch about its mean plane (half-thickness |twist| / 4) and by the tetrahedron
// of its corners (its hull, exact at its edges and corners, where rough terrains are met),
// halving the most promising parts until the least bound is within tolerance of the nearest
// surface point found; the normal points from that point. It returns the bound, still never above
// D. Beyond reach the cheap bound stands, and on a smooth terrain it is mostly within tolerance
// already: 87 % of the queries 3 to 8 mm above scenes/terrain.toml's surface go no further.
//
// Outside the rectangle, f is taken at the nearest point c of the rectangle, and with h_out the
// horizontal distance to the rectangle the distance is sqrt(h_out^2 + v^2), v the bound above
// (or the depth below the bottom): the rectangle is convex, so every solid point is at least
// h_out away horizontally plus its distance from the vertical line through c. That is exact
// beside the vertical sides and conservative above the edges. Inside the solid, the distance is
// the nearest of the top (the same bound, downwards), the sides and the bottom.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <limits>
#include <vector>

#include "geometry/shapes.hpp"

namespace sandflow {

/// The most samples a heightmap may have along either side; larger grids are refused before
/// anything is allocated.
constexpr int kMaxHeightmapSide = 4096;
/// The most samples all the heightmaps of a scene may have together: one of the largest (about
/// 0.6 GB while a scene with it is checked).
constexpr std::size_t kMaxHeightmapSamples = std::size_t{kMaxHeightmapSide} * kMaxHeightmapSide;
/// Noise terrains are sampled every wavelength / 16, with at most this many samples a side.
constexpr int kMaxNoiseSide = 1024;
/// Within reach, closest() is the distance to the surface less at most this fraction of it (plus
/// 1e-4 of a cell side): 50 um for a grain of 5 mm. (1e-3 refines 60 % of the contact queries of
/// scenes/terrain.toml instead of 13 %, and doubled the time of its first 15 frames.)
constexpr Real kExactTolerance = 1e-2;

/// A deterministic smooth terrain over `extent`: a sum of 6 plane waves (directions, wavelengths in
/// [0.7, 1.4] x `wavelength` and phases drawn from `seed`), sampled every wavelength / 16 (at most
/// kMaxNoiseSide samples a side) and scaled so that its lowest sample is z_min and its highest
/// z_max.
HeightGrid noise_heights(const std::array<Real, 4>& extent, Real wavelength, std::uint64_t seed,
                         Real z_min, Real z_max);

class SolidHeightmap final : public Solid {
 public:
  /// `grid` must have at least 2 x 2 samples; the solid reaches base_thickness below the lowest.
  /// `reach`: closest() is exact (within kExactTolerance) up to that distance, a lower bound
  /// beyond it (the largest grain's diameter, in a scene).
  SolidHeightmap(HeightGrid grid, const std::array<Real, 4>& extent, Real base_thickness,
                 Real reach = std::numeric_limits<Real>::infinity());

  SurfacePoint closest(const Vec3& p) const override;
  void bounds(Vec3& lo, Vec3& hi) const override;
  /// [bottom, f(x, y)] inside the rectangle (its edges included), nothing beside it.
  void vertical_stretches(Real x, Real y, Stretches& out) const override;
  Real least_width() const override { return std::numeric_limits<Real>::infinity(); }

  /// Queries within reach that stopped at the cap on the pieces examined (4,096) with a lower
  /// bound, not the distance: grains there may rest up to the bound's shortfall above the
  /// surface. None in the tests' grids, down to 2,001^2 random samples under a grain.
  std::int64_t capped_queries() const { return capped_.load(std::memory_order_relaxed); }

  /// f(x, y), bilinear between samples; outside the extent, f at its nearest point.
  Real height(Real x, Real y) const { return surface_at(x, y).f; }
  Real bottom() const { return bottom_; }

 private:
  struct Local {
    Real f, fx, fy;  // height [m] and its gradient [-]
  };
  struct Bound {
    Real v;  // lower bound of the distance from the top surface [m]
    Vec3 n;  // the local-plane normal (upwards)
    Vec3 q;  // a point of the top surface no farther than delta (the foot, or straight above/below)
  };
  struct Exact {
    Real lb;  // within tolerance(lb) of the distance, or a lower bound of at least reach_ [m]
    Vec3 q;   // the nearest point found
  };
  struct ZRange {
    float lo, hi;  // lowest and highest sample of a block, rounded outwards [m]
  };
  Local surface_at(Real x, Real y) const;
  Bound top_bound(Real cx, Real cy, Real z, const Local& s) const;
  /// Largest |grad f| over [xa, xb] x [ya, yb] (clamped to the extent); exact for a few cells,
  /// an upper bound from the pyramid of block maxima beyond.
  Real max_slope(Real xa, Real ya, Real xb, Real yb) const;
  Real cell_max_slope(int i, int j, Real sa, Real sb, Real ta, Real tb) const;
  Real cell_z(int i, int j, bool highest) const;
  /// How far a bound may fall short of the distance d and still stand for it.
  Real tolerance(Real d) const;
  /// The distance from p to the top surface (column false) or to the solid (true), by branch and
  /// bound over the cells within ub of p, starting from q, a point of it ub away.
  Exact exact(const Vec3& p, bool column, Real ub, Vec3 q) const;

  HeightGrid g_;
  Real x0_, y0_, x1_, y1_, dx_, dy_;
  Real bottom_, top_;
  /// pyramid_[k]: largest slope over blocks of 2^k x 2^k cells, pyr_n_[k] blocks along x, y
  std::vector<std::vector<Real>> pyramid_;
  std::vector<std::array<int, 2>> pyr_n_;
  /// z_pyramid_[k], k >= 1: the range of heights over blocks of 2^k x 2^k cells, pyr_n_[k] blocks
  /// along x, y (z_pyramid_[0] is empty: a cell's range is that of its samples)
  std::vector<std::vector<ZRange>> z_pyramid_;
  Real reach_;
  mutable std::atomic<std::int64_t> capped_{0};  // (touched only by a capped query)
};

}  // namespace sandflow
