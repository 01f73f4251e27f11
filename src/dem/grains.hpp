// Grains in the three states of docs/design.md §2, stored as structure of arrays.
//
// The hot store holds the grains that take part in DEM: ACTIVE ones (integrated) and INTERFACE
// ones (fixed, but they push). Each property is one contiguous array, indexed by a slot that
// changes when grains are re-sorted by cell; `id` is the stable identity of a grain.
//
// STATIC grains live in a separate cold store, StaticStore, which is most of a large bed: a
// static grain costs 12 bytes there, and at most 16 with everything the store allocates.
//
//   - id: 4 bytes (ids are handed out in order and never reused, so they are kept as they are).
//   - centre and radius: one 64-bit code. x and y are quantised inside the grain's own column
//     (14 bits each over the cell widened by a 16th on each side, for grains on its edges), z
//     over the frame's heights (26 bits: the simulation domain widened by its height on either
//     side), the radius over the material's radii [d(1-s)/2, d(1+s)/2] (10 bits). z sits in the
//     high bits. At the scenes' sizes (1 cm grains, 1 cm columns, a domain a few metres tall)
//     the centre comes back within 5e-5 of a diameter and the radius within 5e-5 (spread 0.1);
//     World refuses a scene whose frame would give more than 0.1 % of the smallest diameter.
//     Decoding is a fixed sequence of operations on the code, so a grain that sleeps and wakes
//     comes back at the same place in every run, thread count and restart.
//   - column: implicit. The main body is kept in column order, each column's grains ascending in
//     (z, id), with one offset per column: the query "the grains of column c between two heights"
//     (the invariant of the layers, StaticReach) is a binary search.
//   - grains that fall asleep go to a tail at the end of the same arrays (spare capacity of the
//     main body), which carries its column (4 bytes) and a link to the column's previous tail
//     grain (4 bytes) with a per-column head, so a column's tail is found without a search.
//     Waking marks a slot empty (id kNoGrain, the code kept so heights still ascend). When the
//     tail and the empty slots reach a 32nd of the main body (at least 256), a merge sorts the
//     tail, drops the empty slots and merges both in place, from the back: O(n) every n/32
//     changes, amortised O(1) per sleep or wake and never a pass per step.
//   - capacity: the main arrays keep room for the tail (between 1 and 4 tails' worth, set to 3
//     at a merge that finds it outside), so appending never reallocates, and a merge copies the
//     store only when it grew or shrank by a tail or two since the last reallocation.
//
// Bytes per grain, at most: 12 (1 + 4/32) for the main arrays and their room, 8/32 for the
// tail's column and link, 8 per column for the offsets and heads, over grains of which up to a
// 32nd may be empty slots: 14.2 + 8.3 / (grains per column), 14.6 at 20 grains a column. Measured
// at a million grains (tests/dem/test_static_store.cpp): 13.2 bytes at 20 grains a column, 13.0
// at 50, through rounds of waking and sleeping.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "core/vec3.hpp"

namespace sandflow {

enum class GrainState : std::uint8_t { Active = 0, Interface = 1, Static = 2 };

using GrainId = std::uint32_t;

/// ACTIVE and INTERFACE grains: everything the DEM step reads and writes.
struct Grains {
  std::vector<GrainId> id;
  std::vector<GrainState> state;
  std::vector<Vec3> x;       ///< centre [m]
  std::vector<Vec3> v;       ///< velocity [m/s]
  std::vector<Vec3> w;       ///< angular velocity [rad/s]
  std::vector<Real> r;       ///< radius [m]
  std::vector<Real> m;       ///< mass [kg]
  std::vector<Real> inv_m;   ///< 1/mass [1/kg]
  std::vector<Real> inv_I;   ///< 1/moment of inertia (solid sphere) [1/(kg m^2)]

  std::size_t size() const { return id.size(); }

  /// Appends an ACTIVE grain of the given density.
  void add(GrainId gid, const Vec3& pos, const Vec3& vel, Real radius, Real density);

  /// Reorders every array so that slot k holds what slot perm[k] held; a shorter perm keeps only
  /// the grains it names.
  void permute(std::span<const std::uint32_t> perm);
};

/// What a StaticStore quantises against: the height field's columns, the heights and the radii a
/// static grain may have. The largest errors it gives are position_error() and radius_error().
struct StaticFrame {
  Real x0 = 0, y0 = 0;           ///< corner of column 0 (low x, low y) [m]
  Real cell = 0;                 ///< column width [m]
  std::uint32_t nx = 0, ny = 0;  ///< columns along x and y
  Real z_lo = 0, z_hi = 0;       ///< the heights a static grain's centre may have [m]
  Real r_lo = 0, r_hi = 0;       ///< the radii a static grain may have [m]

