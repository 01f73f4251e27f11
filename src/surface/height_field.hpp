// The height field of the static layer (docs/design.md §4): a uniform grid of columns over the
// scene. Per column, at its centre: L (terrain top), H (top of the sand, measured from the grains),
// h (top of the static layer) and R = H - h (the rolling layer). Slopes live on the edges between
// columns, as on a MAC grid. One update runs the paper's order H -> theta -> Gamma -> h -> R ->
// R_min.
//
// The terrain is multi-valued: a column may cross several solids (a bowl above the floor, the
// back of an obstacle above the ground below it). Its sand rests on one of their tops, the
// column's level: the highest top with sand on it, or the highest top while there is none. L is
// that top and H never reaches the solid above it (the column's ceiling).
//
// Only what can change is updated (docs/design.md §4): a column is measured when grains hit it
// now or at the last update, or its static top changed; the exchange evaluates the measured
// columns, the flowing ones, the open ones and those beside a column whose h changed. Any other
// column is closed, at rest, with none of its inputs changed since an update that left it as it
// was: the update would leave it so again, so skipping it changes nothing (tested against
// updating every column), and a bed at rest costs nothing however large.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "core/vec3.hpp"
#include "dem/grains.hpp"
#include "surface/column_set.hpp"

namespace sandflow {

struct HeightFieldParams {
  Real x0 = 0, y0 = 0;        ///< corner of the grid (low x, low y) [m]
  Real cell = 0.01;           ///< column width [m]
  int nx = 1, ny = 1;         ///< columns along x and y
  Real gamma = 30;            ///< exchange rate [1/s]
  Real theta0 = 0.56;         ///< repose angle [rad]
  Real theta_max = 0.66;      ///< a static slope steeper than this erodes on its own [rad]
  Real rolling_min = 0.01;    ///< R_min [m]
  Real flowing_min = 0;       ///< R_min under a flowing layer [m] (never below rolling_min)
  /// A column that stopped flowing keeps flowing_min for this long, so that the layer DEM still
  /// shears comes to rest on its own instead of on a bed frozen under it (no longer than
  /// close_after) [s]
  Real flowing_hold = 0;
  /// A flowing column erodes its static layer only where a moving grain reaches down to within
  /// this of the static top (infinity: wherever grains flow); grains flowing over grains at rest
  /// do not dig the static sand under those (docs/physics.md, step 3 of the surface flow) [m]
  Real erosion_reach = std::numeric_limits<Real>::infinity();
  Real avalanche_depth = 0.01;///< thickness that rolls where theta > theta_max [m]
  Real gap = 0.01;            ///< a grain separated from the pile below by more is airborne [m]
  /// A column whose grains have not moved the pile for this long is closed: R_min no longer holds
  /// there, so its top freezes into the static layer like the rest (a bed at rest costs nothing)
  /// [s]
  Real close_after = 2.0;

  /// R_min under a flowing layer as used: never below rolling_min [m].
  Real flowing_floor() const { return std::max(flowing_min, rolling_min); }
  /// flowing_hold as used: never longer than close_after [s].
  Real hold_time() const { return std::min(flowing_hold, close_after); }
};

/// The solid intervals [bottom, top] crossed by the vertical line through each column centre,
/// ascending and disjoint, in compressed rows (columns row-major, x fastest).
///
/// And the walls between column centres: a solid standing on an edge between two neighbouring
/// columns higher than either column's own solids there (a container's wall thinner than a
/// column, a ridge), which a column's centre line misses. Sand does not cross an edge below its
/// wall's top (docs/design.md §4, "Walls between columns").
struct TerrainColumns {
  std::vector<std::uint32_t> start{0};  ///< columns+1 offsets
  std::vector<Real> bottom, top;        ///< per interval [m]; the lowest may start at -infinity

