#include "surface/height_field.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include <omp.h>

#include "core/error.hpp"
#include "core/hash.hpp"
#include "dem/neighbor_list.hpp"  // kParallelMinGrains

namespace sandflow {

TerrainColumns TerrainColumns::single(const std::vector<Real>& L) {
  TerrainColumns t;
  for (Real l : L) t.add_column({{-std::numeric_limits<Real>::infinity(), l}});
  return t;
}

void TerrainColumns::add_column(const std::vector<std::pair<Real, Real>>& intervals,
                                const std::vector<Wall>& edge_walls) {
  for (const auto& [b, t] : intervals) {
    bottom.push_back(b);
    top.push_back(t);
  }
  start.push_back(static_cast<std::uint32_t>(top.size()));
  walls.insert(walls.end(), edge_walls.begin(), edge_walls.end());
  wall_start.push_back(static_cast<std::uint32_t>(walls.size()));
}

namespace {

// The checks both constructors and set_solids make.
void check_terrain(const TerrainColumns& t, std::size_t columns) {
  if (t.columns() != columns || t.wall_start.size() != columns + 1)
    throw InputError("height field: the terrain must give one height per column");
  for (std::size_t c = 0; c < columns; ++c)
    if (t.start[c + 1] == t.start[c])
      throw InputError("height field: every column needs a solid below it");
}

}  // namespace

HeightField::HeightField(const HeightFieldParams& p, std::vector<Real> terrain)
    : HeightField(p, TerrainColumns::single(terrain)) {}

HeightField::HeightField(const HeightFieldParams& p, TerrainColumns terrain)
    : p_(p),
      tan_theta0_(std::tan(p.theta0)),
      tan_theta_max_(std::tan(p.theta_max)),
      solids_(std::move(terrain)) {
  if (p_.nx < 1 || p_.ny < 1 || !(p_.cell > 0))
    throw InputError("height field: the grid needs at least one column of positive width");
  check_terrain(solids_, columns());
  Hasher tops;
  for (Real t : solids_.top) tops.add(t);
  initial_terrain_hash_ = tops.value();
  L_.resize(columns());
  for (std::size_t c = 0; c < columns(); ++c)
    L_[c] = solids_.top[solids_.start[c + 1] - 1];  // the highest top, until sand says otherwise
  H_ = L_;
  h_ = L_;
  R_.assign(columns(), 0);
  theta_.assign(columns(), 0);
  Gamma_.assign(columns(), 0);
  // every column starts open (a bed born at rest closes its own: close())
  rest_.assign(columns(), 0);
  hold_left_.assign(columns(), 0);
  for (ColumnSet* set : {&measured_, &pending_, &evaluate_, &flow_all_, &moved_})
    set->resize(columns());
  hit_slot_.assign(columns(), kNoSlot);
  everything_changed();
}

void HeightField::everything_changed() {
  everything_ = true;
  moved_all_ = true;
  moved_.clear();
}

void HeightField::moved(std::size_t c) {
  if (!moved_all_) moved_.add(static_cast<std::uint32_t>(c));
  // its slope and its neighbours' (the exchange's upwind slopes reach one column)
  pending_.add(static_cast<std::uint32_t>(c));
  for_each_neighbour(c, [&](std::size_t n) { pending_.add(static_cast<std::uint32_t>(n)); });
}

void HeightField::take_moved(std::vector<std::uint32_t>& out, bool& all) {
  all = moved_all_;
  out = moved_.list();
  moved_.clear();
  moved_all_ = false;
}

void HeightField::set_solids(TerrainColumns terrain) {
  check_terrain(terrain, columns());
  solids_ = std::move(terrain);
  for (std::size_t c = 0; c < columns(); ++c) {
    const std::uint32_t k0 = solids_.start[c], k1 = solids_.start[c + 1];
    bool kept = false;
    Real below = -std::numeric_limits<Real>::infinity();
    for (std::uint32_t k = k0; k < k1; ++k) {
      kept = kept || solids_.top[k] == L_[c];
      if (solids_.top[k] <= L_[c]) below = std::max(below, solids_.top[k]);
    }
    if (kept) continue;
    L_[c] = std::isfinite(below) ? below : solids_.top[k1 - 1];
    H_[c] = h_[c] = L_[c];
    R_[c] = 0;
  }
  ++level_revision_;
  everything_changed();
}

std::int64_t HeightField::column_of(Real x, Real y) const {
  const Real fx = std::floor((x - p_.x0) / p_.cell), fy = std::floor((y - p_.y0) / p_.cell);
  if (!(fx >= 0 && fx < p_.nx && fy >= 0 && fy < p_.ny)) return -1;
  return static_cast<std::int64_t>(fy) * p_.nx + static_cast<std::int64_t>(fx);
}

Real HeightField::static_top_at(Real x, Real y) const {
  // bilinear between the four nearest column centres, clamped at the border
  const Real u = std::clamp((x - p_.x0) / p_.cell - 0.5, 0.0, static_cast<Real>(p_.nx - 1));
  const Real v = std::clamp((y - p_.y0) / p_.cell - 0.5, 0.0, static_cast<Real>(p_.ny - 1));
  const int i = std::min(static_cast<int>(u), std::max(p_.nx - 2, 0));
  const int j = std::min(static_cast<int>(v), std::max(p_.ny - 2, 0));
  const int i1 = std::min(i + 1, p_.nx - 1), j1 = std::min(j + 1, p_.ny - 1);
  const Real a = u - i, b = v - j;
  auto idx = [&](int ii, int jj) { return static_cast<std::size_t>(jj) * p_.nx + ii; };
  // across a step of the terrain or a wall, interpolation would put the static top halfway up
  // the wall, or carry one side's sand over to the other: there the grain's own column decides
  if (!smooth_square(i, j)) {
    const std::int64_t c = column_of(x, y);
    return c >= 0 ? h_[static_cast<std::size_t>(c)] : h_[idx(i, j)];
  }
  auto at = [&](int ii, int jj) { return h_[idx(ii, jj)]; };
  return (1 - b) * ((1 - a) * at(i, j) + a * at(i1, j)) + b * ((1 - a) * at(i, j1) + a * at(i1, j1));
}

bool HeightField::smooth_square(int i, int j) const {
  const int i1 = std::min(i + 1, p_.nx - 1), j1 = std::min(j + 1, p_.ny - 1);
  auto idx = [&](int ii, int jj) { return static_cast<std::size_t>(jj) * p_.nx + ii; };
  const std::size_t c00 = idx(i, j), c10 = idx(i1, j), c01 = idx(i, j1), c11 = idx(i1, j1);
  const Real l00 = L_[c00];
  const Real step =
      std::max({std::abs(L_[c10] - l00), std::abs(L_[c01] - l00), std::abs(L_[c11] - l00)});
  if (step > p_.cell) return false;
  constexpr Real kNone = -std::numeric_limits<Real>::infinity();
  auto wall = [&](std::size_t a, std::size_t b) { return a != b && wall_top(a, b) > kNone; };
  return !(wall(c00, c10) || wall(c00, c01) || wall(c10, c11) || wall(c01, c11));
}

bool HeightField::walled_off(int i0, int j0, int i1, int j1, Real z) const {
  auto at = [&](int i, int j) { return static_cast<std::size_t>(j) * p_.nx + i; };
  // each way steps from column to column; it is closed where an edge's wall stands above z
  auto closed_way = [&](bool x_first) {
    int i = i0, j = j0;
    while (i != i1 || j != j1) {
      const bool along_x = i != i1 && (x_first || j == j1);
      const int ni = along_x ? i + (i1 > i ? 1 : -1) : i, nj = along_x ? j : j + (j1 > j ? 1 : -1);
      if (wall_top(at(i, j), at(ni, nj)) > z) return true;
      i = ni, j = nj;
    }
    return false;
  };
  return closed_way(true) && closed_way(false);
}

void HeightField::measure(const Grains& hot, const std::vector<Real>& static_top,
                          const std::vector<std::uint8_t>& counts,
                          const std::vector<std::uint32_t>* changed_tops) {
  auto skip = [&](std::size_t i) { return !counts.empty() && !counts[i]; };
  // 1. every counted grain's ray hits: each thread lists those of its share of the grains, in
  // grain order, so the threads' lists joined in thread order are in grain order for any count
  // 2. filed by column (a counting sort over the columns hit, not the grid), as the lists joined
  // in thread order would be: the columns in the order first met, each column's hits thread by
  // thread. Each thread counts and files its own list; only the columns' offsets are one
  // thread's work (filed by one thread, the hits were 0.8 % of a surface run's wall time:
  // docs/performance.md, ninety-seventh)
  const std::size_t n = hot.size();
#pragma omp parallel if (n >= kParallelMinGrains)
  {
#pragma omp single
    thread_hits_.resize(static_cast<std::size_t>(omp_get_num_threads()));
    ThreadHits& mine = thread_hits_[static_cast<std::size_t>(omp_get_thread_num())];
    mine.hits.clear();
    mine.columns.clear();
    mine.at.resize(columns(), 0);
#pragma omp for schedule(static) nowait
    for (std::size_t i = 0; i < n; ++i)
      if (!skip(i))
        for_each_ray_hit(hot.x[i], hot.r[i], [&](std::size_t c, Real bottom, Real top) {
          mine.hits.push_back({static_cast<std::uint32_t>(c), bottom, top,
                               !counts.empty() && counts[i] == kHeldOnPile});
        });
    for (const ColumnHit& e : mine.hits)
      if (mine.at[e.column]++ == 0) mine.columns.push_back(e.column);
#pragma omp barrier
#pragma omp single
    {
      hit_columns_.clear();
      for (const ThreadHits& list : thread_hits_)
        for (const std::uint32_t c : list.columns)
          if (hit_slot_[c] == kNoSlot) {
            hit_slot_[c] = static_cast<std::uint32_t>(hit_columns_.size());
            hit_columns_.push_back(c);
          }
      // each thread's count of a column becomes where its first hit there goes
      hit_start_.resize(hit_columns_.size() + 1);
      std::uint32_t filed = 0;
      for (std::size_t k = 0; k < hit_columns_.size(); ++k) {
        hit_start_[k] = filed;
        for (ThreadHits& list : thread_hits_) {
          std::uint32_t& at = list.at[hit_columns_[k]];
          filed += std::exchange(at, filed);
        }
      }
      hit_start_.back() = filed;
      hits_.resize(filed);
    }
    for (const ColumnHit& e : mine.hits) hits_[mine.at[e.column]++] = {e.bottom, e.top, e.held};
    for (const std::uint32_t c : hit_columns_) mine.at[c] = 0;  // (zero for the next measure)
  }

  // 3. H where it can change: columns hit now or at the last measure, or whose static top changed
  // (added to those measured since the last exchange)
  if (everything_ || !changed_tops) {
    measured_.add_all();
  } else {
    measured_.add(hit_columns_);
    measured_.add(hit_before_);
    measured_.add(*changed_tops);
  }
  const std::vector<std::uint32_t>& walk = measured_.list();
  relevelled_.assign(walk.size(), 0);
  // (columns are independent: each thread walks its own)
#pragma omp parallel for schedule(dynamic, 256) if (hits_.size() >= 4096)
  for (std::size_t w = 0; w < walk.size(); ++w) {
    const std::size_t c = walk[w];
    const std::uint32_t slot = hit_slot_[c];
    const std::uint32_t q0 = slot == kNoSlot ? 0 : hit_start_[slot];
    const std::uint32_t q1 = slot == kNoSlot ? 0 : hit_start_[slot + 1];
    std::sort(hits_.begin() + q0, hits_.begin() + q1,
              [](const Hit& a, const Hit& b) { return a.bottom < b.bottom; });
    // the level: the highest solid with sand on it, else the highest solid
    const std::size_t k0 = solids_.start[c], k1 = solids_.start[c + 1];
    std::size_t level = k1 - 1;
    Real H = walk_up(c, level, static_top[c], q0, q1);
    for (std::size_t k = k1 - 1; k-- > k0 && !(H > solids_.top[level]);) {
      const Real Hk = walk_up(c, k, static_top[c], q0, q1);
      if (Hk > solids_.top[k]) level = k, H = Hk;
    }
    if (!(H > solids_.top[level])) level = k1 - 1, H = solids_.top[level];
    if (solids_.top[level] != L_[c]) {
      // a new level: its static layer starts empty
      L_[c] = solids_.top[level];
      h_[c] = L_[c];
      relevelled_[w] = 1;
    }
    H_[c] = H;
  }
  bool relevelled = false;
  for (std::size_t w = 0; w < walk.size(); ++w)
    if (relevelled_[w]) {
      relevelled = true;
      moved(walk[w]);
    }
  level_revision_ += relevelled;
  for (std::uint32_t c : hit_columns_) hit_slot_[c] = kNoSlot;
  hit_before_.swap(hit_columns_);
}

Real HeightField::walk_up(std::size_t c, std::size_t k, Real static_top, std::uint32_t q0,
                          std::uint32_t q1) const {
  Real top = std::max(solids_.top[k], static_top);
  const Real ceiling = k + 1 < solids_.start[c + 1] ? solids_.bottom[k + 1]
                                                    : std::numeric_limits<Real>::infinity();
  if (static_top >= ceiling) top = solids_.top[k];  // static grains of a higher level
  for (std::uint32_t q = q0; q < q1; ++q) {
    // hits below the solid's top are grains of a lower level: they raise nothing
    if (hits_[q].bottom >= ceiling) break;
    if (hits_[q].bottom > top + p_.gap && !hits_[q].held) continue;  // in flight
    top = std::max(top, hits_[q].top);
  }
  return std::min(top, ceiling);
}

void HeightField::set_surface(std::vector<Real> H) {
  if (H.size() != columns()) throw InputError("height field: H needs one height per column");
  for (std::size_t c = 0; c < H.size(); ++c) H_[c] = std::max(H[c], L_[c]);
  everything_changed();
}

void HeightField::set_static_top(std::vector<Real> h) {
  if (h.size() != columns()) throw InputError("height field: h needs one height per column");
  for (std::size_t c = 0; c < h.size(); ++c) {
    h_[c] = std::clamp(h[c], L_[c], std::max(H_[c], L_[c]));
    R_[c] = H_[c] - h_[c];
  }
  everything_changed();
}

void HeightField::restore(State s) {
  L_ = std::move(s.L);
  H_ = std::move(s.H);
  h_ = std::move(s.h);
  R_ = std::move(s.R);
  theta_ = std::move(s.theta);
  Gamma_ = std::move(s.Gamma);
  rest_ = std::move(s.rest);
  hold_left_ = std::move(s.hold);
  ++level_revision_;
  everything_changed();
}

void HeightField::exchange(Real dt, const std::vector<std::uint8_t>& flowing) {
  flow_all_.clear();
  for (std::size_t c = 0; c < columns(); ++c)
    if (flowing.empty() || flowing[c]) flow_all_.add(static_cast<std::uint32_t>(c));
  exchange(dt, flow_all_);
}

void HeightField::exchange(Real dt, const ColumnSet& flowing, const ColumnSet* eroding) {
  const int nx = p_.nx, ny = p_.ny;
  const Real dx = p_.cell;
  // the columns that can change (see the top of the file)
  evaluate_.clear();
  if (everything_) {
    evaluate_.add_all();
  } else {
    evaluate_.add(measured_.list());
    evaluate_.add(pending_.list());
    evaluate_.add(flowing.list());
  }
  measured_.clear();
  pending_.clear();
  everything_ = false;
  const std::vector<std::uint32_t>& todo = evaluate_.list();
  evaluated_ = todo.size();
  // the fall of the static top h over the edge from column c to its neighbour n (MAC), where a
  // wall between stands in for a lower neighbour
  auto fall = [&](std::size_t c, std::size_t n) { return (h_[c] - top_across(c, n, h_)) / dx; };
  const std::size_t row = static_cast<std::size_t>(nx);
  h_new_.resize(todo.size());
  // (each column's new top from the old tops around it: the threads take shares of the columns)
#pragma omp parallel for schedule(static) if (todo.size() >= 1024)
  for (std::size_t w = 0; w < todo.size(); ++w) {
    const std::size_t c = todo[w];
    const int i = static_cast<int>(c % nx), j = static_cast<int>(c / nx);
    // the column's slope, downhill from it: on each axis the steeper of its two edges where h
    // falls away from the column (upwind). A peak then sees its full slope and erodes, a pit
    // sees none and fills, so no checkerboard can hide from the exchange as it would from a
    // central difference; on a plane it is the exact gradient.
    Real gx = 0, gy = 0;
    if (i > 0) gx = std::max(gx, fall(c, c - 1));
    if (i + 1 < nx) gx = std::max(gx, fall(c, c + 1));
    if (j > 0) gy = std::max(gy, fall(c, c - row));
    if (j + 1 < ny) gy = std::max(gy, fall(c, c + row));
    const Real tan_theta = std::sqrt(gx * gx + gy * gy);
    const Real theta = std::atan(tan_theta);
    theta_[c] = theta;

    const Real R = std::max(H_[c] - h_[c], 0.0);
    Real dh = 0;
    if (H_[c] > L_[c]) {
      // BCRE exchange dR/dt = gamma R (theta - theta_c), integrated exactly over dt with the
      // slope held: stable for any dt, and a deposit never takes more than R. theta_c is
      // theta0 under a flowing layer and theta_max under one at rest: grains that stopped on
      // a slope between the two stay there in DEM, so they join the static layer.
      const bool flows = flowing.contains(c);
      const Real theta_c = flows ? p_.theta0 : p_.theta_max;
      const Real tan_c = flows ? tan_theta0_ : tan_theta_max_;
      dh = -R * std::expm1(p_.gamma * (theta - theta_c) * dt);
      // a deposit stops where the column's own downhill slope would pass theta_c: otherwise it
      // builds a step that the next update erodes again, and the grains on it flip between
      // trapped and dislodged at every update
      if (dh > 0) {
        const Real cap = 0.5 * dx * std::max(tan_c - tan_theta, 0.0);
        dh = std::min(dh, cap);
        // the exchange's deposit takes a fraction of R at each update, never all of it: what it
        // would leave thinner than a thousandth of a column (a fraction of a grain's rounding in
        // the static store) goes all the way, so that a column at rest stops changing and its
        // updates stop (docs/design.md §4, "Only what can change")
        if (R - dh < 1e-3 * dx && R <= cap) dh = R;
      }
      // a flow that does not reach the static top (grains moving over grains at rest) does not
      // dig it
      if (dh < 0 && flows && eroding && !eroding->contains(c)) dh = 0;
      // an avalanche: a static slope above theta_max erodes even with no rolling layer
      if (theta > p_.theta_max) dh -= p_.gamma * p_.avalanche_depth * (theta - p_.theta_max) * dt;
      // erosion stops where the slope would fall below theta0 (no overshoot between updates)
      if (dh < 0) dh = std::max(dh, -0.5 * dx * std::max(tan_theta - tan_theta0_, 0.0));
    }
    h_new_[w] = std::max(h_[c] + dh, L_[c]);  // erosion never digs below the terrain
    Gamma_[c] = -(h_new_[w] - h_[c]) / dt;
  }
  const Real flowing_min = p_.flowing_floor();
  // a layer that stopped flowing keeps its depth while DEM brings it to rest (flowing_hold)
  const Real hold = p_.hold_time();
  // (each column from its own values: the threads take shares; the sets then take the columns
  // in the order of the list)
  next_.resize(todo.size());
#pragma omp parallel for schedule(static) if (todo.size() >= 1024)
  for (std::size_t w = 0; w < todo.size(); ++w) {
    const std::size_t c = todo[w];
    // R_min: the visible surface is made of grains that can move, until the column has been at
    // rest for close_after (then nothing there moves: its top joins the static layer). Where grains
    // flow, DEM shears a layer several grains deep (docs/physics.md, "The flowing layer"): a static
    // top one grain below the surface would hold up grains that DEM lets slide, and the heap grows
    // steep.
    const bool flows = flowing.contains(c);
    rest_[c] = flows ? 0 : std::min(rest_[c] + dt, p_.close_after);
    hold_left_[c] = flows ? hold : std::max(hold_left_[c] - dt, 0.0);
    const Real r_min = flows || hold_left_[c] > 0 ? flowing_min : closed(c) ? 0 : p_.rolling_min;
    const Real h = std::max(std::min(h_new_[w], H_[c] - r_min), L_[c]);
    const bool changed = h != h_[c];
    h_[c] = h;
    R_[c] = H_[c] - h_[c];
    // (an open column counts its rest; a changed one, and its neighbours, may change again)
    next_[w] = changed ? kMoved : !closed(c) || flows ? kPending : kSettled;
  }
  for (std::size_t w = 0; w < todo.size(); ++w) {
    if (next_[w] == kMoved)
      moved(todo[w]);
    else if (next_[w] == kPending)
      pending_.add(todo[w]);
  }
  // a free face steeper than theta_max fails at once, with the wedge behind it: the avalanche's
  // rate alone held a lifted tube's sand up as a wall while it eroded; how fast the released
  // grains fall is the DEM's
  hold_max_slope(todo);
}

Real HeightField::max_slope_top(std::size_t c, const std::vector<Real>& z) const {
  constexpr Real kNone = std::numeric_limits<Real>::infinity();
  const int i = static_cast<int>(c % p_.nx), j = static_cast<int>(c / p_.nx);
  // the lower neighbour on each axis: the exchange's upwind slope is measured towards it
  auto across = [&](std::size_t n) { return top_across(c, n, z); };
  const Real a = std::min(i > 0 ? across(c - 1) : kNone, i + 1 < p_.nx ? across(c + 1) : kNone);
  const Real b =
      std::min(j > 0 ? across(c - p_.nx) : kNone, j + 1 < p_.ny ? across(c + p_.nx) : kNone);
  const Real s = p_.cell * tan_theta_max_;
  // the h at which (h - a)^2 + (h - b)^2 = s^2 (each term only where h is above it)
  if (std::abs(a - b) >= s || !std::isfinite(a) || !std::isfinite(b)) return std::min(a, b) + s;
  return 0.5 * (a + b + std::sqrt(2 * s * s - (a - b) * (a - b)));
}

void HeightField::hold_max_slope(const std::vector<std::uint32_t>& seeds) {
  const Real tol = 1e-9 * p_.cell;  // (rounding must not keep the sweep going)
  // 1. free faces: static sand standing steeper than theta_max above the sand beside it (H: the
  // grains there, moving or not, buttress it; under an impact's pit they still do)
  // (each seed's five tests on the threads, one bit each; the queue is then filled in seed order)
  queue_.clear();
  auto face = [&](std::size_t c) { return h_[c] > max_slope_top(c, H_) + tol; };
  faces_.resize(seeds.size());
#pragma omp parallel for schedule(static) if (seeds.size() >= 1024)
  for (std::size_t w = 0; w < seeds.size(); ++w) {
    std::uint8_t bits = face(seeds[w]), bit = 2;
    for_each_neighbour(seeds[w], [&](std::size_t n) {
      if (face(n)) bits |= bit;
      bit <<= 1;
    });
    faces_[w] = bits;
  }
  for (std::size_t w = 0; w < seeds.size(); ++w) {
    if (!faces_[w]) continue;
    if (faces_[w] & 1) queue_.push_back(seeds[w]);
    std::uint8_t bit = 2;
    for_each_neighbour(seeds[w], [&](std::size_t n) {
      if (faces_[w] & bit) queue_.push_back(static_cast<std::uint32_t>(n));
      bit <<= 1;
    });
  }
  // 2. the wedge behind each face fails with it: a label-correcting sweep of the static top to
  // the theta_max slope from the face's foot (h only falls, never below L, so it ends)
  for (std::size_t q = 0; q < queue_.size(); ++q) {
    const std::size_t c = queue_[q];
    const Real h = std::max(std::min(h_[c], max_slope_top(c, h_)), L_[c]);
    if (!(h < h_[c] - tol)) continue;
    h_[c] = h;
    R_[c] = H_[c] - h_[c];
    moved(c);
    for_each_neighbour(c, [&](std::size_t n) { queue_.push_back(static_cast<std::uint32_t>(n)); });
  }
}

Real HeightField::static_volume() const {
  Real v = 0;
  for (std::size_t c = 0; c < h_.size(); ++c) v += h_[c] - L_[c];
  return v * p_.cell * p_.cell;
}

std::size_t HeightField::sand_columns() const {
  std::size_t n = 0;
  for (std::size_t c = 0; c < H_.size(); ++c) n += H_[c] > L_[c];
  return n;
}

}  // namespace sandflow