  std::size_t columns() const { return static_cast<std::size_t>(nx) * ny; }
  /// "" for a frame a store can use (finite, cell > 0, z_lo < z_hi, 0 < r_lo <= r_hi, fewer than
  /// 2^31 columns), else what is wrong.
  std::string error() const;
  /// The largest distance between a grain's centre and its stored centre [m].
  Real position_error() const;
  /// The largest difference between a grain's radius and its stored radius [m].
  Real radius_error() const;
  bool operator==(const StaticFrame&) const = default;
};

/// One static grain as the store gives it back (decoded).
struct StaticGrain {
  std::uint32_t slot;    ///< where it is held: valid until the store next changes
  std::uint32_t column;  ///< the height-field column that files it
  GrainId id;
  Vec3 x;  ///< centre [m], within StaticFrame::position_error() of the one it slept at
  Real r;  ///< radius [m], within StaticFrame::radius_error()
};

/// STATIC grains in 12 bytes each, filed by height-field column (the layout is explained at the
/// top of this file). Slots [0, slot_count()) are the main body, column after column, then the
/// tail; a removed grain leaves an empty slot until the next merge. Slots change whenever the
/// store does (add, remove): hold ids, not slots, across changes.
class StaticStore {
 public:
  static constexpr GrainId kNoGrain = 0xffffffffu;  ///< the id of an empty slot
  static constexpr int kZBits = 26, kXBits = 14, kYBits = 14, kRBits = 10;
  /// A stored centre lies at most this many cells outside its column's square.
  static constexpr Real kMargin = 1.0 / 16;
  /// The tail holds at most a 32nd of the main body (at least kTailMin grains) before a merge.
  static constexpr std::uint32_t kTailDivisor = 32, kTailMin = 256;

  /// A store that holds nothing and accepts nothing (plain DEM mode).
  StaticStore() = default;
  /// An empty store for `frame`; std::invalid_argument when frame.error() is not empty.
  explicit StaticStore(const StaticFrame& frame);

  const StaticFrame& frame() const { return f_; }
  std::size_t columns() const { return f_.columns(); }
  /// The grains held.
  std::size_t size() const { return live_; }

  /// Files grain `gid` (radius `radius` [m], centre `pos` [m]) in column `col`, which must be the
  /// column whose square holds pos.x, pos.y (within a 16th of a cell). Returns its slot. Throws
  /// SimulationError when pos.z is outside the frame's heights; std::invalid_argument for a
  /// column, position or radius the frame does not hold, or an unconfigured store.
  std::uint32_t add(GrainId gid, const Vec3& pos, Real radius, std::uint32_t col);
  /// Removes the grains in these slots (each held, each once); may merge the tail after.
  void remove(std::span<const std::uint32_t> slots);

  // ---- reading, by slot ----
  std::uint32_t slot_count() const { return static_cast<std::uint32_t>(id_.size()); }
  /// Slots [0, main_slots()) are the main body, the rest the tail.
  std::uint32_t main_slots() const { return main_; }
  bool holds(std::uint32_t k) const { return k < id_.size() && id_[k] != kNoGrain; }
  GrainId id(std::uint32_t k) const { return id_[k]; }
  /// The column of slot k (a binary search over the columns in the main body).
  std::uint32_t column(std::uint32_t k) const;
  Vec3 position(std::uint32_t k) const { return decode_x(code_[k], column(k)); }
  Real radius(std::uint32_t k) const { return decode_r(code_[k]); }
  StaticGrain grain(std::uint32_t k) const { return grain(k, column(k)); }