  /// A solid [bottom, top] on the edge from a column to its neighbour at +x (axis 0) or +y (1).
  struct Wall {
    std::uint8_t axis;
    Real bottom, top;
  };
  std::vector<std::uint32_t> wall_start{0};  ///< columns+1 offsets into walls, by lower column
  std::vector<Wall> walls;

  std::size_t columns() const { return start.size() - 1; }
  /// One solid per column, from -infinity up to L[c], and no walls.
  static TerrainColumns single(const std::vector<Real>& L);
  /// Appends a column (intervals ascending, disjoint) and the walls on its +x and +y edges.
  void add_column(const std::vector<std::pair<Real, Real>>& intervals,
                  const std::vector<Wall>& edge_walls = {});
};

class HeightField {
 public:
  /// `terrain` holds L per column (row-major, x fastest); h starts at L.
  HeightField(const HeightFieldParams& p, std::vector<Real> terrain);
  /// A multi-valued terrain: every column needs at least one solid interval.
  HeightField(const HeightFieldParams& p, TerrainColumns terrain);

  // ---- the grid ----
  int nx() const { return p_.nx; }
  int ny() const { return p_.ny; }
  std::size_t columns() const { return static_cast<std::size_t>(p_.nx) * p_.ny; }
  Real cell() const { return p_.cell; }
  const HeightFieldParams& params() const { return p_; }
  Vec3 centre(std::size_t c) const {
    return {p_.x0 + (static_cast<Real>(c % p_.nx) + 0.5) * p_.cell,
            p_.y0 + (static_cast<Real>(c / p_.nx) + 0.5) * p_.cell, 0};
  }
  /// Column holding (x, y), or -1 outside the grid.
  std::int64_t column_of(Real x, Real y) const;
  /// h interpolated bilinearly between column centres (clamped at the border); across a step of
  /// the terrain or a wall, h of the column holding (x, y).
  Real static_top_at(Real x, Real y) const;
  /// Whether h and L may be interpolated over the square between the centres of columns (i, j)
  /// and (i + 1, j + 1): no step of the terrain higher than a column and no wall on its edges.
  bool smooth_square(int i, int j) const;
  /// The top of the wall on the edge between neighbouring columns c and n where it stands above
  /// both their levels [m]; -infinity where none does.
  Real wall_top(std::size_t c, std::size_t n) const {
    const std::size_t lo = std::min(c, n), hi = std::max(c, n);
    const std::uint32_t k0 = solids_.wall_start[lo], k1 = solids_.wall_start[lo + 1];
    Real top = -std::numeric_limits<Real>::infinity();
    if (k0 == k1) return top;  // (nearly every edge)
    const std::uint8_t axis = hi - lo == static_cast<std::size_t>(p_.nx) ? 1 : 0;
    const Real level = std::max(L_[c], L_[n]);
    for (std::uint32_t k = k0; k < k1; ++k) {
      const TerrainColumns::Wall& w = solids_.walls[k];
      if (w.axis == axis && w.bottom <= level && level < w.top) top = w.top;
    }
    return top;
  }
  /// Whether walls higher than z stand between columns (i0, j0) and (i1, j1) on both of the
  /// shortest ways from one to the other along the grid (x first, or y first).
  bool walled_off(int i0, int j0, int i1, int j1, Real z) const;
  /// Neighbour n's height in z (its static top, or a trial one) as column c's sand sees it: a
  /// wall between them stands in for it up to its top.
  Real top_across(std::size_t c, std::size_t n, const std::vector<Real>& z) const {
    return std::max(z[n], wall_top(c, n));
  }

