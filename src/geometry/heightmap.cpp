#include "geometry/heightmap.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <utility>

#include "core/rng.hpp"

namespace sandflow {

HeightGrid noise_heights(const std::array<Real, 4>& extent, Real wavelength, std::uint64_t seed,
                         Real z_min, Real z_max) {
  const auto& [x0, y0, x1, y1] = extent;
  const auto samples = [&](Real len) {
    const Real n = std::ceil(len / (wavelength / 16)) + 1;
    return static_cast<int>(std::clamp(n, 2.0, static_cast<Real>(kMaxNoiseSide)));
  };
  HeightGrid g;
  g.nx = samples(x1 - x0);
  g.ny = samples(y1 - y0);
  // six plane waves: direction, wavenumber and phase from the seed
  struct Wave {
    Real kx, ky, phase;
  };
  Rng rng(seed);
  std::array<Wave, 6> waves;
  for (Wave& w : waves) {
    const Real angle = rng.uniform(0, 2 * kPi);
    const Real k = 2 * kPi / (wavelength * rng.uniform(0.7, 1.4));
    w = {k * std::cos(angle), k * std::sin(angle), rng.uniform(0, 2 * kPi)};
  }
  g.z.resize(static_cast<std::size_t>(g.nx) * static_cast<std::size_t>(g.ny));
  for (int j = 0; j < g.ny; ++j)
    for (int i = 0; i < g.nx; ++i) {
      const Real x = x0 + (x1 - x0) * i / (g.nx - 1), y = y0 + (y1 - y0) * j / (g.ny - 1);
      Real s = 0;
      for (const Wave& w : waves) s += std::cos(w.kx * x + w.ky * y + w.phase);
      g.z[static_cast<std::size_t>(j) * g.nx + i] = s;
    }
  // scale the samples onto [z_min, z_max]
  const auto [lo, hi] = std::minmax_element(g.z.begin(), g.z.end());
  const Real a = *lo, span = *hi - *lo;
  for (Real& z : g.z) z = span > 0 ? z_min + (z_max - z_min) * (z - a) / span : z_min;
  return g;
}

SolidHeightmap::SolidHeightmap(HeightGrid grid, const std::array<Real, 4>& extent,
                               Real base_thickness)
    : g_(std::move(grid)),
      x0_(extent[0]),
      y0_(extent[1]),
      x1_(extent[2]),
      y1_(extent[3]) {
  if (g_.nx < 2 || g_.ny < 2 ||
      g_.z.size() != static_cast<std::size_t>(g_.nx) * static_cast<std::size_t>(g_.ny) ||
      !(x1_ > x0_) || !(y1_ > y0_))
    throw std::invalid_argument("SolidHeightmap: need a grid of at least 2 x 2 samples over a "
                                "non-empty extent");
  dx_ = (x1_ - x0_) / (g_.nx - 1);
  dy_ = (y1_ - y0_) / (g_.ny - 1);
  const auto [lo, hi] = std::minmax_element(g_.z.begin(), g_.z.end());
  bottom_ = *lo - base_thickness;
  top_ = *hi;

  // level 0: the largest slope of each cell (at one of its corners); level k + 1: of 2 x 2 blocks
  int nx = g_.nx - 1, ny = g_.ny - 1;
  std::vector<Real> level(static_cast<std::size_t>(nx) * ny);
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) level[static_cast<std::size_t>(j) * nx + i] = cell_max_slope(i, j, 0, 1, 0, 1);
  pyramid_.push_back(std::move(level));
  pyr_n_.push_back({nx, ny});
  while (nx > 1 || ny > 1) {
    const int mx = (nx + 1) / 2, my = (ny + 1) / 2;
    const std::vector<Real>& fine = pyramid_.back();
    std::vector<Real> coarse(static_cast<std::size_t>(mx) * my, 0.0);
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        Real& c = coarse[static_cast<std::size_t>(j / 2) * mx + i / 2];
        c = std::max(c, fine[static_cast<std::size_t>(j) * nx + i]);
      }
    pyramid_.push_back(std::move(coarse));
    pyr_n_.push_back({mx, my});
    nx = mx;
    ny = my;
  }
}

SolidHeightmap::Local SolidHeightmap::surface_at(Real x, Real y) const {
  const Real u = (std::clamp(x, x0_, x1_) - x0_) / dx_, w = (std::clamp(y, y0_, y1_) - y0_) / dy_;
  const int i = std::min(static_cast<int>(u), g_.nx - 2), j = std::min(static_cast<int>(w), g_.ny - 2);
  const Real s = u - i, t = w - j;
  const std::size_t k = static_cast<std::size_t>(j) * g_.nx + i;
  const Real z00 = g_.z[k], z10 = g_.z[k + 1], z01 = g_.z[k + g_.nx], z11 = g_.z[k + g_.nx + 1];
  return {(1 - t) * ((1 - s) * z00 + s * z10) + t * ((1 - s) * z01 + s * z11),
          ((1 - t) * (z10 - z00) + t * (z11 - z01)) / dx_,
          ((1 - s) * (z01 - z00) + s * (z11 - z10)) / dy_};
}

// f_x depends on t only and f_y on s only, each linearly: |grad f|^2 is largest at a corner.
Real SolidHeightmap::cell_max_slope(int i, int j, Real sa, Real sb, Real ta, Real tb) const {
  const std::size_t k = static_cast<std::size_t>(j) * g_.nx + i;
  const Real z00 = g_.z[k], z10 = g_.z[k + 1], z01 = g_.z[k + g_.nx], z11 = g_.z[k + g_.nx + 1];
  const auto fx = [&](Real t) { return ((1 - t) * (z10 - z00) + t * (z11 - z01)) / dx_; };
  const auto fy = [&](Real s) { return ((1 - s) * (z01 - z00) + s * (z11 - z10)) / dy_; };
  const Real ax = std::max(std::abs(fx(ta)), std::abs(fx(tb)));
  const Real ay = std::max(std::abs(fy(sa)), std::abs(fy(sb)));
  return std::sqrt(ax * ax + ay * ay);  // (hypot's overflow care costs 12 % of a terrain run)
}

