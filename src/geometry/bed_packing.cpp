#include "geometry/bed_packing.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <exception>
#include <limits>
#include <stdexcept>
#include <string>

#include <omp.h>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "core/rng.hpp"

namespace sandflow {

namespace {

constexpr Real kInf = std::numeric_limits<Real>::infinity();
constexpr Real kTwoPi = 2 * kPi;
/// The most samples of the floor and of the top: 2^22 each (32 MiB); a larger footprint is
/// sampled more coarsely.
constexpr Real kMaxMapSamples = 4194304.0;
/// A grain that has not come to rest after this many arcs is discarded (rounding can make a
/// grain take and leave the same contact over and over; real sequences take a handful).
constexpr int kMaxArcs = 64;
/// The packing fraction estimate_bed_grains assumes.
constexpr Real kEstimatePacking = 0.60;
/// Tiles are kTile columns wide; a drop reads columns at most kMargin beyond its tile's (2 kMargin
/// < kTile + 1, see run).
constexpr int kTile = 16;
constexpr int kMargin = 7;
/// The slab's periodic tile is kSlabTile columns wide, with kSlabGhost columns of images around
/// it; the slab is laid where the footprint is at least two tiles wide and the bed kSlabLeast
/// cells deep under a cut kSlabBelowTop cells below the lowest top.
constexpr int kSlabTile = 32;
constexpr int kSlabGhost = 8;
constexpr Real kSlabLeast = 4;
constexpr Real kSlabBelowTop = 2;

/// A seed for stream k of a round (splitmix64 of the three).
std::uint64_t mix_seed(std::uint64_t seed, std::uint64_t round, std::uint64_t k) {
  std::uint64_t z = seed ^ (round + 1) * 0x9e3779b97f4a7c15ULL ^ k * 0xd1b54a32d192ed03ULL;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

// ---- The floor and the top, sampled ---------------------------------------------------------

struct Map {
  Real x0 = 0, y0 = 0, hx = 1, hy = 1;
  int mx = 2, my = 2;
  std::vector<Real> v;
  Real lo = 0, hi = 0;  ///< smallest and largest sample

  Real at(int i, int j) const { return v[static_cast<std::size_t>(j) * mx + i]; }

  /// Bilinear value and gradient at (x, y), clamped to the map.
  Real eval(Real x, Real y, Real& fx, Real& fy) const {
    const Real u = std::clamp((x - x0) / hx, 0.0, static_cast<Real>(mx - 1));
    const Real w = std::clamp((y - y0) / hy, 0.0, static_cast<Real>(my - 1));
    const int i = std::min(static_cast<int>(u), mx - 2);
    const int j = std::min(static_cast<int>(w), my - 2);
    const Real a = u - i, b = w - j;
    const Real f00 = at(i, j), f10 = at(i + 1, j), f01 = at(i, j + 1), f11 = at(i + 1, j + 1);
    fx = ((1 - b) * (f10 - f00) + b * (f11 - f01)) / hx;
    fy = ((1 - a) * (f01 - f00) + a * (f11 - f10)) / hy;
    return (1 - b) * ((1 - a) * f00 + a * f10) + b * ((1 - a) * f01 + a * f11);
  }
  Real value(Real x, Real y) const {
    Real fx, fy;
    return eval(x, y, fx, fy);
  }
};

/// f sampled every `spacing` (or more coarsely: at most kMaxMapSamples).
Map sample_map(const BedRegion& R, const std::function<Real(Real, Real)>& f, const char* what,
               Real spacing) {
  Map m;
  const Real w = R.x1 - R.x0, h = R.y1 - R.y0;
  const Real n = (w / spacing + 2) * (h / spacing + 2);
  if (n > kMaxMapSamples) spacing *= std::sqrt(n / kMaxMapSamples);
  m.mx = std::max(2, static_cast<int>(std::ceil(w / spacing)) + 1);
  m.my = std::max(2, static_cast<int>(std::ceil(h / spacing)) + 1);
  m.x0 = R.x0;
  m.y0 = R.y0;
  m.hx = w / (m.mx - 1);
  m.hy = h / (m.my - 1);
  m.v.resize(static_cast<std::size_t>(m.mx) * m.my);
  m.lo = kInf;
  m.hi = -kInf;
  for (int j = 0; j < m.my; ++j)
    for (int i = 0; i < m.mx; ++i) {
      const Real z = f(m.x0 + i * m.hx, m.y0 + j * m.hy);
      if (!std::isfinite(z))
        throw std::invalid_argument(std::string("bed packing: the ") + what +
                                    " is not finite at a point of the footprint");
      m.v[static_cast<std::size_t>(j) * m.mx + i] = z;
      m.lo = std::min(m.lo, z);
      m.hi = std::max(m.hi, z);
    }
  return m;
}

void check_region(const BedRegion& R) {
  if (!(R.x1 > R.x0 && R.y1 > R.y0) || !std::isfinite(R.x1 - R.x0) || !std::isfinite(R.y1 - R.y0))
    throw std::invalid_argument("bed packing: the footprint is empty or not finite");
  if (!(R.r_lo > 0 && R.r_hi >= R.r_lo) || !std::isfinite(R.r_hi))
    throw std::invalid_argument("bed packing: radii need 0 < r_lo <= r_hi");
  if (!R.floor || !R.top) throw std::invalid_argument("bed packing: needs a floor and a top");
  if (R.patience < 1) throw std::invalid_argument("bed packing: patience must be at least 1");
}

Real mean_grain_volume(const BedRegion& R) {
  // <r^3> for r uniform in [r_lo, r_hi]
  const Real a = R.r_lo, b = R.r_hi;
  const Real r3 = b > a ? (b * b * b * b - a * a * a * a) / (4 * (b - a)) : a * a * a;
  return 4.0 / 3.0 * kPi * r3;
}

Real estimate_from_maps(const BedRegion& R, const Map& floor, const Map& top) {
  Real volume = 0;
  for (int j = 0; j + 1 < floor.my; ++j)
    for (int i = 0; i + 1 < floor.mx; ++i) {
      Real dz = 0;
      for (int q = 0; q < 4; ++q)
        dz += std::max(0.0, top.at(i + q % 2, j + q / 2) - floor.at(i + q % 2, j + q / 2));
      volume += dz / 4;
    }
  return volume * floor.hx * floor.hy * kEstimatePacking / mean_grain_volume(R);
}

// ---- Arcs and the events along them -----------------------------------------------------------

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// Four floats at once (GCC and Clang vectors: SSE2 on x86-64, NEON on ARM).
using F4 = float __attribute__((vector_size(16)));
using I4 = std::int32_t __attribute__((vector_size(16)));
inline F4 splat(float v) {
  return F4{v, v, v, v};
}
inline F4 load4(const float* p) {
  F4 v;
  std::memcpy(&v, p, sizeof v);
  return v;
}
/// Bit k set for each lane k < 3 of `in` that is true.
inline unsigned mask3(I4 in) {
#if defined(__SSE2__)
  return static_cast<unsigned>(_mm_movemask_ps(reinterpret_cast<__m128>(in))) & 7u;
#else
  return (in[0] & 1u) | (in[1] & 2u) | (in[2] & 4u);
#endif
}

/// An angle t of [0, 2 pi) along an arc as its cosine and sine, with a key that orders angles
/// without trigonometry: the "diamond angle", 0 to 4, and about t near 0 (1 - cos t would lose
/// small angles). A key of 5: none.
struct Angle {
  Real c = 1, s = 0, key = 5;
  static Angle of(Real c, Real s) {
    Real k;
    if (s >= 0)
      k = c >= 0 ? s / (c + s) : 1 - c / (s - c);
    else
      k = c < 0 ? 2 - s / (-c - s) : 3 + c / (c - s);
    return {c, s, k};
  }
  static Angle zero() { return {1, 0, 0}; }
  static Angle none() { return {1, 0, 5}; }
  bool is_none() const { return key > 4.5; }
  Real radians() const {
    const Real t = std::atan2(s, c);
    return t < 0 ? t + kTwoPi : t;
  }
};

/// The first angle up to the key `key_max` where g(t) = k + a cos t + b sin t falls through 0, or
/// none. A contact touching now (g(0) <= 0, to rounding) and closing (g'(0) = b < 0) is met at
/// once; one touching and opening is met again only after it has opened, and so is one the grain
/// is `leaving` (it has just left it: see first_contact).
inline Angle first_entry(Real k, Real a, Real b, Real key_max, bool leaving = false) {
  const Real g0 = k + a;
  const Real r2 = a * a + b * b;
  // (closing slower than choose_supports' tolerance is leaving, as choose_supports decided)
  if (g0 <= 0 && b < -1e-9 * std::sqrt(r2) && !leaving) return Angle::zero();
  if (k * k >= r2) return Angle::none();  // g keeps its sign
  // g = k + R cos(t - phi) falls through 0 at t = phi + theta, cos theta = -k / R: the sum of the
  // two angles by their cosines and sines, (a, b) / R and (-k, q) / R (no atan2 nor acos)
  const Real q = std::sqrt(r2 - k * k);
  const Angle t = Angle::of((-a * k - b * q) / r2, (a * q - b * k) / r2);
  if (g0 > 0) {
    // the root lies ahead: a hair behind 0 is rounding
    if (t.key > 4 - 1e-6) return Angle::zero();
  } else if (t.key < 1e-6) {
    return Angle::none();  // touching and opening: the root just passed (or rounding put it ahead)
  }
  return t.key <= key_max ? t : Angle::none();
}

/// A circle c + rho (cos t e1 + sin t e2), followed from t = 0 (the grain's centre now) down.
struct Arc {
  Vec3 c, e1, e2;
  Real rho = 0;
  Angle t_max;
  Vec3 at(const Angle& t) const { return c + (e1 * t.c + e2 * t.s) * rho; }
  Vec3 at(Real t) const { return c + (e1 * std::cos(t) + e2 * std::sin(t)) * rho; }
};

struct Cell {
  Real x, y, z, r;
};

/// A contact: a grain (id >= 0) or a wall of the footprint (kWall0 - k, k = 0..3).
constexpr int kWall0 = -1;
constexpr int kFloor = -100;
inline bool is_wall(int id) {
  return id < 0;
}
inline int wall_index(int id) {
  return kWall0 - id;
}

/// Which of m <= 3 touching contacts (unit normals n, pointing to the grain) hold the grain, as
/// quasi-static rolling has it: the subset S whose contacts push (multipliers N > 0) while the
/// motion they leave, gravity projected on the directions they allow, moves away from the others
/// (v . n_j >= 0). Returns the subset as a bit mask; all m bits with m = 3: at rest. -1: none
/// fits (rounding at a degenerate configuration). A tiny non-negative least-squares problem,
/// solved by trying the subsets, largest first.
int choose_supports(const Vec3* n, int m) {
  constexpr Real kPush = 1e-12, kAway = -1e-9;
  const Vec3 ez{0, 0, 1};
  auto away = [&](const Vec3& v, int mask) {
    for (int j = 0; j < m; ++j)
      if (!(mask >> j & 1) && dot(v, n[j]) < kAway) return false;
    return true;
  };
  if (m == 3) {
    const Real det = dot(n[0], cross(n[1], n[2]));
    if (std::abs(det) > 1e-12) {
      const Real N0 = cross(n[1], n[2]).z / det, N1 = cross(n[2], n[0]).z / det,
                 N2 = cross(n[0], n[1]).z / det;
      if (N0 >= 0 && N1 >= 0 && N2 >= 0) return 7;
    }
  }
  // pairs: N from the 2 x 2 Gram system, v = -ez + N_a n_a + N_b n_b along their groove
  for (int a = 0; a < m; ++a)
    for (int b = a + 1; b < m; ++b) {
      const Real k = dot(n[a], n[b]);
      if (1 - k * k < 1e-12) continue;
      const Real Na = (n[a].z - k * n[b].z) / (1 - k * k), Nb = (n[b].z - k * n[a].z) / (1 - k * k);
      if (Na <= kPush || Nb <= kPush) continue;
      if (away(n[a] * Na + n[b] * Nb - ez, 1 << a | 1 << b)) return 1 << a | 1 << b;
    }
  for (int a = 0; a < m; ++a)
    if (n[a].z > kPush && away(n[a] * n[a].z - ez, 1 << a)) return 1 << a;
  if (away(-ez, 0)) return 0;
  return -1;
}

/// The state of one drop: the walls' planes for its grain (n . p >= w), and the columns it may
/// read, those of its tile widened by kMargin (`out` once it would read beyond them).
struct Walk {
  std::array<Real, 4> wall_w{};
  int ix0 = 0, ix1 = 0, iy0 = 0, iy1 = 0;
  bool out = false;
  bool reads(int jx0, int jx1, int jy0, int jy1) {
    out = out || jx0 < ix0 || jx1 > ix1 || jy0 < iy0 || jy1 > iy1;
    return !out;
  }
};

enum class Drop { Rest, Discard, Leave };

/// A tile's drops of one phase: its columns, the first of the grain ids reserved for its drops,
/// how many, and its random stream.
struct Tile {
  int ix0, ix1, iy0, iy1;  // (inclusive)
  std::int32_t base = 0;
  std::int32_t drops = 0;
  std::uint64_t seed = 0;
  // the outcome
  std::int64_t made = 0, discarded = 0, blocked = 0, kept = 0, closed = 0;
};

class Packer {
 public:
  explicit Packer(const BedRegion& R) : R_(R) {}
  BedPacking run();
  // the periodic tile of the slab, its grains in the order they were laid (see lay_slab)
  struct TileGrain {
    Vec3 p;
    Real r;
    std::int32_t support[3];   ///< grains of the tile holding it, -1 past the last
    std::int8_t sx[3], sy[3];  ///< ... in the copy of the tile this far away in x and y
  };
  std::vector<TileGrain> pack_periodic(int n_tile, int ghost);

 private:
  // checks the region, samples its floor and top, makes the grid; the columns open for drops
  std::int64_t prepare();
  // the slab under the top laid from a periodic tile, where one fits (see the top of the file):
  // its grains inserted as the first ids; how many (and out's settled and copied)
  std::int64_t lay_slab(BedPacking& out);
  // the drops of one tile (see run)
  void run_tile(Tile& tile, std::vector<std::int32_t>& open);
  // where a grain of radius r dropped at (x, y) comes to rest (Rest), or Discard (it did not
  // settle), or Leave (it would read columns beyond w's); `support` (when given) the grains
  // holding it at rest, -1 past the last. From `z_start` (kInf: from above everything) the
  // grain falls from (x, y, z_start), which must overlap nothing.
  Drop drop(Real x, Real y, Real r, Walk& w, Vec3& rest, int* support = nullptr,
            Real z_start = kInf) const;
  // no grain overlaps a grain of radius r at p by more than 1e-6 of a cell
  bool clear(const Vec3& p, Real r) const;
  // the highest contact below z_max on the vertical line at (x, y): a grain, or kFloor
  int fall(Real x, Real y, Real r, Real z_max, int exclude, Walk& w, Real& z, Cell& met) const;
  Real floor_rest(Real x, Real y, Real r) const;
  // the first contact met along the arc (not one of `held`), and where (t); kInf when none.
  // `left`: the contact just left, not met again before it has opened
  void first_contact(const Arc& arc, Real r, const int* held, int n_held, int left, Walk& w,
                     Angle& t, int& id, Cell& met) const;
  // the unit normal at p of contact id (a grain at o, or a wall)
  Vec3 normal(int id, const Cell& o, const Vec3& p, Real r) const;
  // gap along the arc of wall j: k + a cos t + b sin t
  void wall_gap(int j, const Arc& arc, const Walk& w, Real& k, Real& a, Real& b) const;
  void insert(std::int32_t id, const Vec3& p, Real r);

  // (clamped before the cast, which then truncates as floor would: std::floor is a libm call
  // without SSE4.1, and these run in the innermost loops)
  static int index(Real u, int n) {
    return u <= 0 ? 0 : (u >= n - 1 ? n - 1 : static_cast<int>(u));
  }
  int column_x(Real x) const { return index((x - R_.x0) * inv_cs_, nx_); }
  int column_y(Real y) const { return index((y - R_.y0) * inv_cs_, ny_); }
  int layer(Real z) const { return index((z - z0_) * inv_cs_, nz_); }
  std::size_t cell(int ix, int iy, int iz) const {
    return (static_cast<std::size_t>(iy) * nx_ + ix) * nz_ + iz;
  }

  const BedRegion& R_;
  Map floor_, top_;
  bool flat_floor_ = false;
  Real cs_ = 0, inv_cs_ = 0, z0_ = 0;
  float fcs_ = 0;
  int nx_ = 1, ny_ = 1, nz_ = 1;
  // Each cell holds its first three grains inline, in one cache line (coordinates as floats
  // relative to the cell's low corner: within 6e-8 of its width, far below the 1e-6 d the
  // contacts are exact to), and chains the rest through next_ (rare: a cell holds 1.15 grains
  // on average at this packing). A scan reads a cell's line, not a list spread over memory.
  // An empty slot's coordinates are NaN, which no box holds.
  struct alignas(64) Slots {
    float x[3] = {kNaN, kNaN, kNaN}, y[3] = {kNaN, kNaN, kNaN}, z[3] = {kNaN, kNaN, kNaN}, r[3];
    std::int32_t id[3] = {-1, -1, -1};
    std::int32_t more = -1;
  };
  static_assert(sizeof(Slots) == 64);
  std::vector<Slots> cells_;
  std::vector<std::int32_t> next_;
  /// The bounds [lo, hi] of a box about the cell whose low corner is at c, in floats relative
  /// to it (widened by far more than their rounding).
  F4 rel_lo(Real lo, Real c) const { return splat(static_cast<float>(lo - c) - 1e-5f * fcs_); }
  F4 rel_hi(Real hi, Real c) const { return splat(static_cast<float>(hi - c) + 1e-5f * fcs_); }
  /// The slots of a cell centred in the box of the relative bounds given, as bits 0 to 2 (and
  /// perhaps a few more: the callers test each grain exactly). The three are tested at once (4
  /// floats from x, y and z: the fourth lane is the next array's first).
  static unsigned in_xy(const Slots& s, F4 xl, F4 xh, F4 yl, F4 yh) {
    const F4 x = load4(s.x), y = load4(s.y);
    return mask3((x >= xl) & (x <= xh) & (y >= yl) & (y <= yh));
  }
  static unsigned in_xyz(const Slots& s, F4 xl, F4 xh, F4 yl, F4 yh, F4 zl, F4 zh) {
    const F4 x = load4(s.x), y = load4(s.y), z = load4(s.z);
    return mask3((x >= xl) & (x <= xh) & (y >= yl) & (y <= yh) & (z >= zl) & (z <= zh));
  }
  std::vector<std::int32_t> col_top_;  ///< per column: highest layer holding a grain, or -1
  std::vector<Real> col_floor_;        ///< per column: the highest floor within r_hi of it
  std::vector<Cell> g_;                ///< by id; r = 0: a drop that left no grain
  std::vector<std::uint8_t> open_;     ///< per column: drops are made in it
  std::vector<std::uint16_t> fails_;   ///< per column: discarded drops in a row, in eighths
  // the walls' inward normals
  std::array<Vec3, 4> wall_n_{Vec3{1, 0, 0}, Vec3{-1, 0, 0}, Vec3{0, 1, 0}, Vec3{0, -1, 0}};
};

Real Packer::floor_rest(Real x, Real y, Real r) const {
  if (flat_floor_) return floor_.hi + r;
  // a tangent plane at the centre: exact on a plane, conservative on a bump, within r^2 / R_c in
  // a hollow of curvature radius R_c
  Real fx, fy;
  const Real f = floor_.eval(x, y, fx, fy);
  const Real g2 = fx * fx + fy * fy;
  if (g2 <= 1) return f + r * std::sqrt(1 + g2);
  // steeper than 45 degrees (a step, the flank of an obstacle), where a tangent plane would lift
  // the grain into the air: the floor at points r / 4 apart under the grain ("nails"), between
  // which it sinks at most (r / 4)^2 / (2 r) = r / 32 into a plane
  Real best = f + r;
  const Real h = r / 4;
  for (int j = -4; j <= 4; ++j)
    for (int i = -4; i <= 4; ++i) {
      const Real rho2 = (i * i + j * j) * h * h;
      if (rho2 >= r * r) continue;
      best = std::max(best, floor_.value(x + i * h, y + j * h) + std::sqrt(r * r - rho2));
    }
  return best;
}

int Packer::fall(Real x, Real y, Real r, Real z_max, int exclude, Walk& w, Real& z,
                 Cell& met) const {
  Real best = floor_rest(x, y, r);
  int hit = kFloor;
  const int cx = column_x(x), cy = column_y(y);
  const int jx0 = std::max(cx - 1, 0), jx1 = std::min(cx + 1, nx_ - 1);
  const int jy0 = std::max(cy - 1, 0), jy1 = std::min(cy + 1, ny_ - 1);
  if (!w.reads(jx0, jx1, jy0, jy1)) return kFloor;
  int top = -1;
  for (int jy = jy0; jy <= jy1; ++jy)
    for (int jx = jx0; jx <= jx1; ++jx)
      top = std::max(top, col_top_[static_cast<std::size_t>(jy) * nx_ + jx]);
  if (z_max < kInf) top = std::min(top, layer(z_max + r + R_.r_hi));
  // the 3 x 3 columns, and the square of a contact's reach about (x, y) relative to each, once
  // (their corners not in Vec3s, whose members are set to 0 first)
  const Real reach = r + R_.r_hi;
  int n_cols = 0;
  const Slots* col[9];
  Real cx_of[9], cy_of[9];
  F4 xl[9], xh[9], yl[9], yh[9];
  for (int jy = jy0; jy <= jy1; ++jy)
    for (int jx = jx0; jx <= jx1; ++jx, ++n_cols) {
      col[n_cols] = &cells_[cell(jx, jy, 0)];
      cx_of[n_cols] = R_.x0 + jx * cs_;
      cy_of[n_cols] = R_.y0 + jy * cs_;
      xl[n_cols] = rel_lo(x - reach, cx_of[n_cols]);
      xh[n_cols] = rel_hi(x + reach, cx_of[n_cols]);
      yl[n_cols] = rel_lo(y - reach, cy_of[n_cols]);
      yh[n_cols] = rel_hi(y + reach, cy_of[n_cols]);
    }
  auto meet = [&](std::int32_t k, Real ox, Real oy, Real oz, Real orad) {
    const Real dx = ox - x, dy = oy - y, s = r + orad;
    const Real rho2 = dx * dx + dy * dy;
    if (rho2 >= s * s || k == exclude) return;
    const Real zc = oz + std::sqrt(s * s - rho2);
    if (zc > best && zc < z_max - 1e-10 * cs_) {
      best = zc;
      hit = k;
      met = {ox, oy, oz, orad};
    }
  };
  // layer by layer from the highest of the columns down: every grain of layer iz and below lies
  // under z0 + (iz + 1) cs, so none of them can be met higher than that plus two radii. A
  // layer's slots in the square gathered as bits of one word first (as in first_contact).
  for (int iz = top; iz >= 0 && z0_ + (iz + 1) * cs_ + reach > best; --iz) {
    const Real cz = z0_ + iz * cs_;
    std::uint32_t bits = 0;
    for (int c = 0; c < n_cols; ++c) {
      const Slots& sl = col[c][iz];
      bits |= in_xy(sl, xl[c], xh[c], yl[c], yh[c]) << (3 * c);
      for (std::int32_t q = sl.more; q >= 0; q = next_[q])
        meet(q, g_[q].x, g_[q].y, g_[q].z, g_[q].r);
    }
    for (; bits; bits &= bits - 1) {
      const int b = __builtin_ctz(bits), c = b / 3, k = b - 3 * c;
      const Slots& sl = col[c][iz];
      meet(sl.id[k], cx_of[c] + sl.x[k], cy_of[c] + sl.y[k], cz + sl.z[k], sl.r[k]);
    }
  }
  z = std::min(best, z_max);
  return hit;
}

Vec3 Packer::normal(int id, const Cell& o, const Vec3& p, Real r) const {
  if (is_wall(id)) return wall_n_[wall_index(id)];
  return (p - Vec3{o.x, o.y, o.z}) / (r + o.r);
}

void Packer::wall_gap(int j, const Arc& arc, const Walk& w, Real& k, Real& a, Real& b) const {
  const Vec3& n = wall_n_[j];
  k = dot(n, arc.c) - w.wall_w[j];
  a = arc.rho * dot(n, arc.e1);
  b = arc.rho * dot(n, arc.e2);
}

void Packer::first_contact(const Arc& arc, Real r, const int* held, int n_held, int left, Walk& w,
                           Angle& t, int& id, Cell& met) const {
  t = Angle::none();
  id = kFloor;
  auto is_held = [&](int q) {
    for (int h = 0; h < n_held; ++h)
      if (held[h] == q) return true;
    return false;
  };
  constexpr int kNoId = -1000;  // (no grain, no wall)
  // Whether g(t) = k + a cos t + b sin t, positive at 0, falls through 0 by t = T (T <= pi,
  // cos T and sin T given), without trigonometry: at T, or at its minimum (t = phi + pi, where
  // (cos t, sin t) = -(a, b) / R) if that lies in [0, T] and is below 0.
  const Real cT = arc.t_max.c, sT = arc.t_max.s, T = arc.t_max.key;
  const bool narrow = T <= 2;  // (pi)
  auto within = [&](Real k, Real a, Real b) {
    if (!narrow || (k + a <= 0 && b < 0)) return true;  // (first_entry decides)
    if (k + a * cT + b * sT <= 0) return true;
    // the direction (-a, -b) in the sector [0, T]: at or above the t = 0 axis, and not past T
    return -b >= 0 && (-a) * sT - (-b) * cT >= 0 && k * k < a * a + b * b;
  };
  // the grains near the arc: the cells of its bounding box widened by a contact's reach; the
  // box holds the two ends and, on each axis, the circle's extreme point if the arc passes it
  const Vec3 p0 = arc.at(Angle::zero()), p1 = arc.at(arc.t_max);
  Vec3 lo = min(p0, p1), hi = max(p0, p1);
  for (int ax = 0; ax < 3; ++ax) {
    const Real u = arc.e1[ax], v = arc.e2[ax];  // coordinate: c + rho (u cos t + v sin t)
    const Real m = std::sqrt(u * u + v * v);
    // the maximum is at direction (u, v), the minimum at (-u, -v)
    for (Real sgn : {1.0, -1.0}) {
      const Real du = sgn * u, dv = sgn * v;
      const bool in = !narrow || (dv >= 0 && du * sT - dv * cT >= 0);
      if (!in) continue;
      const Real e = arc.c[ax] + sgn * m * arc.rho;
      if (sgn > 0)
        hi[ax] = std::max(hi[ax], e);
      else
        lo[ax] = std::min(lo[ax], e);
    }
  }
  // the walls the box comes near (n . p - w over the box: its least, for each wall's normal)
  const Real nearest[4] = {lo.x, -hi.x, lo.y, -hi.y};
  for (int j = 0; j < 4; ++j) {
    const int q = kWall0 - j;
    if (nearest[j] > w.wall_w[j] + 1e-6 * cs_ || is_held(q)) continue;
    Real k, a, b;
    wall_gap(j, arc, w, k, a, b);
    if (!within(k, a, b)) continue;
    const Angle tw = first_entry(k, a, b, T, q == left);
    if (tw.key < t.key) t = tw, id = q;
  }
  const Real reach = r + R_.r_hi;
  const Vec3 wide{reach, reach, reach};
  lo = lo - wide;
  hi = hi + wide;
  const int ix0 = column_x(lo.x), ix1 = column_x(hi.x);
  const int iy0 = column_y(lo.y), iy1 = column_y(hi.y);
  const int iz0 = layer(lo.z), iz1 = layer(hi.z);
  if (!w.reads(ix0, ix1, iy0, iy1)) return;
  // A grain of the box: within reach of the circle, within the arc (as `within`) and not held,
  // tested without a branch (each a coin toss), then its root. (A grain of the box beyond its
  // own reach of the arc fails these.)
  const int h0 = held[0], h1 = n_held > 1 ? held[1] : kNoId, h2 = n_held > 2 ? held[2] : kNoId;
  const Real rho2 = arc.rho * arc.rho;
  auto test = [&](std::int32_t q, Real ox, Real oy, Real oz, Real orad) {
    const Real s = r + orad;
    const Real dx = arc.c.x - ox, dy = arc.c.y - oy, dz = arc.c.z - oz;
    const Real k = dx * dx + dy * dy + dz * dz + rho2 - s * s;
    const Real a = 2 * arc.rho * (dx * arc.e1.x + dy * arc.e1.y + dz * arc.e1.z);
    const Real b = 2 * arc.rho * (dx * arc.e2.x + dy * arc.e2.y + dz * arc.e2.z);
    const Real R2 = a * a + b * b;
    const bool reaches = (k <= 0) | (k * k < R2);
    const bool in = (!narrow) | ((k + a <= 0) & (b < 0)) | (k + a * cT + b * sT <= 0) |
                    ((b <= 0) & (b * cT - a * sT >= 0) & (k * k < R2));
    const bool free = (q != h0) & (q != h1) & (q != h2);
    if (reaches & in & free) {
      const Angle tq = first_entry(k, a, b, std::min(t.key, T), q == left);
      if (tq.key < t.key) t = tq, id = q, met = {ox, oy, oz, orad};
    }
  };
  // The cells: each one's slots in the box, 3 bits a cell of one word, tested once 21 cells
  // are in (a loop over a cell's own few would guess its end wrong about once a cell). The
  // layers' bounds once (an arc's box, at most 4 cells high, spans at most 5 layers).
  constexpr int kLayers = 8;
  F4 zl[kLayers], zh[kLayers];
  for (int i = 0; i < std::min(iz1 - iz0 + 1, kLayers); ++i) {
    zl[i] = rel_lo(lo.z, z0_ + (iz0 + i) * cs_);
    zh[i] = rel_hi(hi.z, z0_ + (iz0 + i) * cs_);
  }
  const Slots* cells[21];
  Real cx_of[21], cy_of[21];  // (not Vec3: its members are set to 0 first)
  int iz_of[21];
  std::uint64_t bits = 0;
  int n = 0;
  auto flush = [&] {
    for (; bits; bits &= bits - 1) {
      const int b = __builtin_ctzll(bits), c = b / 3, k = b - 3 * c;
      const Slots& sl = *cells[c];
      test(sl.id[k], cx_of[c] + sl.x[k], cy_of[c] + sl.y[k], z0_ + iz_of[c] * cs_ + sl.z[k],
           sl.r[k]);
    }
    n = 0;
  };
  for (int iy = iy0; iy <= iy1; ++iy) {
    const Real cy = R_.y0 + iy * cs_;
    const F4 yl = rel_lo(lo.y, cy), yh = rel_hi(hi.y, cy);
    for (int ix = ix0; ix <= ix1; ++ix) {
      const int top = std::min(iz1, col_top_[static_cast<std::size_t>(iy) * nx_ + ix]);
      const Real cx = R_.x0 + ix * cs_;
      const F4 xl = rel_lo(lo.x, cx), xh = rel_hi(hi.x, cx);
      const Slots* col = &cells_[cell(ix, iy, 0)];
      for (int iz = iz0; iz <= top; ++iz) {
        const Slots& sl = col[iz];
        const int i = iz - iz0;
        const F4 l = i < kLayers ? zl[i] : rel_lo(lo.z, z0_ + iz * cs_);
        const F4 h = i < kLayers ? zh[i] : rel_hi(hi.z, z0_ + iz * cs_);
        cells[n] = &sl;
        cx_of[n] = cx, cy_of[n] = cy, iz_of[n] = iz;
        bits |= static_cast<std::uint64_t>(in_xyz(sl, xl, xh, yl, yh, l, h)) << (3 * n);
        for (std::int32_t q = sl.more; q >= 0; q = next_[q])
          test(q, g_[q].x, g_[q].y, g_[q].z, g_[q].r);
        if (++n == 21) flush();
      }
    }
  }
  flush();
}

Drop Packer::drop(Real x, Real y, Real r, Walk& w, Vec3& rest, int* support, Real z_start) const {
  w.wall_w = {R_.x0 + r, -(R_.x1 - r), R_.y0 + r, -(R_.y1 - r)};
  w.out = false;
  Vec3 p{x, y, z_start};
  // the contacts holding the grain, and (for grains) where they are, as the grid gave them
  int held[3];
  Cell at[3];
  int n_held = 0;
  int exclude = kFloor;
  const Vec3 ez{0, 0, 1};
  auto on_floor = [&](const Vec3& q) { return q.z <= floor_rest(q.x, q.y, r); };
  auto report_supports = [&] {
    if (!support) return;
    int k = 0;
    for (int h = 0; h < n_held; ++h)
      if (!is_wall(held[h])) support[k++] = held[h];
    if (k < 3) support[k] = -1;
  };

  for (int step = 0; step < kMaxArcs; ++step) {
    // no grain among the supports: fall straight down (a wall does not hold a grain up)
    bool any_grain = false;
    for (int h = 0; h < n_held; ++h) any_grain = any_grain || !is_wall(held[h]);
    if (!any_grain) {
      Real z;
      const int hit = fall(p.x, p.y, r, p.z, exclude, w, z, at[0]);
      if (w.out) return Drop::Leave;
      p.z = z;
      if (hit == kFloor) {
        rest = p;
        n_held = 0;
        report_supports();
        return Drop::Rest;
      }
      held[0] = hit;
      n_held = 1;  // (walls touched on the way are met again at once if the roll closes on them)
      exclude = kFloor;
      continue;
    }

    // the arc the grain follows on its supports: over one grain, or in the groove of two (a grain
    // and a grain, or a grain and a wall)
    Arc arc;
    int other = kFloor;
    if (n_held == 1) {
      const Cell& o = at[0];
      const Vec3 a{o.x, o.y, o.z};
      const Real s = r + o.r;
      Vec3 e1 = p - a;
      e1 = e1 / norm(e1);
      p = a + e1 * s;
      if (e1.z <= 1e-12) {  // at or below its equator: it leaves the grain
        exclude = held[0];
        n_held = 0;
        continue;
      }
      Vec3 t = e1 * e1.z - ez;  // steepest descent on the sphere
      Real tn = norm(t);
      if (tn < 1e-12) {  // dropped exactly on the top: any way down
        t = Vec3{1, 0, 0} - e1 * e1.x;
        tn = norm(t);
      }
      arc.c = a;
      arc.rho = s;
      arc.e1 = e1;
      arc.e2 = t / tn;
      // the equator: p.z - a.z = rho (e1.z cos t + e2.z sin t) falls through 0
      arc.t_max = first_entry(0, s * arc.e1.z, s * arc.e2.z, 2);  // (up to pi)
      if (arc.t_max.is_none()) arc.t_max = Angle::of(0, 1);       // (pi / 2)
      other = kFloor - 1;                                         // (the equator)
    } else {
      const int ig = is_wall(held[0]) ? 1 : 0;  // (a grain; the other a grain or a wall)
      const int wj = held[1 - ig];
      const Cell& o = at[ig];
      const Vec3 a{o.x, o.y, o.z};
      const Real sa = r + o.r;
      Vec3 u;
      Real along, rho2;
      if (is_wall(wj)) {
        const int j = wall_index(wj);
        u = wall_n_[j];
        along = w.wall_w[j] - dot(u, a);
        rho2 = sa * sa - along * along;
      } else {
        const Cell& ob = at[1 - ig];
        u = Vec3{ob.x, ob.y, ob.z} - a;
        const Real L = norm(u);
        u = u / L;
        const Real sb = r + ob.r;
        along = (L * L + sa * sa - sb * sb) / (2 * L);
        rho2 = sa * sa - along * along;
      }
      if (!(rho2 > 0)) return Drop::Discard;  // (rounding: the two cannot both be touched)
      arc.c = a + u * along;
      arc.rho = std::sqrt(rho2);
      Vec3 e1 = p - arc.c;
      e1 = e1 - u * dot(u, e1);
      e1 = e1 / norm(e1);
      p = arc.c + e1 * arc.rho;
      Vec3 e2 = cross(u, e1);
      if (e2.z > 0) e2 = -e2;
      arc.e1 = e1;
      arc.e2 = e2;
      // the support each contact gives: N_q ~ n_q.ez - k n_other.ez with k = n_0 . n_1, constant
      // on the circle; n_q.ez = (c.z - x_q.z + rho (e1.z cos t + e2.z sin t)) / s_q for a grain
      const Vec3 n0 = normal(held[0], at[0], p, r), n1 = normal(held[1], at[1], p, r);
      const Real kk = dot(n0, n1);
      Real zk[2], za[2], zb[2];
      for (int h = 0; h < 2; ++h) {
        if (is_wall(held[h])) {
          zk[h] = za[h] = zb[h] = 0;
          continue;
        }
        const Cell& q = at[h];
        const Real s = r + q.r;
        zk[h] = (arc.c.z - q.z) / s;
        za[h] = arc.rho * e1.z / s;
        zb[h] = arc.rho * e2.z / s;
      }
      // the lowest point of the circle bounds the arc (no grain rests on two: it is left first)
      arc.t_max = first_entry(0, -arc.rho * e2.z, arc.rho * e1.z, 4);
      if (arc.t_max.is_none()) arc.t_max = Angle::of(-1, 0);  // (pi)
      Angle t_off = Angle::none();
      for (int h = 0; h < 2; ++h) {
        const Angle to = first_entry(zk[h] - kk * zk[1 - h], za[h] - kk * za[1 - h],
                                     zb[h] - kk * zb[1 - h], arc.t_max.key);
        if (to.key < t_off.key) t_off = to, other = held[h];
      }
      if (!t_off.is_none())
        arc.t_max = t_off;
      else
        other = held[zk[0] < zk[1] ? 0 : 1];
    }

    // along the arc: the first new contact, else its end (the equator, a lift-off)
    Angle t;
    int hit;
    // (at a lift-off the grain moves along the contact it leaves, and rounding may make it
    // close: met again at once, it would be left again, over and over; on one sphere the path
    // leaves it for good, a great circle tangent to a cap smaller than a hemisphere)
    Cell met;
    first_contact(arc, r, held, n_held, exclude, w, t, hit, met);
    if (w.out) return Drop::Leave;
    if (t.is_none()) t = arc.t_max;
    Vec3 q = arc.at(t);
    // the floor met on the way: the grain rests there
    const int col = column_y(q.y) * nx_ + column_x(q.x);
    if (q.z - r <= col_floor_[static_cast<std::size_t>(col)] && on_floor(q)) {
      Real lo = 0, hi = t.radians();
      for (int it = 0; it < 48 && hi - lo > 1e-12; ++it) {
        const Real mid = 0.5 * (lo + hi);
        (on_floor(arc.at(mid)) ? hi : lo) = mid;
      }
      rest = arc.at(hi);  // (the first point of the arc found on the floor, to 1e-12 rad)
      report_supports();
      return Drop::Rest;
    }
    p = q;
    if (hit == kFloor) {
      // the end of the arc: off the equator (fall), or a lift-off (roll on the other)
      if (n_held == 1) {
        exclude = held[0];
        n_held = 0;
      } else {
        const int keep = held[0] == other ? 1 : 0;
        exclude = other;
        held[0] = held[keep];
        at[0] = at[keep];
        n_held = 1;
      }
      continue;
    }
    held[n_held] = hit;
    at[n_held++] = met;
    // which of the contacts now touching hold it: all three (at rest), two (a groove), one or none
    Vec3 n[3];
    for (int h = 0; h < n_held; ++h) n[h] = normal(held[h], at[h], p, r);
    const int mask = choose_supports(n, n_held);
    if (mask < 0) return Drop::Discard;
    if (n_held == 3 && mask == 7) {
      rest = p;
      report_supports();
      return Drop::Rest;
    }
    int kept = 0;
    exclude = kFloor;
    for (int h = 0; h < n_held; ++h) {
      if (mask >> h & 1)
        held[kept] = held[h], at[kept++] = at[h];
      else
        exclude = held[h];  // (for a fall and the next arc: the contact it leaves)
    }
    n_held = kept;
  }
  return Drop::Discard;
}

void Packer::insert(std::int32_t k, const Vec3& p, Real r) {
  g_[static_cast<std::size_t>(k)] = {p.x, p.y, p.z, r};
  const int ix = column_x(p.x), iy = column_y(p.y), iz = layer(p.z);
  Slots& s = cells_[cell(ix, iy, iz)];
  int slot = 0;
  while (slot < 3 && s.id[slot] >= 0) ++slot;
  if (slot < 3) {
    s.id[slot] = k;
    s.x[slot] = static_cast<float>(p.x - (R_.x0 + ix * cs_));
    s.y[slot] = static_cast<float>(p.y - (R_.y0 + iy * cs_));
    s.z[slot] = static_cast<float>(p.z - (z0_ + iz * cs_));
    s.r[slot] = static_cast<float>(r);
    // (the float radius may round up or down by 3e-8 r: the contacts stay within 1e-7 d)
  } else {
    next_[static_cast<std::size_t>(k)] = s.more;
    s.more = k;
  }
  int& top = col_top_[static_cast<std::size_t>(iy) * nx_ + ix];
  top = std::max(top, iz);
}

bool Packer::clear(const Vec3& p, Real r) const {
  // (a cell's three slots at once, in floats relative to it as in fall: within 1e-7 of a cell)
  const int ix = column_x(p.x), iy = column_y(p.y), iz = layer(p.z);
  const Real tol = 1e-6 * cs_;
  const F4 reach = splat(static_cast<float>(r - tol));
  for (int jy = std::max(iy - 1, 0); jy <= std::min(iy + 1, ny_ - 1); ++jy)
    for (int jx = std::max(ix - 1, 0); jx <= std::min(ix + 1, nx_ - 1); ++jx) {
      const F4 px = splat(static_cast<float>(p.x - (R_.x0 + jx * cs_)));
      const F4 py = splat(static_cast<float>(p.y - (R_.y0 + jy * cs_)));
      for (int jz = std::max(iz - 1, 0); jz <= std::min(iz + 1, nz_ - 1); ++jz) {
        const Slots& sl = cells_[cell(jx, jy, jz)];
        const F4 pz = splat(static_cast<float>(p.z - (z0_ + jz * cs_)));
        const F4 dx = load4(sl.x) - px, dy = load4(sl.y) - py, dz = load4(sl.z) - pz;
        const F4 s = load4(sl.r) + reach;
        if (mask3(dx * dx + dy * dy + dz * dz < s * s)) return false;  // (NaN: an empty slot)
        for (std::int32_t q = sl.more; q >= 0; q = next_[static_cast<std::size_t>(q)]) {
          const Cell& o = g_[static_cast<std::size_t>(q)];
          const Real sum = r + o.r - tol;
          if (norm2(p - Vec3{o.x, o.y, o.z}) < sum * sum) return false;
        }
      }
    }
  return true;
}

void Packer::run_tile(Tile& tile, std::vector<std::int32_t>& open) {
  open.clear();
  for (int iy = tile.iy0; iy <= tile.iy1; ++iy)
    for (int ix = tile.ix0; ix <= tile.ix1; ++ix)
      if (open_[static_cast<std::size_t>(iy) * nx_ + ix]) open.push_back(iy * nx_ + ix);
  Walk w;
  w.ix0 = std::max(0, tile.ix0 - kMargin);
  w.ix1 = std::min(nx_ - 1, tile.ix1 + kMargin);
  w.iy0 = std::max(0, tile.iy0 - kMargin);
  w.iy1 = std::min(ny_ - 1, tile.iy1 + kMargin);
  Rng rng(tile.seed);
  for (std::int32_t n = 0; n < tile.drops && !open.empty(); ++n) {
    const auto pick = static_cast<std::size_t>(rng.uniform() * static_cast<Real>(open.size()));
    const std::size_t slot = std::min(pick, open.size() - 1);
    const int c = open[slot];
    const int ix = c % nx_, iy = c / nx_;
    const Real r = R_.r_hi > R_.r_lo ? rng.uniform(R_.r_lo, R_.r_hi) : R_.r_lo;
    const Real ux = rng.uniform(), uy = rng.uniform();
    {
      // (the next drop's column, from a copy of the stream, and the cells its fall reads first
      // asked for now: far from this drop's, they would be read from memory, not the cache)
      Rng peek = rng;
      const int nc =
          open[std::min(static_cast<std::size_t>(peek.uniform() * static_cast<Real>(open.size())),
                        open.size() - 1)];
      const int top = col_top_[static_cast<std::size_t>(nc)];
      const int jx = nc % nx_, jy = nc / nx_;
      for (int dy = -2; dy <= 2; ++dy)
        for (int dx = -2; dx <= 2; ++dx) {
          const int qx = std::clamp(jx + dx, 0, nx_ - 1), qy = std::clamp(jy + dy, 0, ny_ - 1);
          const Slots* col = &cells_[cell(qx, qy, 0)];
          __builtin_prefetch(col + std::max(top, 0));
          __builtin_prefetch(col + std::max(top - 1, 0));
        }
    }
    // a point of the cell where the grain lies inside the footprint
    const Real xa = std::max(R_.x0 + ix * cs_, R_.x0 + r),
               xb = std::min(R_.x0 + (ix + 1) * cs_, R_.x1 - r);
    const Real ya = std::max(R_.y0 + iy * cs_, R_.y0 + r),
               yb = std::min(R_.y0 + (iy + 1) * cs_, R_.y1 - r);
    ++tile.made;
    bool kept = false, blocked = false;
    Vec3 p;
    const Drop d = xb >= xa && yb >= ya ? drop(xa + ux * (xb - xa), ya + uy * (yb - ya), r, w, p)
                                        : Drop::Discard;
    if (d == Drop::Leave) {
      // (it rolled too far for its tile: not made here, and no evidence of a full top)
      ++tile.discarded;
      continue;
    }
    if (d == Drop::Rest) {
      // (the bilinear top lies at or above its lowest sample: most grains need no look-up)
      if (p.z > top_.lo - r && p.z > top_.value(p.x, p.y) - r) {
        ++tile.discarded;
      } else {
        if (R_.blocked) {
          // (the caller's function need not be safe to call from two threads at once)
          std::exception_ptr failed;  // (nor may an exception leave a critical section)
#pragma omp critical(sandflow_bed_blocked)
          try {
            blocked = R_.blocked(p, r);
          } catch (...) {
            failed = std::current_exception();
          }
          if (failed) std::rethrow_exception(failed);
        }
        if (blocked) {
          ++tile.discarded;
          ++tile.blocked;
        } else {
          insert(tile.base + n, p, r);
          ++tile.kept;
          kept = true;
        }
      }
    } else {
      ++tile.discarded;
    }
    // A drop refused by an obstacle counts an eighth of one that found the top: the flanks of an
    // obstacle refuse drops until the sand around has grown up to them, and must not close the
    // cells over it before (a cell inside an obstacle closes after 8 patience drops)
    std::uint16_t& fail = fails_[static_cast<std::size_t>(c)];
    if (kept) {
      fail = 0;
    } else if ((fail += blocked ? 1 : 8) >= 8 * R_.patience) {
      open_[static_cast<std::size_t>(c)] = 0;
      ++tile.closed;
      open[slot] = open.back();
      open.pop_back();
    }
  }
}

std::int64_t Packer::prepare() {
  check_region(R_);
  floor_ = sample_map(R_, R_.floor, "floor", R_.r_lo);
  top_ = sample_map(R_, R_.top, "top", R_.r_lo);
  // (flat to rounding: a container's floor comes back from the geometry within 1e-17 m)
  flat_floor_ = floor_.hi - floor_.lo <= 1e-9 * R_.r_lo;
  if (!flat_floor_) {
    // A floor that is not flat, every r_lo / 2: between samples the bilinear floor sags
    // h^2 |f''| / 8 under a bump, and at r_lo grains of the wavy floor of the tests reached 1.1 %
    // of d into it, 0.5 % at r_lo / 2. (Not a flat one: the scene's geometry can be slow to ask,
    // 6 us a point for a box container.)
    floor_ = sample_map(R_, R_.floor, "floor", R_.r_lo / 2);
    top_ = sample_map(R_, R_.top, "top", R_.r_lo / 2);
  }
  const Real estimate = estimate_from_maps(R_, floor_, top_);
  if (estimate > R_.max_grains)
    throw std::length_error("bed packing: the region would hold about " +
                            std::to_string(static_cast<long long>(estimate)) +
                            " grains, more than the limit of " +
                            std::to_string(static_cast<long long>(R_.max_grains)));

  // the grid: cells 2 r_hi wide, from under the lowest floor to over the highest top
  cs_ = 2 * R_.r_hi;
  inv_cs_ = 1 / cs_;
  fcs_ = static_cast<float>(cs_);
  nx_ = std::max(1, static_cast<int>(std::ceil((R_.x1 - R_.x0) / cs_)));
  ny_ = std::max(1, static_cast<int>(std::ceil((R_.y1 - R_.y0) / cs_)));
  z0_ = floor_.lo - cs_;
  const Real layers = std::ceil((std::max(top_.hi, floor_.lo) - z0_) / cs_) + 1;
  const Real cells = layers * nx_ * ny_;
  if (cells > std::max(8 * estimate, 1.0e6) || cells > 2.0e9)
    throw std::length_error("bed packing: the region's bounding box (" +
                            std::to_string(static_cast<long long>(cells)) +
                            " cells) is too large for the grains it holds");
  nz_ = static_cast<int>(layers);
  cells_.assign(static_cast<std::size_t>(cells), Slots{});
  col_top_.assign(static_cast<std::size_t>(nx_) * ny_, -1);
  col_floor_.assign(col_top_.size(), -kInf);
  for (int j = 0; j < floor_.my; ++j)  // each column's highest floor, with a grain's reach
    for (int i = 0; i < floor_.mx; ++i) {
      const Real x = floor_.x0 + i * floor_.hx, y = floor_.y0 + j * floor_.hy;
      for (int iy = column_y(y - R_.r_hi - floor_.hy); iy <= column_y(y + R_.r_hi + floor_.hy);
           ++iy)
        for (int ix = column_x(x - R_.r_hi - floor_.hx); ix <= column_x(x + R_.r_hi + floor_.hx);
             ++ix) {
          Real& f = col_floor_[static_cast<std::size_t>(iy) * nx_ + ix];
          f = std::max(f, floor_.at(i, j));
        }
    }
  if (flat_floor_) std::fill(col_floor_.begin(), col_floor_.end(), floor_.hi);
  // (a tangent plane lies at most r (sqrt(2) - 1) above the samples: it is used up to 45 degrees)
  for (Real& f : col_floor_) f += (std::sqrt(2.0) - 1) * R_.r_hi + 1e-12;
  // (ids are reserved for drops, about 1.3 a grain)
  const auto reserve = static_cast<std::size_t>(std::min(estimate * 1.5 + 16, 2.0e9));
  g_.reserve(reserve);
  next_.reserve(reserve);

  // the cells drops are made in, each open until `patience` drops in a row fail there
  open_.assign(col_top_.size(), 0);
  fails_.assign(col_top_.size(), 0);
  std::int64_t n_open = 0;
  for (int iy = 0; iy < ny_; ++iy)
    for (int ix = 0; ix < nx_; ++ix) {
      // closed at once where no grain fits under the top anywhere in the cell
      const int i0 = static_cast<int>(std::floor(ix * cs_ / floor_.hx));
      const int i1 =
          std::min(floor_.mx - 1, static_cast<int>(std::ceil((ix + 1) * cs_ / floor_.hx)));
      const int j0 = static_cast<int>(std::floor(iy * cs_ / floor_.hy));
      const int j1 =
          std::min(floor_.my - 1, static_cast<int>(std::ceil((iy + 1) * cs_ / floor_.hy)));
      bool room = false;
      for (int j = j0; j <= j1 && !room; ++j)
        for (int i = i0; i <= i1 && !room; ++i)
          room = top_.at(i, j) - floor_.at(i, j) >= 2 * R_.r_lo;
      if (room) {
        open_[static_cast<std::size_t>(iy) * nx_ + ix] = 1;
        ++n_open;
      }
    }
  return n_open;
}

std::vector<Packer::TileGrain> Packer::pack_periodic(int n_tile, int ghost) {
  // The tile is the central n_tile x n_tile columns of this packer's grid; the `ghost` columns
  // around it hold the images of the grains within reach of its sides, so that a drop near a side
  // sees the grains across it as they lie in the next copy. A drop that would read past the
  // ghosts is not made (none of the tile's drops did, 2026-11-27).
  const Real L = n_tile * cs_;
  const Real c_lo = R_.x0 + ghost * cs_, c_hi = c_lo + L;  // (x and y alike: a square)
  std::vector<TileGrain> tile;
  struct Image {
    std::int32_t of;
    std::int8_t sx, sy;
  };
  std::vector<Image> image;  // by id
  std::vector<std::int32_t> open;
  for (int iy = ghost; iy < ghost + n_tile; ++iy)
    for (int ix = ghost; ix < ghost + n_tile; ++ix) open.push_back(iy * nx_ + ix);
  Walk w;
  w.ix0 = w.iy0 = 1;
  w.ix1 = nx_ - 2;
  w.iy1 = ny_ - 2;
  Rng rng(R_.seed);
  while (!open.empty()) {
    const std::size_t slot = std::min(
        static_cast<std::size_t>(rng.uniform() * static_cast<Real>(open.size())), open.size() - 1);
    const int c = open[slot];
    const int ix = c % nx_, iy = c / nx_;
    const Real r = R_.r_hi > R_.r_lo ? rng.uniform(R_.r_lo, R_.r_hi) : R_.r_lo;
    const Real x = R_.x0 + (ix + rng.uniform()) * cs_, y = R_.y0 + (iy + rng.uniform()) * cs_;
    Vec3 p;
    int support[3] = {-1, -1, -1};
    const Drop d = drop(x, y, r, w, p, support);
    if (d == Drop::Leave) continue;
    bool kept = false;
    if (d == Drop::Rest && p.z <= top_.lo - r) {
      // into the central square, and its supports as seen from there
      int wx = 0, wy = 0;
      for (; p.x < c_lo; p.x += L) ++wx;
      for (; p.x >= c_hi; p.x -= L) --wx;
      for (; p.y < c_lo; p.y += L) ++wy;
      for (; p.y >= c_hi; p.y -= L) --wy;
      TileGrain t{p, r, {-1, -1, -1}, {0, 0, 0}, {0, 0, 0}};
      for (int k = 0; k < 3 && support[k] >= 0; ++k) {
        const Image& s = image[static_cast<std::size_t>(support[k])];
        t.support[k] = s.of;
        t.sx[k] = static_cast<std::int8_t>(s.sx + wx);
        t.sy[k] = static_cast<std::int8_t>(s.sy + wy);
      }
      const auto of = static_cast<std::int32_t>(tile.size());
      tile.push_back(t);
      // the grain and its images on the grid
      for (int sy = -1; sy <= 1; ++sy)
        for (int sx = -1; sx <= 1; ++sx) {
          const Vec3 q{p.x + sx * L, p.y + sy * L, p.z};
          if (q.x < R_.x0 || q.x >= R_.x1 || q.y < R_.y0 || q.y >= R_.y1) continue;
          const auto id = static_cast<std::int32_t>(g_.size());
          g_.push_back({});
          next_.push_back(-1);
          image.push_back({of, static_cast<std::int8_t>(sx), static_cast<std::int8_t>(sy)});
          insert(id, q, r);
        }
      kept = true;
    }
    std::uint16_t& fail = fails_[static_cast<std::size_t>(c)];
    if (kept) {
      fail = 0;
    } else if (++fail >= R_.patience) {
      open[slot] = open.back();
      open.pop_back();
    }
  }
  return tile;
}

std::int64_t Packer::lay_slab(BedPacking& out) {
  const Real z_cut = top_.lo - kSlabBelowTop * cs_;
  const Real L = kSlabTile * cs_;
  if (!flat_floor_ || z_cut - floor_.hi < kSlabLeast * cs_ || R_.x1 - R_.x0 < 2 * L ||
      R_.y1 - R_.y0 < 2 * L)
    return 0;
  // the tile: packed on the same floor up to a little over the cut, so that the cut passes
  // through its bulk and not its ragged top
  const int n_all = kSlabTile + 2 * kSlabGhost;
  BedRegion T;
  T.x0 = T.y0 = 0;
  T.x1 = T.y1 = (n_all - 0.5) * cs_;  // (n_all columns, the last half wide)
  const Real floor = floor_.hi, top = z_cut + 2 * cs_;
  T.floor = [floor](Real, Real) { return floor; };
  T.top = [top](Real, Real) { return top; };
  T.r_lo = R_.r_lo;
  T.r_hi = R_.r_hi;
  T.seed = mix_seed(R_.seed, ~0ULL, 1);
  T.patience = R_.patience;
  Packer packer(T);
  packer.prepare();
  const std::vector<TileGrain> tile = packer.pack_periodic(kSlabTile, kSlabGhost);
  const Real c_lo = kSlabGhost * cs_;

  // copy (a, b) of the tile puts its square's low corner at (x0 - ox + a L, y0 - oy + b L), the
  // offset at random; a grain of a copy is laid when it lies under the cut, inside the footprint,
  // not in an obstacle, and every grain holding it is laid (those lie earlier in the tile's
  // order): whatever stays rests as it did in the tile
  Rng rng(mix_seed(R_.seed, ~0ULL, 2));
  const Real ox = rng.uniform() * L, oy = rng.uniform() * L;
  const int na = static_cast<int>(std::ceil((R_.x1 - R_.x0 + ox) / L));
  const int nb = static_cast<int>(std::ceil((R_.y1 - R_.y0 + oy) / L));
  const std::size_t copies = static_cast<std::size_t>(na) * nb;
  enum : std::uint8_t { kCut, kLaid, kFallen };
  std::vector<std::uint8_t> state(tile.size() * copies, kCut);  // grain-major
  auto where = [&](const TileGrain& t, int a, int b) {
    return Vec3{t.p.x - c_lo + R_.x0 - ox + a * L, t.p.y - c_lo + R_.y0 - oy + b * L, t.p.z};
  };
  for (std::size_t k = 0; k < tile.size(); ++k) {
    const TileGrain& t = tile[k];
    if (t.p.z >= z_cut) continue;
    for (int b = 0; b < nb; ++b)
      for (int a = 0; a < na; ++a) {
        const Vec3 p = where(t, a, b);
        if (p.x - t.r < R_.x0 || p.x + t.r > R_.x1 || p.y - t.r < R_.y0 || p.y + t.r > R_.y1)
          continue;
        bool held = true;
        for (int s = 0; s < 3 && held && t.support[s] >= 0; ++s) {
          const int sa = a + t.sx[s], sb = b + t.sy[s];
          held = sa >= 0 && sa < na && sb >= 0 && sb < nb &&
                 state[static_cast<std::size_t>(t.support[s]) * copies +
                       static_cast<std::size_t>(sb) * na + sa] == kLaid;
        }
        if (held && R_.blocked && R_.blocked(p, t.r)) continue;
        state[k * copies + static_cast<std::size_t>(b) * na + a] = held ? kLaid : kFallen;
      }
  }
  // into the grid, copy by copy; the id each grain of a copy takes, once it is in
  std::vector<std::int32_t> id_of(tile.size() * copies, -1);
  std::vector<std::uint32_t> kc_of;                  // by id - first_id: k * copies + c
  std::vector<std::array<std::int32_t, 3>> held_by;  // by id - first_id: a fallen grain's holders
  const auto first_id = static_cast<std::int32_t>(g_.size());
  auto put = [&](std::size_t k, std::size_t c, const Vec3& p) {
    const auto id = static_cast<std::int32_t>(g_.size());
    g_.push_back({});
    next_.push_back(-1);
    insert(id, p, tile[k].r);
    id_of[k * copies + c] = id;
    kc_of.push_back(static_cast<std::uint32_t>(k * copies + c));
    held_by.push_back({-1, -1, -1});
  };
  std::int64_t n = 0;
  for (std::size_t c = 0; c < copies; ++c) {
    const int a = static_cast<int>(c % na), b = static_cast<int>(c / na);
    for (std::size_t k = 0; k < tile.size(); ++k) {
      if (state[k * copies + c] != kLaid) continue;
      put(k, c, where(tile[k], a, b));
      ++n;
    }
  }
  // Then the grains that lost a grain holding them (the cut's cone): each falls from where it lay
  // in the tile and rolls to rest in the hole under it, from the lowest up (a grain after the
  // grains that held it), unless one fallen before it has taken its place. (Dropped at random
  // points instead, its holes were found by chance, layer after layer, with as many drops again
  // discarded.)
  //
  // Along a wall the cone is the same in every copy, but for its ends: the copies of the middle
  // row and column (the templates) settle theirs, and another copy takes a grain of the template
  // in its column (or else in its row) shifted by the copies between them, where the grains
  // holding it there lie shifted the same way (so it rests as the template's does) and nothing is
  // in its place; a grain that cannot settles by itself (docs/performance.md, 2026-11-27, ninth).
  const int a_mid = na / 2, b_mid = nb / 2;
  struct Fallen {
    float z;
    bool copied;  // (a template's grain settles before its copies)
    std::uint32_t k, c;
  };
  std::vector<Fallen> fallen;
  for (std::size_t k = 0; k < tile.size(); ++k)
    for (std::size_t c = 0; c < copies; ++c)
      if (state[k * copies + c] == kFallen) {
        const bool copied = static_cast<int>(c % na) != a_mid && static_cast<int>(c / na) != b_mid;
        fallen.push_back({static_cast<float>(tile[k].p.z), copied, static_cast<std::uint32_t>(k),
                          static_cast<std::uint32_t>(c)});
      }
  std::stable_sort(fallen.begin(), fallen.end(), [](const Fallen& u, const Fallen& v) {
    return u.z < v.z || (u.z == v.z && !u.copied && v.copied);
  });
  auto shift_of = [&](std::int32_t id) {
    const std::uint32_t kc = kc_of[static_cast<std::size_t>(id - first_id)];
    const std::size_t c = kc % copies;
    const Cell& g = g_[static_cast<std::size_t>(id)];
    return Vec3{g.x, g.y, g.z} -
           where(tile[kc / copies], static_cast<int>(c % na), static_cast<int>(c / na));
  };
  // where grain k of copy c stands in for the same grain of the template copy t: its shifted place
  // and the grains holding it there, or false when it would not rest there as the template's does
  auto copy_of = [&](std::size_t k, std::size_t c, std::size_t t, Vec3& q,
                     std::array<std::int32_t, 3>& held) {
    // (a laid template grain rests on its holders in the tile, which copy c has not all laid)
    const std::int32_t tid = id_of[k * copies + t];
    if (tid < 0 || state[k * copies + t] != kFallen) return false;
    held = {-1, -1, -1};
    int n_held = 0;
    const int da = static_cast<int>(c % na) - static_cast<int>(t % na);
    const int db = static_cast<int>(c / na) - static_cast<int>(t / na);
    const Vec3 shift = shift_of(tid);
    const Real tol = 1e-9 * cs_;
    for (const std::int32_t h : held_by[static_cast<std::size_t>(tid - first_id)]) {
      if (h < 0) break;
      const std::uint32_t kc = kc_of[static_cast<std::size_t>(h - first_id)];
      const int ha = static_cast<int>(kc % copies % na) + da;
      const int hb = static_cast<int>(kc % copies / na) + db;
      if (ha < 0 || ha >= na || hb < 0 || hb >= nb) return false;
      const std::int32_t hid = id_of[kc / copies * copies + static_cast<std::size_t>(hb) * na + ha];
      if (hid < 0 || norm2(shift_of(hid) - shift_of(h)) > tol * tol) return false;
      held[static_cast<std::size_t>(n_held++)] = hid;
    }
    const Real r = tile[k].r;
    const Cell& g = g_[static_cast<std::size_t>(tid)];
    // (on a wall or across the way a copy is shifted: the template's walls are not the copy's)
    const bool along_y = da == 0;
    const Real lo = along_y ? R_.y0 : R_.x0, hi = along_y ? R_.y1 : R_.x1;
    const Real u = along_y ? g.y : g.x;
    if (u - r < lo + tol || u + r > hi - tol) return false;
    q = where(tile[k], static_cast<int>(c % na), static_cast<int>(c / na)) + shift;
    const Real v = along_y ? q.y : q.x;
    return v - r >= lo + tol && v + r <= hi - tol && clear(q, r);
  };
  Walk w;
  w.ix1 = nx_ - 1;
  w.iy1 = ny_ - 1;
  for (std::size_t i = 0; i < fallen.size(); ++i) {
    const Fallen& f = fallen[i];
    if (i + 1 < fallen.size()) {
      // (the cells the next grain's place is checked in, asked for now: it lies elsewhere)
      const Fallen& g = fallen[i + 1];
      const Vec3 p = where(tile[g.k], static_cast<int>(g.c % na), static_cast<int>(g.c / na));
      const int ix = column_x(p.x), iy = column_y(p.y), iz = std::max(layer(p.z) - 1, 0);
      for (int jy = std::max(iy - 1, 0); jy <= std::min(iy + 1, ny_ - 1); ++jy)
        for (int jx = std::max(ix - 1, 0); jx <= std::min(ix + 1, nx_ - 1); ++jx) {
          const Slots* col = &cells_[cell(jx, jy, iz)];
          __builtin_prefetch(col);
          __builtin_prefetch(col + 1);
          __builtin_prefetch(col + 2);
        }
    }
    const Real r = tile[f.k].r;
    const std::size_t in_column = static_cast<std::size_t>(b_mid) * na + f.c % na;
    const std::size_t in_row = f.c / na * na + static_cast<std::size_t>(a_mid);
    Vec3 q;
    std::array<std::int32_t, 3> held;
    if (f.copied && (copy_of(f.k, f.c, in_column, q, held) || copy_of(f.k, f.c, in_row, q, held)) &&
        !(R_.blocked && R_.blocked(q, r))) {
      put(f.k, f.c, q);
      held_by.back() = held;
      ++n;
      ++out.settled;
      ++out.copied;
      continue;
    }
    const Vec3 p = where(tile[f.k], static_cast<int>(f.c % na), static_cast<int>(f.c / na));
    if (!clear(p, r)) continue;
    // (from a hair above: a fall skips a grain it touches at its start)
    Vec3 rest;
    int support[3] = {-1, -1, -1};
    if (drop(p.x, p.y, r, w, rest, support, p.z + 1e-6 * cs_) != Drop::Rest) continue;
    if (R_.blocked && R_.blocked(rest, r)) continue;
    put(f.k, f.c, rest);
    held_by.back() = {support[0], support[1], support[2]};
    ++n;
    ++out.settled;
  }
  return n;
}

BedPacking Packer::run() {
  std::int64_t n_open = prepare();
  BedPacking out;
  out.tiled = lay_slab(out);
  std::int64_t kept = out.tiled;
  const int threads = std::max(1, R_.threads);
  std::vector<std::vector<std::int32_t>> scratch(static_cast<std::size_t>(threads));
  std::vector<Tile> tiles;
  for (std::uint64_t round = 0; n_open > 0; ++round) {
    // this round's tiling, shifted at random so that no seam stays, and the order of its colours
    Rng rng(mix_seed(R_.seed, round, 0));
    const int ox = static_cast<int>(rng.next() % kTile), oy = static_cast<int>(rng.next() % kTile);
    int colours[4] = {0, 1, 2, 3};
    for (int i = 3; i > 0; --i)
      std::swap(colours[i],
                colours[static_cast<int>(rng.next() % static_cast<std::uint64_t>(i + 1))]);
    const int tx = (nx_ + ox + kTile - 1) / kTile, ty = (ny_ + oy + kTile - 1) / kTile;
    for (const int colour : colours) {
      // its tiles with an open column, their drops and the ids reserved for them, in tile order
      tiles.clear();
      std::int64_t next_id = static_cast<std::int64_t>(g_.size());
      for (int j = colour / 2; j < ty; j += 2)
        for (int i = colour % 2; i < tx; i += 2) {
          Tile t;
          t.ix0 = std::max(0, i * kTile - ox);
          t.ix1 = std::min(nx_ - 1, (i + 1) * kTile - ox - 1);
          t.iy0 = std::max(0, j * kTile - oy);
          t.iy1 = std::min(ny_ - 1, (j + 1) * kTile - oy - 1);
          int n = 0;
          for (int iy = t.iy0; iy <= t.iy1; ++iy)
            for (int ix = t.ix0; ix <= t.ix1; ++ix)
              n += open_[static_cast<std::size_t>(iy) * nx_ + ix];
          if (n == 0) continue;
          // (a drop per open cell, about a layer: half a layer made the bed the same, and twice
          // the phases, each ending when its last tile does, which costs much when another
          // program holds a core)
          t.drops = n;
          t.base = static_cast<std::int32_t>(next_id);
          t.seed = mix_seed(R_.seed, round, static_cast<std::uint64_t>(j * tx + i) + 1);
          next_id += t.drops;
          tiles.push_back(t);
        }
      if (next_id > std::numeric_limits<std::int32_t>::max())
        throw std::length_error("bed packing: more drops than grain ids");
      g_.resize(static_cast<std::size_t>(next_id), Cell{0, 0, 0, 0});
      next_.resize(static_cast<std::size_t>(next_id), -1);
      // tiles of one colour are a tile apart, farther than two margins: their drops read and
      // write disjoint columns, so the bed does not depend on the threads nor their order
      const auto n_tiles = static_cast<std::int64_t>(tiles.size());
      // (an exception of `blocked` must not leave the parallel loop: kept, and thrown after it)
      std::exception_ptr failed;
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads) if (threads > 1 && n_tiles > 1)
      for (std::int64_t k = 0; k < n_tiles; ++k) {
        try {
          run_tile(tiles[static_cast<std::size_t>(k)],
                   scratch[static_cast<std::size_t>(omp_get_thread_num())]);
        } catch (...) {
#pragma omp critical(sandflow_bed_failed)
          if (!failed) failed = std::current_exception();
        }
      }
      if (failed) std::rethrow_exception(failed);
      for (const Tile& t : tiles) {
        out.drops += t.made;
        out.discarded += t.discarded;
        out.blocked += t.blocked;
        kept += t.kept;
        n_open -= t.closed;
      }
      if (static_cast<Real>(kept) > R_.max_grains)
        throw std::length_error("bed packing: more grains than the limit of " +
                                std::to_string(static_cast<long long>(R_.max_grains)));
    }
  }
  out.x.reserve(static_cast<std::size_t>(kept));
  out.r.reserve(static_cast<std::size_t>(kept));
  for (const Cell& c : g_)
    if (c.r > 0) {
      out.x.push_back({c.x, c.y, c.z});
      out.r.push_back(c.r);
    }
  return out;
}

}  // namespace

Real estimate_bed_grains(const BedRegion& region) {
  check_region(region);
  return estimate_from_maps(region, sample_map(region, region.floor, "floor", region.r_lo),
                            sample_map(region, region.top, "top", region.r_lo));
}

BedPacking pack_bed(const BedRegion& region) {
  return Packer(region).run();
}

Real packing_fraction_in(const std::vector<Vec3>& x, const std::vector<Real>& r, const Vec3& lo,
                         const Vec3& hi) {
  Real v = 0;
  for (std::size_t i = 0; i < x.size(); ++i)
    if (x[i].x >= lo.x && x[i].x < hi.x && x[i].y >= lo.y && x[i].y < hi.y && x[i].z >= lo.z &&
        x[i].z < hi.z)
      v += 4.0 / 3.0 * kPi * r[i] * r[i] * r[i];
  const Vec3 e = hi - lo;
  return v / (e.x * e.y * e.z);
}

Real largest_overlap(const std::vector<Vec3>& x, const std::vector<Real>& r) {
  if (x.empty()) return 0;
  Vec3 lo = x[0], hi = x[0];
  Real r_max = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    lo = min(lo, x[i]);
    hi = max(hi, x[i]);
    r_max = std::max(r_max, r[i]);
  }
  const Real cs = 2 * r_max;
  auto n_of = [&](Real a, Real b) {
    return static_cast<std::int64_t>(std::floor((b - a) / cs)) + 1;
  };
  const std::int64_t nx = n_of(lo.x, hi.x), ny = n_of(lo.y, hi.y), nz = n_of(lo.z, hi.z);
  auto idx = [&](const Vec3& p, std::int64_t& i, std::int64_t& j, std::int64_t& k) {
    i = static_cast<std::int64_t>(std::floor((p.x - lo.x) / cs));
    j = static_cast<std::int64_t>(std::floor((p.y - lo.y) / cs));
    k = static_cast<std::int64_t>(std::floor((p.z - lo.z) / cs));
  };
  // grains sorted by cell (counting sort over a hashed cell index keeps memory bounded)
  const std::size_t buckets = x.size() * 2 + 1;
  auto hash = [&](std::int64_t i, std::int64_t j, std::int64_t k) {
    return static_cast<std::size_t>(((i * ny + j) * nz + k) % static_cast<std::int64_t>(buckets));
  };
  std::vector<std::uint32_t> start(buckets + 1, 0), order(x.size());
  for (const Vec3& p : x) {
    std::int64_t i, j, k;
    idx(p, i, j, k);
    ++start[hash(i, j, k) + 1];
  }
  for (std::size_t b = 0; b < buckets; ++b) start[b + 1] += start[b];
  std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
  for (std::size_t n = 0; n < x.size(); ++n) {
    std::int64_t i, j, k;
    idx(x[n], i, j, k);
    order[fill[hash(i, j, k)]++] = static_cast<std::uint32_t>(n);
  }
  Real worst = 0;
  for (std::size_t n = 0; n < x.size(); ++n) {
    std::int64_t i, j, k;
    idx(x[n], i, j, k);
    for (std::int64_t a = i - 1; a <= i + 1; ++a)
      for (std::int64_t b = j - 1; b <= j + 1; ++b)
        for (std::int64_t c = k - 1; c <= k + 1; ++c) {
          if (a < 0 || b < 0 || c < 0 || a >= nx || b >= ny || c >= nz) continue;
          const std::size_t h = hash(a, b, c);
          for (std::uint32_t q = start[h]; q < start[h + 1]; ++q) {
            const std::uint32_t m = order[q];
            if (m <= n) continue;
            const Real s = r[n] + r[m];
            const Real d2 = norm2(x[n] - x[m]);
            if (d2 >= s * s) continue;
            worst = std::max(worst, (s - std::sqrt(d2)) / (2 * std::min(r[n], r[m])));
          }
        }
  }
  return worst;
}

}  // namespace sandflow
