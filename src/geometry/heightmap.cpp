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

namespace {

// One level up a pyramid over an nx x ny grid: each entry of the (nx + 1) / 2 x (ny + 1) / 2
// level combines, from `empty`, the (up to) four entries fine(k, i, j) under it (k = j nx + i).
template <class T, class Fine, class Combine>
std::vector<T> coarsen(int nx, int ny, T empty, Fine fine, Combine combine) {
  const int mx = (nx + 1) / 2, my = (ny + 1) / 2;
  std::vector<T> coarse(static_cast<std::size_t>(mx) * my, empty);
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      T& c = coarse[static_cast<std::size_t>(j / 2) * mx + i / 2];
      c = combine(c, fine(static_cast<std::size_t>(j) * nx + i, i, j));
    }
  return coarse;
}

}  // namespace

SolidHeightmap::SolidHeightmap(HeightGrid grid, const std::array<Real, 4>& extent,
                               Real base_thickness, Real reach)
    : g_(std::move(grid)),
      x0_(extent[0]),
      y0_(extent[1]),
      x1_(extent[2]),
      y1_(extent[3]),
      reach_(reach) {
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

  // Two pyramids over blocks of 2^k x 2^k cells, pyr_n_[k] blocks along x, y for both: the
  // largest slope (level 0: each cell's, at one of its corners) and, for the exact distance, the
  // range of heights rounded outwards to float (from level 1: a cell's own range comes from its
  // four samples)
  const auto down = [](Real v) {
    const float f = static_cast<float>(v);
    return static_cast<Real>(f) > v ? std::nextafter(f, -std::numeric_limits<float>::infinity())
                                    : f;
  };
  const auto up = [](Real v) {
    const float f = static_cast<float>(v);
    return static_cast<Real>(f) < v ? std::nextafter(f, std::numeric_limits<float>::infinity()) : f;
  };
  int nx = g_.nx - 1, ny = g_.ny - 1;
  std::vector<Real> level(static_cast<std::size_t>(nx) * ny);
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i)
      level[static_cast<std::size_t>(j) * nx + i] = cell_max_slope(i, j, 0, 1, 0, 1);
  pyramid_.push_back(std::move(level));
  z_pyramid_.emplace_back();  // level 0: not stored
  pyr_n_.push_back({nx, ny});
  const auto wider = [](ZRange a, ZRange b) {
    return ZRange{std::min(a.lo, b.lo), std::max(a.hi, b.hi)};
  };
  constexpr ZRange kNoRange{std::numeric_limits<float>::infinity(),
                            -std::numeric_limits<float>::infinity()};
  while (nx > 1 || ny > 1) {
    const std::vector<Real>& slopes = pyramid_.back();
    const std::vector<ZRange>& heights = z_pyramid_.back();
    const bool cells = z_pyramid_.size() == 1;
    std::vector<Real> coarse_slopes = coarsen(
        nx, ny, Real{0}, [&](std::size_t k, int, int) { return slopes[k]; },
        [](Real a, Real b) { return std::max(a, b); });
    std::vector<ZRange> coarse_heights = coarsen(
        nx, ny, kNoRange,
        [&](std::size_t k, int i, int j) {
          return cells ? ZRange{down(cell_z(i, j, false)), up(cell_z(i, j, true))} : heights[k];
        },
        wider);
    pyramid_.push_back(std::move(coarse_slopes));
    z_pyramid_.push_back(std::move(coarse_heights));
    nx = (nx + 1) / 2;
    ny = (ny + 1) / 2;
    pyr_n_.push_back({nx, ny});
  }
}

Real SolidHeightmap::cell_z(int i, int j, bool highest) const {
  const std::size_t k = static_cast<std::size_t>(j) * g_.nx + i;
  const auto corners = {g_.z[k], g_.z[k + 1], g_.z[k + g_.nx], g_.z[k + g_.nx + 1]};
  return highest ? std::max(corners) : std::min(corners);
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
  const Vec3 foot{qx, qy, height(qx, qy)};
  const Real d_foot = norm(Vec3{qx - cx, qy - cy, foot.z - z});
  const Real d_up = std::min(delta, d_foot);
  // the largest slope within reach of the nearest point bounds how close the surface can come
  const Real L = max_slope(cx - d_up, cy - d_up, cx + d_up, cy + d_up);
  return {delta / std::sqrt(1 + L * L), n, d_foot < delta ? foot : Vec3{cx, cy, s.f}};
}