  // ---- one update ----
  /// A grain's `counts` in measure(): frozen, or at rest on the pile (it counts across a gap).
  static constexpr std::uint8_t kHeldOnPile = 2;
  /// Step 1: H from vertical thick rays (radius cell/2) against the pile. `static_top` per column
  /// is the highest point the STATIC grains reach there (or anything not above L). Hot grains
  /// count only where `counts` is nonzero (empty: all count), and from the bottom up only while
  /// no gap separates them from what lies below: grains in flight never lift the surface. Those
  /// whose `counts` is kHeldOnPile (frozen, or at rest on the pile) count across a gap too: it is
  /// a void under grains bridged across it, as along a container's wall. Also
  /// picks each column's level; where it changes, h starts afresh at the new L.
  /// `changed_tops` lists the columns whose static top changed since the last measure (null: any
  /// may have).
  void measure(const Grains& hot, const std::vector<Real>& static_top,
               const std::vector<std::uint8_t>& counts = {},
               const std::vector<std::uint32_t>* changed_tops = nullptr);
  /// Steps 2-6 over a time dt: slopes, exchange, h, R, and the R_min floor (flowing_min under a
  /// flowing layer, none in a closed column: see close_after). `flowing` marks the
  /// columns whose rolling layer holds moving grains (empty: all flow). A rolling layer at rest
  /// deposits up to theta_max, the steepest a static slope stands; a flowing one erodes the
  /// static layer down to theta0 (the hysteresis of the angle of repose).
  void exchange(Real dt, const std::vector<std::uint8_t>& flowing = {});
  /// As above, with the flowing columns listed (each once): the update's work follows them.
  /// `eroding`, when given, lists those of them whose static top a moving grain reaches
  /// (erosion_reach): the others deposit down to theta0 but do not erode. Without it every
  /// flowing column erodes.
  void exchange(Real dt, const ColumnSet& flowing, const ColumnSet* eroding = nullptr);
  /// Lowers h of column c to at most z (never below L): the static layer cannot reach up to where
  /// grains are moving.
  void limit_static_top(std::size_t c, Real z) {
    const Real h = std::max(std::min(h_[c], z), L_[c]);
    if (h == h_[c]) return;
    h_[c] = h;
    R_[c] = H_[c] - h_[c];
    moved(c);
  }
  /// The geometry changed (a solid was removed): new solid intervals per column. A column whose
  /// level is no longer a top drops to the highest top below it (or the highest there is), with
  /// H = h = L there until the next measure: the static grains it held then wake, as where h
  /// falls.
  void set_solids(TerrainColumns terrain);
  /// For tests: set H directly (then call exchange).
  void set_surface(std::vector<Real> H);
  /// For tests and restarts: set h directly (clamped to [L, H]).
  void set_static_top(std::vector<Real> h);

  /// For restarts (src/checkpoint/): every per-column array the next update reads or reports.
  struct State {
    std::vector<Real> L, H, h, R, theta, Gamma, rest, hold;
  };
  State state() const { return {L_, H_, h_, R_, theta_, Gamma_, rest_, hold_left_}; }
  /// Sets the arrays as saved (sizes checked by the caller).
  void restore(State s);

  /// Contributions of one sphere to the columns its thick ray touches: f(column, bottom, top).
  /// Not to a column behind a wall (wall_top) higher than the sphere's centre, as seen from the
  /// column holding it: a grain on one side of a thin wall is not sand on the other.
  template <class F>
  void for_each_ray_hit(const Vec3& x, Real r, F&& f) const;

