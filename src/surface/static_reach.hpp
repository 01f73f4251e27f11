// Which STATIC grains lie near a point: the question the invariant of the layers asks of the
// static store at every rebuild of the pair list (InterfaceLayer::wake_within_reach). The store
// files its grains by height-field column, each column's main body in ascending z
// (dem/grains.hpp). This index adds, per column, the highest top of the static
// grains within `reach` of it, so that the many ACTIVE grains well above the static layer are
// passed over with one look; for the others a binary search finds the band of heights in each
// column near them. Tested against brute force (tests/surface/test_static_reach.cpp).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "core/vec3.hpp"
#include "dem/grains.hpp"
#include "surface/column_set.hpp"
#include "surface/height_field.hpp"

namespace sandflow {

class StaticReach {
 public:
  /// Makes the index answer queries of reach up to `reach` [m] (for_each_within's `extra`). It
  /// follows the store's changed columns (StaticStore::changed_columns, which it consumes), so
  /// its work is what changed, not the store; a reach wider than any before recomputes the
  /// windows once.
  void prepare(const HeightField& hf, StaticStore& st, Real reach);

  /// Calls f(k) for the slot k of every static grain with |x - x_k| < extra + r_k; `extra` at
  /// most the reach prepare() was given.
  template <class F>
  void for_each_within(const HeightField& hf, const StaticStore& st, const Vec3& x, Real extra,
                       F&& f) const;

  /// The largest radius a static grain may have [m] (the store's frame; 0 for an empty store).
  Real r_max() const { return r_max_; }

 private:
  /// The highest top of the grains of column c.
  static Real column_top(const StaticStore& st, std::size_t c);

  std::size_t columns_ = 0;
  int span_ = -1;  ///< columns the reach covers on each side (never shrinks)
  Real r_max_ = 0;
  std::vector<Real> top_;            ///< per column: highest z + r of its static grains
  std::vector<Real> near_top_;       ///< per column: highest z + r of the static grains within span_
  ColumnSet changed_, window_;       ///< scratch of prepare()
};

// ---------------------------------------------------------------------------------------------
template <class F>
void StaticReach::for_each_within(const HeightField& hf, const StaticStore& st, const Vec3& x,
                                  Real extra, F&& f) const {
  if (st.size() == 0) return;
  // a grain k within reach has z_k + r_k > x.z - extra and lies at most span_ columns away
  const std::int64_t own = hf.column_of(x.x, x.y);
  if (own >= 0 && !(near_top_[static_cast<std::size_t>(own)] > x.z - extra)) return;
  const Real R = extra + r_max_;  // horizontal and vertical reach of the centres
  const Real cell = hf.cell();
  // (a stored centre lies at most StaticStore::kMargin cells outside its column's square)
  const Real edge = StaticStore::kMargin * cell, Rc = R + edge;
  const HeightFieldParams& g = hf.params();
  const Real fx0 = std::floor((x.x - Rc - g.x0) / cell), fx1 = std::floor((x.x + Rc - g.x0) / cell);
  const Real fy0 = std::floor((x.y - Rc - g.y0) / cell), fy1 = std::floor((x.y + Rc - g.y0) / cell);
  if (!(fx1 >= 0 && fy1 >= 0 && fx0 < g.nx && fy0 < g.ny)) return;  // (NaN too)
  const int i0 = static_cast<int>(std::max(fx0, 0.0)), i1 = static_cast<int>(std::min<Real>(fx1, g.nx - 1));
  const int j0 = static_cast<int>(std::max(fy0, 0.0)), j1 = static_cast<int>(std::min<Real>(fy1, g.ny - 1));
  const Real z_lo = x.z - R, z_hi = x.z + R;
  for (int j = j0; j <= j1; ++j)
    for (int i = i0; i <= i1; ++i) {
      const std::size_t c = static_cast<std::size_t>(j) * g.nx + i;
      if (!(top_[c] > x.z - extra)) continue;  // (every grain of the column is too low)
      // the column's square (with its margin) lies further than R from x: none of its centres
      // is near
      const Real dx =
          std::max({g.x0 + i * cell - edge - x.x, x.x - (g.x0 + (i + 1) * cell + edge), 0.0});
      const Real dy =
          std::max({g.y0 + j * cell - edge - x.y, x.y - (g.y0 + (j + 1) * cell + edge), 0.0});
      if (dx * dx + dy * dy >= R * R) continue;
      st.for_each_in_column_between(c, z_lo, z_hi, [&](const StaticGrain& s) {
        const Real reach = extra + s.r;
        if (norm2(x - s.x) < reach * reach) f(s.slot);
      });
    }
}

}  // namespace sandflow