namespace {

// A part of the surface in the branch and bound of SolidHeightmap::exact(): a block of cells
// (k >= 1: block (i, j) of level k) or a part [s0, s1] x [t0, t1] of cell (i, j) (k = 0), with
// a lower bound of its distance.
struct Node {
  Real lb;
  int k, i, j;
  Real s0, s1, t0, t1;
};

bool farther(const Node& a, const Node& b) {
  return a.lb > b.lb;
}

Real box_distance(const Vec3& p, Real xa, Real xb, Real ya, Real yb, Real za, Real zb) {
  const Real ex = std::max({xa - p.x, Real{0}, p.x - xb});
  const Real ey = std::max({ya - p.y, Real{0}, p.y - yb});
  const Real ez = std::max({za - p.z, Real{0}, p.z - zb});
  return std::sqrt(ex * ex + ey * ey + ez * ez);
}

// The point of triangle abc nearest p (Ericson, Real-Time Collision Detection, 5.1.5).
Vec3 nearest_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const Real d1 = dot(ab, ap), d2 = dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Vec3 bp = p - b;
  const Real d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const Real vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + ab * (d1 / (d1 - d3));
  const Vec3 cp = p - c;
  const Real d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const Real vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + ac * (d2 / (d2 - d6));
  const Real va = d3 * d6 - d5 * d4;
  if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0)
    return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
  const Real den = va + vb + vc;
  if (!(den > 0)) return a;  // (degenerate: a is as good a guess as any; only a bound is used)
  return a + ab * (vb / den) + ac * (vc / den);
}

// The point of the tetrahedron abce nearest p, and whether p is inside it (then p itself).
Vec3 nearest_on_tetrahedron(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c,
                            const Vec3& e) {
  const Vec3 faces[4][4] = {{a, b, c, e}, {a, b, e, c}, {a, c, e, b}, {b, c, e, a}};
  bool inside = true;
  Vec3 best{};
  Real best_d2 = std::numeric_limits<Real>::infinity();
  for (const auto& f : faces) {
    const Vec3 n = cross(f[1] - f[0], f[2] - f[0]);
    const Real sp = dot(n, p - f[0]), so = dot(n, f[3] - f[0]);
    if (!(sp * so > 0)) inside = false;  // (a flat tetrahedron has no inside)
    const Vec3 y = nearest_on_triangle(p, f[0], f[1], f[2]);
    const Real d2 = norm2(y - p);
    if (d2 < best_d2) {
      best_d2 = d2;
      best = y;
    }
  }
  return inside ? p : best;
}

// parts examined at most by one query (then the least bound stands: still a lower bound)
constexpr int kMaxParts = 4096;

}  // namespace

Real SolidHeightmap::tolerance(Real d) const {
  return kExactTolerance * d + 1e-4 * std::min(dx_, dy_);
}

