#include "surface/static_reach.hpp"

namespace sandflow {

void StaticReach::prepare(const HeightField& hf, const StaticStore& st, Real reach) {
  const std::size_t nc = hf.columns();
  // (the largest radius the store may hold: the searches below stay exact, and an index of a
  // store whose largest grain left needs no pass to know it)
  const Real r_max = st.size() > 0 ? st.frame().r_hi : 0.0;
  // a grain within reach of x lies at most this many columns from x's own
  // (and a stored centre lies at most StaticStore::kMargin cells outside its column)
  const int span = static_cast<int>(std::ceil((reach + r_max) / hf.cell() + StaticStore::kMargin));
  if (revision_ == st.revision() && columns_ == nc && span_ == span && r_max_ == r_max) return;
  revision_ = st.revision();
  columns_ = nc;
  span_ = span;
  r_max_ = r_max;

  // the highest top of each column's grains, then the highest within span_ columns: a running
  // maximum along x, then along y (a square window: it holds every column a disk of the reach
  // touches)
  constexpr Real kNone = -std::numeric_limits<Real>::infinity();
  top_.assign(nc, kNone);
  st.for_each(
      [&](const StaticGrain& g) { top_[g.column] = std::max(top_[g.column], g.x.z + g.r); });
  const std::vector<Real>& top = top_;
  const int nx = hf.nx(), ny = hf.ny();
  std::vector<Real> along_x(nc, kNone);
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      Real m = kNone;
      for (int ii = std::max(i - span, 0); ii <= std::min(i + span, nx - 1); ++ii)
        m = std::max(m, top[static_cast<std::size_t>(j) * nx + ii]);
      along_x[static_cast<std::size_t>(j) * nx + i] = m;
    }
  near_top_.assign(nc, kNone);
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      Real m = kNone;
      for (int jj = std::max(j - span, 0); jj <= std::min(j + span, ny - 1); ++jj)
        m = std::max(m, along_x[static_cast<std::size_t>(jj) * nx + i]);
      near_top_[static_cast<std::size_t>(j) * nx + i] = m;
    }
}

}  // namespace sandflow