  // ---- state ----
  /// L: the top of each column's level (changes with the level; see above).
  const std::vector<Real>& terrain() const { return L_; }
  const TerrainColumns& solids() const { return solids_; }
  /// Hash of the solids' tops as the field was made (set_solids does not change it): what a
  /// restart checks the scene against.
  std::uint64_t initial_terrain_hash() const { return initial_terrain_hash_; }
  const std::vector<Real>& surface() const { return H_; }       ///< H
  const std::vector<Real>& static_top() const { return h_; }    ///< h
  const std::vector<Real>& rolling() const { return R_; }       ///< R = H - h
  const std::vector<Real>& slope() const { return theta_; }     ///< theta of h [rad]
  const std::vector<Real>& exchange_rate() const { return Gamma_; }  ///< Gamma [m/s]
  /// Per column: how long since grains last moved the pile there, up to close_after [s].
  const std::vector<Real>& rest() const { return rest_; }
  /// Per column: how much longer the layer of a flow that stopped keeps flowing_min (counts down
  /// from flowing_hold; 0 where nothing has flowed) [s].
  const std::vector<Real>& hold_left() const { return hold_left_; }
  /// A column at rest for close_after: its whole top is static (no R_min).
  bool closed(std::size_t c) const { return rest_[c] >= p_.close_after; }
  /// Closes column c now, as if at rest for close_after (a bed born at rest).
  void close(std::size_t c) {
    rest_[c] = p_.close_after;
    hold_left_[c] = 0;
  }
  /// Counts the changes of any column's level (L): what the static tops follow.
  std::uint64_t level_revision() const { return level_revision_; }
  /// The columns whose h or L changed since the last call (where static grains may have to
  /// wake), into `out`; `all` when any may have (a new field, new solids, a restore).
  void take_moved(std::vector<std::uint32_t>& out, bool& all);
  /// The columns the last exchange evaluated (for tests: the work of an update).
  std::size_t evaluated_columns() const { return evaluated_; }

  /// Volume of the static layer above the terrain [m^3].
  Real static_volume() const;
  /// Columns where there is sand (H above L).
  std::size_t sand_columns() const;

 private:
  /// H of column c with its sand resting on solid k (no higher than the solid above), from its
  /// hits [q0, q1) sorted by bottom.
  Real walk_up(std::size_t c, std::size_t k, Real static_top, std::uint32_t q0,
               std::uint32_t q1) const;
  /// h or L of column c changed: its neighbours' slopes did, and static grains there may wake.
  void moved(std::size_t c);
  /// Calls f(n) for each column n beside c on the grid (-x, +x, -y, +y).
  template <class F>
  void for_each_neighbour(std::size_t c, F&& f) const {
    const int i = static_cast<int>(c % p_.nx), j = static_cast<int>(c / p_.nx);
    const std::size_t nx = static_cast<std::size_t>(p_.nx);
    if (i > 0) f(c - 1);
    if (i + 1 < p_.nx) f(c + 1);
    if (j > 0) f(c - nx);
    if (j + 1 < p_.ny) f(c + nx);
  }
  /// Static sand standing steeper than theta_max above the sand beside it (a free face, found
  /// among `seeds` and their neighbours) fails with the wedge behind it: h falls to the theta_max
  /// slope from the face's foot (docs/physics.md, step 3 of the update).
  void hold_max_slope(const std::vector<std::uint32_t>& seeds);
  /// The highest top column c may have with its neighbours' heights z (a wall between standing
  /// in for a lower one): its upwind slope (as the exchange measures it) at theta_max; +infinity
  /// with no neighbour.
  Real max_slope_top(std::size_t c, const std::vector<Real>& z) const;
  /// Every column may have changed: the next update evaluates them all.
  void everything_changed();

  HeightFieldParams p_;
  // the angles' tangents, which the exchange and the free faces take at every column (computed
  // there, they were 0.7 % of a surface run's samples, all on one thread)
  Real tan_theta0_ = 0, tan_theta_max_ = 0;
  TerrainColumns solids_;
  std::uint64_t initial_terrain_hash_ = 0;
  std::vector<Real> L_, H_, h_, R_, theta_, Gamma_, rest_, hold_left_;
  std::uint64_t level_revision_ = 0;

