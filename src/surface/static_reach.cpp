#include "surface/static_reach.hpp"

namespace sandflow {

void StaticReach::prepare(const HeightField& hf, const StaticStore& st, Real reach) {
  const std::size_t nc = hf.columns();
  Real r_max = 0;
  for (Real r : st.r) r_max = std::max(r_max, r);
  // a grain within reach of x lies at most this many columns from x's own
  const int span = static_cast<int>(std::ceil((reach + r_max) / hf.cell()));
  if (revision_ == st.revision && columns_ == nc && span_ == span && r_max_ == r_max) return;
  revision_ = st.revision;
  columns_ = nc;
  span_ = span;
  r_max_ = r_max;

  // the highest top of each column's grains, then the highest within span_ columns: a running
  // maximum along x, then along y (a square window: it holds every column a disk of the reach
  // touches)
  constexpr Real kNone = -std::numeric_limits<Real>::infinity();
  top_.assign(nc, kNone);
  for (std::size_t k = 0; k < st.size(); ++k)
    top_[st.column[k]] = std::max(top_[st.column[k]], st.x[k].z + st.r[k]);
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