SolidHeightmap::Exact SolidHeightmap::exact(const Vec3& p, bool column, Real ub, Vec3 q) const {
  thread_local std::vector<Node> heap;
  heap.clear();
  const int ncx = g_.nx - 1, ncy = g_.ny - 1;
  const auto push = [&](const Node& n) {
    if (n.lb >= ub) return;  // nothing of it is nearer than q
    heap.push_back(n);
    std::push_heap(heap.begin(), heap.end(), farther);
  };
  const auto block = [&](int k, int i, int j) {
    const int ia = i << k, ib = std::min((i + 1) << k, ncx);
    const int ja = j << k, jb = std::min((j + 1) << k, ncy);
    const ZRange& r = z_pyramid_[k][static_cast<std::size_t>(j) * pyr_n_[k][0] + i];
    push({box_distance(p, x0_ + ia * dx_, x0_ + ib * dx_, y0_ + ja * dy_, y0_ + jb * dy_,
                       column ? bottom_ : Real{r.lo}, Real{r.hi}),
          k, i, j, 0, 1, 0, 1});
  };
  const auto part = [&](int i, int j, Real s0, Real s1, Real t0, Real t1) {
    const std::size_t k = static_cast<std::size_t>(j) * g_.nx + i;
    const Real z00 = g_.z[k], z10 = g_.z[k + 1], z01 = g_.z[k + g_.nx], z11 = g_.z[k + g_.nx + 1];
    const auto f = [&](Real s, Real t) {
      return (1 - t) * ((1 - s) * z00 + s * z10) + t * ((1 - s) * z01 + s * z11);
    };
    const Real a = f(s0, t0), b = f(s1, t0), c = f(s0, t1), e = f(s1, t1);
    const Real xa = x0_ + (i + s0) * dx_, xb = x0_ + (i + s1) * dx_;
    const Real ya = y0_ + (j + t0) * dy_, yb = y0_ + (j + t1) * dy_;
    // the part is bilinear with corners a, b, c, e: within their range, and within |twist| of the
    // plane through their mean with their mean slopes (f = plane + twist 4 sigma tau, with
    // sigma, tau in [-1/2, 1/2] across the part)
    Real lb = box_distance(p, xa, xb, ya, yb, column ? bottom_ : std::min({a, b, c, e}),
                           std::max({a, b, c, e}));
    const Real gx = (b - a + e - c) / (2 * (xb - xa)), gy = (c - a + e - b) / (2 * (yb - ya));
    const Real twist = std::abs(a - b - c + e) / 4;
    const Real gap =
        p.z - ((a + b + c + e) / 4 + gx * (p.x - (xa + xb) / 2) + gy * (p.y - (ya + yb) / 2));
    const Real len2 = 1 + gx * gx + gy * gy;
    // (a column lies below the upper face of the slab: only a gap above it counts)
    const Real slab = (column ? gap : std::abs(gap)) - twist;
    if (slab > 0) lb = std::max(lb, slab / std::sqrt(len2));
    if (lb >= ub) return;  // (nothing of it is nearer than q)
    // and within the tetrahedron of its corners (a bilinear patch is a blend of its corners), whose
    // edges along s and t are the part's own: exact where the nearest point is on one of them
    // (for a column, only from above all of them: its nearest point is then on the top)
    const Real hi = std::max({a, b, c, e});
    const Vec3 y = nearest_on_tetrahedron(p, {xa, ya, a}, {xb, ya, b}, {xa, yb, c}, {xb, yb, e});
    if (!column || p.z >= hi) lb = std::max(lb, norm(y - p));
    // points of the part: under the foot of p on the plane, and under y
    const auto try_point = [&](Real x_at, Real y_at) {
      const Real s = std::clamp((x_at - x0_) / dx_ - i, s0, s1);
      const Real t = std::clamp((y_at - y0_) / dy_ - j, t0, t1);
      const Real fz = f(s, t);
      const Vec3 on{x0_ + (i + s) * dx_, y0_ + (j + t) * dy_,
                    column ? std::clamp(p.z, bottom_, fz) : fz};
      const Real d = norm(on - p);
      if (d < ub) {
        ub = d;
        q = on;
      }
    };
    try_point(p.x + gap * gx / len2, p.y + gap * gy / len2);
    try_point(y.x, y.y);
    push({lb, 0, i, j, s0, s1, t0, t1});
  };

  // start from the blocks of the coarsest level at which the window within ub of p spans at most
  // 2 x 2 of them
  const auto cell = [](Real v, Real lo, Real hi, Real h, int n) {
    return std::min(static_cast<int>((std::clamp(v, lo, hi) - lo) / h), n - 1);
  };
  const int i0 = cell(p.x - ub, x0_, x1_, dx_, ncx), i1 = cell(p.x + ub, x0_, x1_, dx_, ncx);
  const int j0 = cell(p.y - ub, y0_, y1_, dy_, ncy), j1 = cell(p.y + ub, y0_, y1_, dy_, ncy);
  std::size_t k = 0;
  while (k + 1 < z_pyramid_.size() && ((i1 >> k) - (i0 >> k) > 1 || (j1 >> k) - (j0 >> k) > 1)) ++k;
  for (int j = j0 >> k; j <= (j1 >> k); ++j)
    for (int i = i0 >> k; i <= (i1 >> k); ++i) {
      if (k > 0) {
        block(static_cast<int>(k), i, j);
        continue;
      }
      // a few cells: only their parts within the window (smaller parts, tighter bounds)
      const auto clip = [](Real v, Real lo, Real h, int c) {
        return std::clamp((v - lo) / h - c, 0.0, 1.0);
      };
      const Real s0 = clip(p.x - ub, x0_, dx_, i), s1 = clip(p.x + ub, x0_, dx_, i);
      const Real t0 = clip(p.y - ub, y0_, dy_, j), t1 = clip(p.y + ub, y0_, dy_, j);
      if (s1 > s0 && t1 > t0) part(i, j, s0, s1, t0, t1);
    }

  for (int parts = 0; !heap.empty(); ++parts) {
    std::pop_heap(heap.begin(), heap.end(), farther);
    const Node n = heap.back();
    heap.pop_back();
    if (n.lb >= ub) break;  // (the least bound of all left): q is the nearest
    if (ub - n.lb <= tolerance(n.lb) || n.lb >= reach_) return {n.lb, q};
    if (parts >= kMaxParts) {
      capped_.fetch_add(1, std::memory_order_relaxed);
      return {n.lb, q};
    }
    if (n.k >= 2) {
      for (int b = 0; b < 2; ++b)
        for (int a = 0; a < 2; ++a)
          if (2 * n.i + a < pyr_n_[n.k - 1][0] && 2 * n.j + b < pyr_n_[n.k - 1][1])
            block(n.k - 1, 2 * n.i + a, 2 * n.j + b);
    } else if (n.k == 1) {
      for (int b = 0; b < 2; ++b)
        for (int a = 0; a < 2; ++a)
          if (2 * n.i + a < ncx && 2 * n.j + b < ncy) part(2 * n.i + a, 2 * n.j + b, 0, 1, 0, 1);
    } else {
      const Real sm = (n.s0 + n.s1) / 2, tm = (n.t0 + n.t1) / 2;
      part(n.i, n.j, n.s0, sm, n.t0, tm);
      part(n.i, n.j, sm, n.s1, n.t0, tm);
      part(n.i, n.j, n.s0, sm, tm, n.t1);
      part(n.i, n.j, sm, n.s1, tm, n.t1);
    }
  }
  return {ub, q};
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
    Vec3 nv{}, q{};
    if (p.z > s.f) {
      const Bound b = top_bound(cx, cy, p.z, s);
      v = b.v;
      nv = b.n;
      q = b.q;
    } else if (p.z < bottom_) {
      v = bottom_ - p.z;
      nv = {0, 0, -1};
    }
    const Real d = std::sqrt(h_out * h_out + v * v);
    if (p.z > s.f && d < reach_) {
      // within reach, above the top: the bound may fall short of the distance to q, a point of
      // the surface, by more than the tolerance
      const Real ub = norm(q - p);
      if (ub - d > tolerance(d)) {
        // (within the rectangle, the nearest point of the solid is on the top: its columns
        // matter only beside it)
        const Exact e = exact(p, h_out > 0, ub, q);
        const Real dq = norm(p - e.q);
        if (dq > 0) return {std::max(d, e.lb), (p - e.q) / dq};
      }
    }
    Vec3 n = Vec3{ox, oy, 0} + nv * v;
    const Real nn = norm(n);
    n = nn > 0 ? n / nn : (v > 0 ? nv : Vec3{ox, oy, 0} / h_out);
    return {d, n};
  }
  // inside: the nearest of the top, the bottom and the four sides
  SurfacePoint best{std::numeric_limits<Real>::infinity(), {}};
  const auto consider = [&best](Real d, const Vec3& n) {
    if (d < best.distance) best = {d, n};
  };
  consider(p.z - bottom_, {0, 0, -1});
  consider(p.x - x0_, {-1, 0, 0});
  consider(x1_ - p.x, {1, 0, 0});
  consider(p.y - y0_, {0, -1, 0});
  consider(y1_ - p.y, {0, 1, 0});
  const Bound top = top_bound(cx, cy, p.z, s);
  if (top.v <= best.distance) {  // (a lower bound: a side or the bottom nearer is exact)
    SurfacePoint t{top.v, top.n};
    const Real ub = norm(top.q - p);
    if (top.v < reach_ && ub - top.v > tolerance(top.v)) {
      const Exact e = exact(p, false, ub, top.q);
      const Real dq = norm(e.q - p);
      if (dq > 0) t = {std::max(top.v, e.lb), (e.q - p) / dq};
    }
    if (t.distance <= best.distance) best = t;
  }
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