  // ---- reading, by column ----
  /// Calls f(const StaticGrain&) for every grain, in slot order (the main body column by
  /// column, each column's grains ascending in height, then the tail as it came).
  template <class F>
  void for_each(F&& f) const;
  /// Calls f(const StaticGrain&) for the grains of column c: the main body's ascending in
  /// height, then the tail's. A column the store does not have holds none.
  template <class F>
  void for_each_in_column(std::size_t c, F&& f) const;
  /// As for_each_in_column, for the grains whose centre has z_lo < z < z_hi (a binary search in
  /// the main body).
  template <class F>
  void for_each_in_column_between(std::size_t c, Real z_lo, Real z_hi, F&& f) const;
  /// Calls f(const StaticGrain&) for every grain whose centre may lie in the box [lo, hi] (and
  /// some near it: whole columns, within their margin): the work is the columns the box covers,
  /// not the store.
  template <class F>
  void for_each_near_box(const Vec3& lo, const Vec3& hi, F&& f) const;

  /// Counts every change, so that an index built on the store knows when it is stale.
  std::uint64_t revision() const { return revision_; }
  /// The columns whose grains changed (added or removed) since the last forget_changes(), with
  /// repeats, for the one index that follows the store column by column (the reach of the static
  /// layer); null when any may have (a new or restored store, or more changes than columns).
  const std::vector<std::uint32_t>* changed_columns() const {
    return all_changed_ ? nullptr : &changed_;
  }
  void forget_changes() {
    changed_.clear();
    all_changed_ = false;
  }
  /// Bytes the store has allocated: the capacity of every array it holds.
  std::size_t allocated_bytes() const;
  /// The invariants of the layout (sizes, each column ascending in height, the tail's lists,
  /// the counts, the capacity); "" when they hold. O(slots + columns), for assertions and tests.
  std::string check() const;

  /// The compact form, for checkpoints: restoring it gives the same slots, the same merges to
  /// come and the same allocated bytes.
  struct State {
    std::vector<std::uint32_t> column_slots;  ///< per column: its slots in the main body
    std::vector<GrainId> id;                 ///< every slot (main body, then tail); kNoGrain: empty
    std::vector<std::uint64_t> code;         ///< every slot's packed centre and radius
    std::vector<std::uint32_t> tail_column;  ///< per tail slot: its column
    std::uint64_t capacity = 0;              ///< slots the main arrays have room for
  };
  State save_state() const;
  /// "" when this store (configured for its frame) can take `s` as its state, else what is
  /// wrong: counts, columns, each column's heights ascending, the tail's size, the capacity. It
  /// does not check ids against other grains (store_error and the checkpoint reader do).
  std::string state_error(const State& s) const;
  /// Takes `s` (std::invalid_argument with state_error() when it does not fit).
  void restore(State s);

 private:
  StaticFrame f_;
  Real step_u_ = 0, step_z_ = 0, step_r_ = 0;  ///< quantisation steps (u: in cells) [-, m, m]
  std::vector<GrainId> id_;                    ///< per slot; kNoGrain: empty
  std::vector<std::uint64_t> code_;            ///< per slot: z, x, y, r (bits, high to low)
  std::vector<std::uint32_t> start_;           ///< per column + 1: offsets of the main body
  std::vector<std::uint32_t> tail_column_;     ///< per tail slot: its column
  std::vector<std::uint32_t> tail_next_;       ///< per tail slot: the column's previous one
  std::vector<std::uint32_t> tail_last_;       ///< per column: its last tail slot (or kNone)
  std::uint32_t main_ = 0;                     ///< slots of the main body
  std::uint32_t tail_max_ = 0;                 ///< tail + empty slots that make a merge
  std::size_t live_ = 0, empty_ = 0;           ///< grains held, empty slots
  std::uint64_t revision_ = 0;
  std::vector<std::uint32_t> changed_;  ///< see changed_columns()
  bool all_changed_ = true;
  static constexpr std::uint32_t kNone = 0xffffffffu;
  /// Notes a change of column c (see changed_columns()).
  void changed(std::uint32_t c);