Real SolidHeightmap::max_slope(Real xa, Real ya, Real xb, Real yb) const {
  const Real ua = (std::clamp(xa, x0_, x1_) - x0_) / dx_, ub = (std::clamp(xb, x0_, x1_) - x0_) / dx_;
  const Real wa = (std::clamp(ya, y0_, y1_) - y0_) / dy_, wb = (std::clamp(yb, y0_, y1_) - y0_) / dy_;
  const int i0 = std::min(static_cast<int>(ua), g_.nx - 2), i1 = std::min(static_cast<int>(ub), g_.nx - 2);
  const int j0 = std::min(static_cast<int>(wa), g_.ny - 2), j1 = std::min(static_cast<int>(wb), g_.ny - 2);
  Real L = 0;
  if ((i1 - i0 + 1) * (j1 - j0 + 1) <= 16) {
    // a few cells: the exact largest slope over the part of each cell inside the window
    for (int j = j0; j <= j1; ++j)
      for (int i = i0; i <= i1; ++i)
        L = std::max(L, cell_max_slope(i, j, std::clamp(ua - i, 0.0, 1.0), std::clamp(ub - i, 0.0, 1.0),
                                       std::clamp(wa - j, 0.0, 1.0), std::clamp(wb - j, 0.0, 1.0)));
    return L;
  }
  // many cells: the coarsest level at which the window spans at most 2 x 2 blocks
  std::size_t k = 0;
  while (k + 1 < pyramid_.size() && ((i1 >> k) - (i0 >> k) > 1 || (j1 >> k) - (j0 >> k) > 1)) ++k;
  const int n = pyr_n_[k][0];
  for (int j = j0 >> k; j <= (j1 >> k); ++j)
    for (int i = i0 >> k; i <= (i1 >> k); ++i)
      L = std::max(L, pyramid_[k][static_cast<std::size_t>(j) * n + i]);
  return L;
}

SolidHeightmap::Bound SolidHeightmap::top_bound(Real cx, Real cy, Real z, const Local& s) const {
  // the local-plane estimate and its foot point, an upper bound of the distance once put on the
  // surface
  const Real delta = std::abs(z - s.f), sign = z >= s.f ? 1.0 : -1.0;
  const Real len = std::sqrt(1 + s.fx * s.fx + s.fy * s.fy);
  const Vec3 n{-s.fx / len, -s.fy / len, 1 / len};
  const Real d_lp = delta / len;
  const Real qx = std::clamp(cx - sign * d_lp * n.x, x0_, x1_);
  const Real qy = std::clamp(cy - sign * d_lp * n.y, y0_, y1_);
  const Real d_up = std::min(delta, norm(Vec3{qx - cx, qy - cy, height(qx, qy) - z}));
  // the largest slope within reach of the nearest point bounds how close the surface can come
  const Real L = max_slope(cx - d_up, cy - d_up, cx + d_up, cy + d_up);
  return {delta / std::sqrt(1 + L * L), n};
}

SurfacePoint SolidHeightmap::closest(const Vec3& p) const {
  // c: the nearest point of the rectangle; h_out: how far p is beside it
  const Real cx = std::clamp(p.x, x0_, x1_), cy = std::clamp(p.y, y0_, y1_);
  const Real ox = p.x - cx, oy = p.y - cy;
  const Real h_out = std::sqrt(ox * ox + oy * oy);
  const Local s = surface_at(cx, cy);

  if (h_out > 0 || p.z > s.f || p.z < bottom_) {
    // outside: sqrt(h_out^2 + v^2), v the vertical part above the top or below the bottom
    Real v = 0;
    Vec3 nv{};
    if (p.z > s.f) {
      const Bound b = top_bound(cx, cy, p.z, s);
      v = b.v;
      nv = b.n;
    } else if (p.z < bottom_) {
      v = bottom_ - p.z;
      nv = {0, 0, -1};
    }
    const Real d = std::sqrt(h_out * h_out + v * v);
    Vec3 n = Vec3{ox, oy, 0} + nv * v;
    const Real nn = norm(n);
    n = nn > 0 ? n / nn : (v > 0 ? nv : Vec3{ox, oy, 0} / h_out);
    return {d, n};
  }
  // inside: the nearest of the top, the bottom and the four sides
  const Bound top = top_bound(cx, cy, p.z, s);
  SurfacePoint best{top.v, top.n};
  const auto consider = [&best](Real d, const Vec3& n) {
    if (d < best.distance) best = {d, n};
  };
  consider(p.z - bottom_, {0, 0, -1});
  consider(p.x - x0_, {-1, 0, 0});
  consider(x1_ - p.x, {1, 0, 0});
  consider(p.y - y0_, {0, -1, 0});
  consider(y1_ - p.y, {0, 1, 0});
  best.distance = -best.distance;
  return best;
}

void SolidHeightmap::vertical_stretches(Real x, Real y, Stretches& out) const {
  if (x >= x0_ && x <= x1_ && y >= y0_ && y <= y1_) out.push_back({bottom_, height(x, y)});
}

void SolidHeightmap::bounds(Vec3& lo, Vec3& hi) const {
  lo = {x0_, y0_, bottom_};
  hi = {x1_, y1_, top_};
}

}  // namespace sandflow
