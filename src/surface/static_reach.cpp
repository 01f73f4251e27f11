#include "surface/static_reach.hpp"

namespace sandflow {

namespace {
constexpr Real kNone = -std::numeric_limits<Real>::infinity();
}

Real StaticReach::column_top(const StaticStore& st, std::size_t c) {
  Real top = kNone;
  st.for_each_in_column(c, [&](const StaticGrain& g) { top = std::max(top, g.x.z + g.r); });
  return top;
}

void StaticReach::prepare(const HeightField& hf, StaticStore& st, Real reach) {
  const std::size_t nc = hf.columns();
  // (the largest radius the store may hold: the searches below stay exact, and an index of a
  // store whose largest grain left needs no pass to know it)
  const Real r_max = st.size() > 0 ? st.frame().r_hi : 0.0;
  // a grain within reach of x lies at most this many columns from x's own
  // (and a stored centre lies at most StaticStore::kMargin cells outside its column)
  const int span = static_cast<int>(std::ceil((reach + r_max) / hf.cell() + StaticStore::kMargin));
  const std::vector<std::uint32_t>* changed = st.changed_columns();
  const int nx = hf.nx(), ny = hf.ny();
  auto window_top = [&](std::size_t c) {
    // the highest top within span_ columns: a square window holds every column a disk of the
    // reach touches
    const int i = static_cast<int>(c % nx), j = static_cast<int>(c / nx);
    Real m = kNone;
    for (int jj = std::max(j - span_, 0); jj <= std::min(j + span_, ny - 1); ++jj)
      for (int ii = std::max(i - span_, 0); ii <= std::min(i + span_, nx - 1); ++ii)
        m = std::max(m, top_[static_cast<std::size_t>(jj) * nx + ii]);
    return m;
  };

  if (!changed || columns_ != nc || r_max_ != r_max) {
    // afresh: every column's top, then every window
    columns_ = nc;
    r_max_ = r_max;
    span_ = std::max(span_, span);
    top_.assign(nc, kNone);
    st.for_each(
        [&](const StaticGrain& g) { top_[g.column] = std::max(top_[g.column], g.x.z + g.r); });
    near_top_.resize(nc);
    for (std::size_t c = 0; c < nc; ++c) near_top_[c] = window_top(c);
    changed_.resize(nc);
    window_.resize(nc);
    st.forget_changes();
    return;
  }
  if (span > span_) {
    // a wider reach than any before (a faster grain): the windows once, then kept
    span_ = span;
    for (std::size_t c = 0; c < nc; ++c) near_top_[c] = window_top(c);
  }
  // the columns whose grains changed, then the windows that hold them
  changed_.clear();
  changed_.add(*changed);
  st.forget_changes();
  window_.clear();
  for (std::uint32_t c : changed_.list()) {
    top_[c] = column_top(st, c);
    const int i = static_cast<int>(c % nx), j = static_cast<int>(c / nx);
    for (int jj = std::max(j - span_, 0); jj <= std::min(j + span_, ny - 1); ++jj)
      for (int ii = std::max(i - span_, 0); ii <= std::min(i + span_, nx - 1); ++ii)
        window_.add(static_cast<std::uint32_t>(jj * nx + ii));
  }
  for (std::uint32_t c : window_.list()) near_top_[c] = window_top(c);
}

}  // namespace sandflow