  static std::uint32_t tail_limit(std::uint32_t main);
  std::uint64_t encode(GrainId gid, const Vec3& pos, Real radius, std::uint32_t col) const;
  Vec3 decode_x(std::uint64_t code, std::uint32_t col) const;
  Real decode_z(std::uint64_t code) const {
    return f_.z_lo + static_cast<Real>(code >> (64 - kZBits)) * step_z_;
  }
  Real decode_r(std::uint64_t code) const {
    return f_.r_lo + static_cast<Real>(code & ((1u << kRBits) - 1)) * step_r_;
  }
  StaticGrain grain(std::uint32_t k, std::uint32_t col) const {
    return {k, col, id_[k], decode_x(code_[k], col), decode_r(code_[k])};
  }
  /// Sets the main arrays' capacity for a main body of `main` slots (see the top of the file).
  void fit_capacity(std::uint32_t main);
  /// Merges the tail into the main body and drops the empty slots.
  void merge();
};

/// The invariant of the stores (docs/design.md §2), for assertions: every array of each store has
/// its size, the hot store holds no STATIC grain, every id is below `next_id` and held at most
/// once in the two stores together, and they hold `expected` grains (so each of those is in
/// exactly one). Returns what is wrong, or "" when nothing is. O(n + next_id).
std::string store_error(const Grains& hot, const StaticStore& statics, GrainId next_id,
                        std::int64_t expected);

// ---------------------------------------------------------------------------------------------
template <class F>
void StaticStore::for_each(F&& f) const {
  const std::size_t nc = start_.empty() ? 0 : start_.size() - 1;
  for (std::size_t c = 0; c < nc; ++c)
    for (std::uint32_t q = start_[c]; q < start_[c + 1]; ++q)
      if (id_[q] != kNoGrain) f(grain(q, static_cast<std::uint32_t>(c)));
  for (std::uint32_t t = 0; t < tail_column_.size(); ++t)
    if (id_[main_ + t] != kNoGrain) f(grain(main_ + t, tail_column_[t]));
}

template <class F>
void StaticStore::for_each_in_column(std::size_t c, F&& f) const {
  if (c + 1 >= start_.size()) return;
  const auto col = static_cast<std::uint32_t>(c);
  for (std::uint32_t q = start_[c]; q < start_[c + 1]; ++q)
    if (id_[q] != kNoGrain) f(grain(q, col));
  for (std::uint32_t t = tail_last_[c]; t != kNone; t = tail_next_[t])
    if (id_[main_ + t] != kNoGrain) f(grain(main_ + t, col));
}

template <class F>
void StaticStore::for_each_near_box(const Vec3& lo, const Vec3& hi, F&& f) const {
  if (start_.empty() || live_ == 0) return;
  // (a stored centre lies at most kMargin cells outside its column's square)
  const Real m = kMargin * f_.cell;
  const Real fx0 = std::floor((lo.x - m - f_.x0) / f_.cell),
             fx1 = std::floor((hi.x + m - f_.x0) / f_.cell);
  const Real fy0 = std::floor((lo.y - m - f_.y0) / f_.cell),
             fy1 = std::floor((hi.y + m - f_.y0) / f_.cell);
  if (!(fx1 >= 0 && fy1 >= 0 && fx0 < f_.nx && fy0 < f_.ny)) return;  // (NaN too)
  const auto i0 = static_cast<std::size_t>(std::max(fx0, 0.0));
  const auto i1 = static_cast<std::size_t>(std::min<Real>(fx1, f_.nx - 1));
  const auto j0 = static_cast<std::size_t>(std::max(fy0, 0.0));
  const auto j1 = static_cast<std::size_t>(std::min<Real>(fy1, f_.ny - 1));
  // (the stored heights are within the frame's step of the true ones: a step's margin)
  const Real dz = f_.position_error();
  for (std::size_t j = j0; j <= j1; ++j)
    for (std::size_t i = i0; i <= i1; ++i)
      for_each_in_column_between(j * f_.nx + i, lo.z - dz, hi.z + dz, f);
}

template <class F>
void StaticStore::for_each_in_column_between(std::size_t c, Real z_lo, Real z_hi, F&& f) const {
  if (c + 1 >= start_.size()) return;
  const auto col = static_cast<std::uint32_t>(c);
  // the main body's heights ascend (an empty slot keeps the height it had): the first above z_lo
  std::uint32_t lo = start_[c], hi = start_[c + 1];
  while (lo < hi) {
    const std::uint32_t mid = lo + (hi - lo) / 2;
    if (decode_z(code_[mid]) <= z_lo)
      lo = mid + 1;
    else
      hi = mid;
  }
  for (std::uint32_t q = lo; q < start_[c + 1] && decode_z(code_[q]) < z_hi; ++q)
    if (id_[q] != kNoGrain) f(grain(q, col));
  for (std::uint32_t t = tail_last_[c]; t != kNone; t = tail_next_[t]) {
    const std::uint32_t k = main_ + t;
    if (id_[k] == kNoGrain) continue;
    const Real z = decode_z(code_[k]);
    if (z > z_lo && z < z_hi) f(grain(k, col));
  }
}

}  // namespace sandflow