  // what can change (see the top of the file)
  bool everything_ = true;  ///< the next update evaluates every column
  ColumnSet measured_;      ///< columns measure() computed H for, for the next exchange
  ColumnSet pending_;       ///< columns the next exchange evaluates besides those
  ColumnSet evaluate_;      ///< scratch of exchange(): the columns it evaluates
  ColumnSet flow_all_;      ///< scratch of exchange(flowing bytes)
  ColumnSet moved_;         ///< columns whose h or L changed since take_moved()
  bool moved_all_ = true;
  std::size_t evaluated_ = 0;
  std::vector<Real> h_new_;
  /// scratch of exchange(): per column evaluated, what follows for the sets
  enum Next : std::uint8_t { kSettled, kPending, kMoved };
  std::vector<Next> next_;
  std::vector<std::uint32_t> queue_;  ///< scratch of hold_max_slope()
  std::vector<std::uint8_t> faces_;   ///< scratch of hold_max_slope(): a seed's faces, one bit each

  // scratch of measure(): ray hits filed by column, for the columns hit only
  struct ColumnHit {
    std::uint32_t column;
    Real bottom, top;
    bool held;  ///< the grain is held on the pile (kHeldOnPile)
  };
  struct ThreadHits {
    std::vector<ColumnHit> hits;         ///< the thread's grains' hits, in grain order
    std::vector<std::uint32_t> columns;  ///< the columns they hit, as first met
    std::vector<std::uint32_t> at;       ///< per column: its count of hits, then where they go
  };
  std::vector<ThreadHits> thread_hits_;  ///< per thread
  static constexpr std::uint32_t kNoSlot = 0xffffffffu;
  std::vector<std::uint32_t> hit_slot_;     ///< per column: its place in hit_columns_, or kNoSlot
  std::vector<std::uint32_t> hit_columns_;  ///< the columns hit, as first met
  std::vector<std::uint32_t> hit_before_;   ///< the columns hit at the last measure
  std::vector<std::uint32_t> hit_start_;    ///< per column hit (+1): offsets into hits_
  std::vector<std::uint8_t> relevelled_;  ///< per measured column: its level changed
  struct Hit {
    Real bottom, top;
    bool held;
  };
  std::vector<Hit> hits_;
};

// ---------------------------------------------------------------------------------------------
template <class F>
void HeightField::for_each_ray_hit(const Vec3& x, Real r, F&& f) const {
  const Real w = 0.5 * p_.cell;  // ray radius
  const Real reach = r + w;
  const int i0 = static_cast<int>(std::floor((x.x - reach - p_.x0) / p_.cell));
  const int i1 = static_cast<int>(std::floor((x.x + reach - p_.x0) / p_.cell));
  const int j0 = static_cast<int>(std::floor((x.y - reach - p_.y0) / p_.cell));
  const int j1 = static_cast<int>(std::floor((x.y + reach - p_.y0) / p_.cell));
  // the column holding the centre, when there are walls to look across
  const Real fi = std::floor((x.x - p_.x0) / p_.cell), fj = std::floor((x.y - p_.y0) / p_.cell);
  const bool walls = !solids_.walls.empty() && fi >= 0 && fi < p_.nx && fj >= 0 && fj < p_.ny;
  const int own_i = walls ? static_cast<int>(fi) : 0, own_j = walls ? static_cast<int>(fj) : 0;
  for (int j = std::max(j0, 0); j <= std::min(j1, p_.ny - 1); ++j)
    for (int i = std::max(i0, 0); i <= std::min(i1, p_.nx - 1); ++i) {
      const Real dx = x.x - (p_.x0 + (i + 0.5) * p_.cell);
      const Real dy = x.y - (p_.y0 + (j + 0.5) * p_.cell);
      const Real rho = std::sqrt(dx * dx + dy * dy);
      if (rho >= reach) continue;
      if (walls && (i != own_i || j != own_j) && walled_off(own_i, own_j, i, j, x.z)) continue;
      const Real e = rho - w;  // horizontal distance from the ray's rim
      const Real half = e <= 0 ? r : std::sqrt(r * r - e * e);
      f(static_cast<std::size_t>(j) * p_.nx + i, x.z - half, x.z + half);
    }
}

}  // namespace sandflow
