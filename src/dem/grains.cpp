#include "dem/grains.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <stdexcept>
#include <utility>

#include <fmt/format.h>

#include "core/error.hpp"
#include "dem/neighbor_list.hpp"  // kParallelMinGrains

namespace sandflow {

void Grains::add(GrainId gid, const Vec3& pos, const Vec3& vel, Real radius, Real density) {
  const Real mass = density * (4.0 / 3.0) * kPi * radius * radius * radius;
  id.push_back(gid);
  state.push_back(GrainState::Active);
  x.push_back(pos);
  v.push_back(vel);
  w.push_back({});
  r.push_back(radius);
  m.push_back(mass);
  inv_m.push_back(1.0 / mass);
  inv_I.push_back(1.0 / (0.4 * mass * radius * radius));
}

namespace {
template <class T>
void apply_permutation(std::vector<T>& a, std::span<const std::uint32_t> perm) {
  std::vector<T> out(perm.size());
  for (std::size_t k = 0; k < perm.size(); ++k) out[k] = a[perm[k]];
  a = std::move(out);
}

/// The grains `keep` names (ascending), moved down in place: keep[k] >= k, so nothing is
/// overwritten before it is read, and no array is allocated and filled anew.
template <class T>
void keep_in_place(std::vector<T>& a, std::span<const std::uint32_t> keep) {
  for (std::size_t k = 0; k < keep.size(); ++k)
    if (keep[k] != k) a[k] = a[keep[k]];
  a.resize(keep.size());
}
}  // namespace

void Grains::permute(std::span<const std::uint32_t> perm) {
  // the arrays are independent: the threads take them (the largest first), a copy each; on one
  // thread the compaction of a surface run's hot grains was 0.6 % of its wall time
  // (docs/performance.md, ninety-seventh)
  auto each = [this, n = perm.size()](auto&& f) {
    const std::array<std::function<void()>, 9> jobs{
        [&] { f(x); },     [&] { f(v); },     [&] { f(w); },  [&] { f(r); },    [&] { f(m); },
        [&] { f(inv_m); }, [&] { f(inv_I); }, [&] { f(id); }, [&] { f(state); }};
#pragma omp parallel for schedule(dynamic, 1) if (n >= kParallelMinGrains)
    for (std::size_t k = 0; k < jobs.size(); ++k) jobs[k]();
  };
  // (a surface run drops the grains that fell asleep at most transfers: a compaction)
  if (std::adjacent_find(perm.begin(), perm.end(), std::greater_equal<>()) == perm.end())
    each([perm](auto& a) { keep_in_place(a, perm); });
  else
    each([perm](auto& a) { apply_permutation(a, perm); });
}

// ---- StaticStore
// ---------------------------------------------------------------------------------

namespace {
/// Gives v exactly this capacity (at least its size), keeping its contents: reserve() only grows.
template <class T>
void set_capacity(std::vector<T>& v, std::size_t capacity) {
  std::vector<T> w;
  w.reserve(capacity);
  w.assign(v.begin(), v.end());
  v.swap(w);
}

// x and y in cells of their column, over [-kMargin, 1 + kMargin]
constexpr Real kMargin = StaticStore::kMargin;
constexpr std::uint64_t kXMax = (1u << StaticStore::kXBits) - 1;
constexpr std::uint64_t kYMax = (1u << StaticStore::kYBits) - 1;
constexpr std::uint64_t kZMax = (1u << StaticStore::kZBits) - 1;
constexpr std::uint64_t kRMax = (1u << StaticStore::kRBits) - 1;
constexpr int kRShift = 0, kYShift = StaticStore::kRBits, kXShift = kYShift + StaticStore::kYBits,
              kZShift = kXShift + StaticStore::kXBits;
static_assert(kZShift + StaticStore::kZBits == 64, "the code's fields fill 64 bits");

std::uint64_t z_of(std::uint64_t code) {
  return code >> kZShift;
}
// a column's grains ascend in (z, id)
bool below(std::uint64_t code_a, GrainId a, std::uint64_t code_b, GrainId b) {
  return z_of(code_a) < z_of(code_b) || (z_of(code_a) == z_of(code_b) && a < b);
}
Real step_u() {
  return (1 + 2 * kMargin) / static_cast<Real>(kXMax);
}
}  // namespace

std::string StaticFrame::error() const {
  for (Real v : {x0, y0, cell, z_lo, z_hi, r_lo, r_hi})
    if (!std::isfinite(v)) return "a bound of the static store's frame is not finite";
  if (!(cell > 0)) return fmt::format("the columns are {} m wide", cell);
  if (nx == 0 || ny == 0 || columns() >= (std::size_t{1} << 31))
    return fmt::format("{} x {} columns", nx, ny);
  if (!(z_lo < z_hi)) return fmt::format("the heights [{}, {}] m are empty", z_lo, z_hi);
  if (!(r_lo > 0 && r_lo <= r_hi)) return fmt::format("the radii [{}, {}] m", r_lo, r_hi);
  return {};
}

Real StaticFrame::position_error() const {
  const Real ex = 0.5 * cell * step_u(), ez = 0.5 * (z_hi - z_lo) / static_cast<Real>(kZMax);
  return std::sqrt(2 * ex * ex + ez * ez);
}

Real StaticFrame::radius_error() const {
  return 0.5 * (r_hi - r_lo) / static_cast<Real>(kRMax);
}

StaticStore::StaticStore(const StaticFrame& frame) : f_(frame) {
  if (const std::string e = f_.error(); !e.empty())
    throw std::invalid_argument("StaticStore: " + e);
  step_u_ = step_u();
  step_z_ = (f_.z_hi - f_.z_lo) / static_cast<Real>(kZMax);
  step_r_ = (f_.r_hi - f_.r_lo) / static_cast<Real>(kRMax);
  start_.assign(f_.columns() + 1, 0);
  tail_last_.assign(f_.columns(), kNone);
  fit_capacity(0);
}

std::uint32_t StaticStore::tail_limit(std::uint32_t main) {
  return std::max(kTailMin, main / kTailDivisor);
}

void StaticStore::fit_capacity(std::uint32_t main) {
  // room for one to four tails: set to three when outside (growing, or after many woke)
  tail_max_ = tail_limit(main);
  const std::size_t lo = std::size_t{main} + tail_max_, hi = std::size_t{main} + 4 * tail_max_;
  if (code_.capacity() < lo || code_.capacity() > hi) {
    const std::size_t room = std::size_t{main} + 3 * tail_max_;
    set_capacity(id_, room);
    set_capacity(code_, room);
  }
  if (tail_column_.capacity() != tail_max_) {
    set_capacity(tail_column_, tail_max_);
    set_capacity(tail_next_, tail_max_);
  }
}

std::uint64_t StaticStore::encode(GrainId gid, const Vec3& pos, Real radius,
                                  std::uint32_t col) const {
  if (start_.empty())
    throw std::invalid_argument("StaticStore::add: the store has no frame (plain DEM mode)");
  if (col >= f_.columns())
    throw std::invalid_argument(
        fmt::format("StaticStore::add: grain {} filed in column {} of {}", gid, col, f_.columns()));
  if (gid == kNoGrain) throw std::invalid_argument("StaticStore::add: grain id 2^32 - 1");
  // x and y in cells from the column's corner, z and r over the frame's ranges
  const Real u = (pos.x - f_.x0) / f_.cell - static_cast<Real>(col % f_.nx);
  const Real v = (pos.y - f_.y0) / f_.cell - static_cast<Real>(col / f_.nx);
  if (!(u >= -kMargin && u <= 1 + kMargin && v >= -kMargin && v <= 1 + kMargin))
    throw std::invalid_argument(
        fmt::format("StaticStore::add: grain {} at ({}, {}) m lies outside column {} ({}, {})", gid,
                    pos.x, pos.y, col, col % f_.nx, col / f_.nx));
  const Real w = (pos.z - f_.z_lo) / (f_.z_hi - f_.z_lo);
  if (!(w >= 0 && w <= 1))
    throw SimulationError(fmt::format(
        "grain {} would become STATIC at z = {:.6g} m, outside the heights the static layer "
        "holds, [{:.6g}, {:.6g}] m (simulation.domain widened by its height)",
        gid, pos.z, f_.z_lo, f_.z_hi));
  // (a radius drawn at the end of its range may round past it by an ulp)
  const Real span = f_.r_hi - f_.r_lo;
  const Real s = span > 0 ? (radius - f_.r_lo) / span : 0.0;
  if (!(std::abs(radius - std::clamp(radius, f_.r_lo, f_.r_hi)) <= 1e-9 * f_.r_hi))
    throw std::invalid_argument(
        fmt::format("StaticStore::add: grain {} has radius {} m, outside [{}, {}] m", gid, radius,
                    f_.r_lo, f_.r_hi));
  auto q = [](Real t, std::uint64_t max) {
    return static_cast<std::uint64_t>(
        std::clamp(std::nearbyint(t * static_cast<Real>(max)), 0.0, static_cast<Real>(max)));
  };
  return q(w, kZMax) << kZShift | q((u + kMargin) / (1 + 2 * kMargin), kXMax) << kXShift |
         q((v + kMargin) / (1 + 2 * kMargin), kYMax) << kYShift | q(s, kRMax) << kRShift;
}

Vec3 StaticStore::decode_x(std::uint64_t code, std::uint32_t col) const {
  const Real u = static_cast<Real>((code >> kXShift) & kXMax) * step_u_ - kMargin;
  const Real v = static_cast<Real>((code >> kYShift) & kYMax) * step_u_ - kMargin;
  return {f_.x0 + f_.cell * (static_cast<Real>(col % f_.nx) + u),
          f_.y0 + f_.cell * (static_cast<Real>(col / f_.nx) + v), decode_z(code)};
}

std::uint32_t StaticStore::column(std::uint32_t k) const {
  if (k >= main_) return tail_column_[k - main_];
  // the last column whose main body starts at or before k (empty columns share its start)
  const auto it = std::upper_bound(start_.begin(), start_.end(), k);
  return static_cast<std::uint32_t>(it - start_.begin() - 1);
}

std::uint32_t StaticStore::add(GrainId gid, const Vec3& pos, Real radius, std::uint32_t col) {
  const std::uint64_t code = encode(gid, pos, radius, col);
  if (id_.size() >= std::size_t{0xfffffff0u})
    throw SimulationError("the static store holds 2^32 slots");
  // merge first when this grain would fill the tail: the tail + empty slots stay below tail_max_
  if (tail_column_.size() + empty_ + 1 >= tail_max_) merge();
  const auto t = static_cast<std::uint32_t>(tail_column_.size());
  id_.push_back(gid);
  code_.push_back(code);
  tail_column_.push_back(col);
  tail_next_.push_back(tail_last_[col]);
  tail_last_[col] = t;
  ++live_;
  ++revision_;
  changed(col);
  return main_ + t;
}

void StaticStore::changed(std::uint32_t c) {
  if (all_changed_) return;
  // (bounded: past one change per column, "any may have" costs no more to follow)
  if (changed_.size() >= f_.columns()) {
    changed_.clear();
    all_changed_ = true;
    return;
  }
  changed_.push_back(c);
}

void StaticStore::remove(std::span<const std::uint32_t> slots) {
  ++revision_;
  for (std::uint32_t k : slots) {
    if (!holds(k))
      throw std::invalid_argument(fmt::format("StaticStore::remove: slot {} holds no grain", k));
    if (!all_changed_) changed(column(k));
    id_[k] = kNoGrain;
    --live_;
    ++empty_;
  }
  if (tail_column_.size() + empty_ >= tail_max_) merge();
}

void StaticStore::merge() {
  const std::size_t nc = f_.columns();
  // 1. the tail's grains, out of the arrays, by column, then height, then id
  struct Entry {
    std::uint64_t code;
    GrainId id;
    std::uint32_t column;
  };
  std::vector<Entry> tail;
  tail.reserve(tail_column_.size());
  for (std::uint32_t t = 0; t < tail_column_.size(); ++t)
    if (id_[main_ + t] != kNoGrain)
      tail.push_back({code_[main_ + t], id_[main_ + t], tail_column_[t]});
  std::sort(tail.begin(), tail.end(), [](const Entry& a, const Entry& b) {
    return a.column != b.column ? a.column < b.column : below(a.code, a.id, b.code, b.id);
  });
  // 2. the main body without its empty slots, in place; start_ becomes its offsets
  std::uint32_t w = 0;
  for (std::size_t c = 0; c < nc; ++c) {
    const std::uint32_t begin = start_[c], end = start_[c + 1];
    start_[c] = w;
    for (std::uint32_t q = begin; q < end; ++q)
      if (id_[q] != kNoGrain) {
        id_[w] = id_[q];
        code_[w] = code_[q];
        ++w;
      }
  }
  start_[nc] = w;
  // 3. the tail merged in, from the back: a column's grains move up by the tail grains of the
  // columns before it, so nothing is overwritten before it is read
  const auto total = static_cast<std::uint32_t>(w + tail.size());
  id_.resize(total);  // (never larger than it was: no reallocation)
  code_.resize(total);
  std::size_t a = tail.size();
  std::uint32_t out = total;
  for (std::size_t c = nc; c-- > 0;) {
    const std::uint32_t begin = start_[c];
    std::uint32_t q = start_[c + 1];
    start_[c + 1] = out;
    while (q > begin || (a > 0 && tail[a - 1].column == c)) {
      const bool from_tail =
          a > 0 && tail[a - 1].column == c &&
          (q == begin || below(code_[q - 1], id_[q - 1], tail[a - 1].code, tail[a - 1].id));
      --out;
      if (from_tail) {
        --a;
        id_[out] = tail[a].id;
        code_[out] = tail[a].code;
      } else {
        --q;
        id_[out] = id_[q];
        code_[out] = code_[q];
      }
    }
  }
  start_[0] = 0;
  main_ = total;
  empty_ = 0;
  tail_column_.clear();
  tail_next_.clear();
  std::fill(tail_last_.begin(), tail_last_.end(), kNone);
  fit_capacity(main_);
  ++revision_;
}

std::size_t StaticStore::allocated_bytes() const {
  return id_.capacity() * sizeof(GrainId) + code_.capacity() * sizeof(std::uint64_t) +
         (start_.capacity() + tail_column_.capacity() + tail_next_.capacity() +
          tail_last_.capacity()) *
             sizeof(std::uint32_t);
}

std::string StaticStore::check() const {
  if (start_.empty()) {
    if (!id_.empty() || live_ != 0) return "an unconfigured static store holds grains";
    return {};
  }
  const std::size_t nc = f_.columns(), tail = tail_column_.size();
  if (start_.size() != nc + 1 || tail_last_.size() != nc)
    return fmt::format("the static store's column arrays have {} and {} entries for {} columns",
                       start_.size(), tail_last_.size(), nc);
  if (code_.size() != id_.size() || tail_next_.size() != tail || main_ + tail != id_.size())
    return fmt::format(
        "the static store's arrays differ in length ({} ids, {} codes, main {}, "
        "tail {} and {})",
        id_.size(), code_.size(), main_, tail, tail_next_.size());
  if (start_[0] != 0 || start_[nc] != main_) return "the static store's offsets do not span it";
  for (std::size_t c = 0; c < nc; ++c) {
    if (start_[c + 1] < start_[c]) return fmt::format("column {} ends before it starts", c);
    for (std::uint32_t q = start_[c] + 1; q < start_[c + 1]; ++q)
      if (z_of(code_[q]) < z_of(code_[q - 1]))
        return fmt::format("column {}'s grains do not ascend in height (slot {})", c, q);
  }
  // each tail slot on its column's list, once
  std::size_t linked = 0;
  for (std::size_t c = 0; c < nc; ++c)
    for (std::uint32_t t = tail_last_[c]; t != kNone; t = tail_next_[t]) {
      if (t >= tail || tail_column_[t] != c || ++linked > tail)
        return fmt::format("the tail list of column {} is broken", c);
    }
  if (linked != tail)
    return fmt::format("{} of {} tail slots are on their column's list", linked, tail);
  std::size_t empty = 0;
  for (GrainId id : id_) empty += id == kNoGrain;
  if (empty != empty_ || live_ + empty_ != id_.size())
    return fmt::format("the static store counts {} grains and {} empty slots, it has {} and {}",
                       live_, empty_, id_.size() - empty, empty);
  if (tail_max_ != tail_limit(main_) || tail + empty_ >= tail_max_)
    return fmt::format("the static store's tail ({} + {} empty) has outgrown its limit {}", tail,
                       empty_, tail_max_);
  if (code_.capacity() < std::size_t{main_} + tail_max_ ||
      code_.capacity() > std::size_t{main_} + 4 * std::size_t{tail_max_})
    return fmt::format("the static store has room for {} slots, with {} in its main body",
                       code_.capacity(), main_);
  return {};
}

StaticStore::State StaticStore::save_state() const {
  State s;
  if (start_.empty()) return s;
  s.column_slots.resize(f_.columns());
  for (std::size_t c = 0; c < s.column_slots.size(); ++c)
    s.column_slots[c] = start_[c + 1] - start_[c];
  s.id = id_;
  s.code = code_;
  s.tail_column = tail_column_;
  s.capacity = code_.capacity();
  return s;
}

std::string StaticStore::state_error(const State& s) const {
  const std::size_t nc = start_.empty() ? 0 : f_.columns();
  if (s.column_slots.size() != nc)
    return fmt::format("{} columns of static grains, the grid has {}", s.column_slots.size(), nc);
  if (s.code.size() != s.id.size())
    return fmt::format("{} static grain ids and {} codes", s.id.size(), s.code.size());
  std::uint64_t main = 0;
  for (std::uint32_t n : s.column_slots) main += n;
  if (main + s.tail_column.size() != s.id.size())
    return fmt::format("{} static slots in the columns and {} in the tail, but {} ids", main,
                       s.tail_column.size(), s.id.size());
  if (nc == 0) return s.id.empty() ? "" : "static grains, but no height field to file them";
  if (s.id.size() >= 0xfffffff0u) return "too many static slots";
  std::uint64_t q = 0;
  for (std::size_t c = 0; c < nc; ++c) {
    for (std::uint32_t k = 1; k < s.column_slots[c]; ++k)
      if (z_of(s.code[q + k]) < z_of(s.code[q + k - 1]))
        return fmt::format("the static grains of column {} do not ascend in height", c);
    q += s.column_slots[c];
  }
  for (std::uint32_t col : s.tail_column)
    if (col >= nc) return fmt::format("a static grain is filed in column {} of {}", col, nc);
  std::size_t empty = 0;
  for (GrainId id : s.id) empty += id == kNoGrain;
  const std::uint64_t limit = tail_limit(static_cast<std::uint32_t>(main));
  if (s.tail_column.size() + empty >= limit)
    return fmt::format("{} static grains in the tail and {} empty slots: a merge was due at {}",
                       s.tail_column.size(), empty, limit);
  if (s.capacity < main + limit || s.capacity > main + 4 * limit)
    return fmt::format("room for {} static slots with {} in the main body", s.capacity, main);
  return {};
}

void StaticStore::restore(State s) {
  if (const std::string e = state_error(s); !e.empty())
    throw std::invalid_argument("StaticStore::restore: " + e);
  if (start_.empty()) return;  // (an empty state of a store without a frame)
  const std::size_t nc = f_.columns();
  main_ = static_cast<std::uint32_t>(s.id.size() - s.tail_column.size());
  tail_max_ = tail_limit(main_);
  for (std::size_t c = 0; c < nc; ++c) start_[c + 1] = start_[c] + s.column_slots[c];
  id_.clear();
  code_.clear();
  id_.shrink_to_fit();
  code_.shrink_to_fit();
  id_.reserve(s.capacity);
  code_.reserve(s.capacity);
  id_.assign(s.id.begin(), s.id.end());
  code_.assign(s.code.begin(), s.code.end());
  tail_column_.clear();
  tail_next_.clear();
  tail_column_.shrink_to_fit();
  tail_next_.shrink_to_fit();
  tail_column_.reserve(tail_max_);
  tail_next_.reserve(tail_max_);
  std::fill(tail_last_.begin(), tail_last_.end(), kNone);
  // the tail's lists, as add() linked them
  for (std::uint32_t t = 0; t < s.tail_column.size(); ++t) {
    const std::uint32_t col = s.tail_column[t];
    tail_column_.push_back(col);
    tail_next_.push_back(tail_last_[col]);
    tail_last_[col] = t;
  }
  empty_ = 0;
  for (GrainId id : id_) empty_ += id == kNoGrain;
  live_ = id_.size() - empty_;
  ++revision_;
  changed_.clear();
  all_changed_ = true;
}

std::string store_error(const Grains& hot, const StaticStore& statics, GrainId next_id,
                        std::int64_t expected) {
  const std::size_t n = hot.size(), ns = statics.size();
  for (std::size_t size : {hot.state.size(), hot.x.size(), hot.v.size(), hot.w.size(), hot.r.size(),
                           hot.m.size(), hot.inv_m.size(), hot.inv_I.size()})
    if (size != n)
      return fmt::format("the hot store's arrays differ in length ({} ids, {})", n, size);
  if (const std::string e = statics.check(); !e.empty()) return e;
  std::vector<std::uint8_t> held(next_id, 0);  // 1: hot, 2: static
  for (std::size_t i = 0; i < n; ++i) {
    const GrainId id = hot.id[i];
    if (hot.state[i] == GrainState::Static)
      return fmt::format("grain {} is STATIC but in the hot store (slot {})", id, i);
    if (id >= next_id) return fmt::format("grain {} in the hot store: ids end at {}", id, next_id);
    if (held[id]) return fmt::format("grain {} is twice in the hot store", id);
    held[id] = 1;
  }
  std::string fault;
  statics.for_each([&](const StaticGrain& g) {
    if (!fault.empty()) return;
    if (g.id >= next_id)
      fault = fmt::format("grain {} in the static store: ids end at {}", g.id, next_id);
    else if (held[g.id])
      fault = fmt::format("grain {} is in the static store and {}", g.id,
                          held[g.id] == 1 ? "in the hot store" : "twice in it");
    else
      held[g.id] = 2;
  });
  if (!fault.empty()) return fault;
  if (static_cast<std::int64_t>(n + ns) != expected)
    return fmt::format("{} ACTIVE and INTERFACE grains and {} STATIC ones are {}, not {}", n, ns,
                       n + ns, expected);
  return {};
}

}  // namespace sandflow
