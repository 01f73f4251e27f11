#include "analysis/crater.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include "analysis/grain_cells.hpp"
#include "analysis/statistics.hpp"

namespace sandflow {
namespace {

constexpr double kRimReach = 3.0;          // the rim is sought out to this many crater radii

struct Cell {
  std::int64_t i = 0, j = 0;
  double top = -std::numeric_limits<double>::infinity();  // highest grain top [m]
  double smooth = 0;                                      // 3x3 median of top [m]
};

}  // namespace

CraterFit measure_crater(const std::vector<Vec3>& pos, const std::vector<Real>& radius,
                         double z_ref, double cx, double cy) {
  if (pos.size() != radius.size())
    throw std::invalid_argument("measure_crater: positions and radii have different lengths");
  CraterFit fit;
  const GrainCells map = grain_cells(pos, radius);
  if (!map.problem.empty()) {
    fit.reason = map.problem;
    return fit;
  }
  const std::vector<std::size_t>& use = map.use;
  const double d = map.d, x0 = map.x0, y0 = map.y0;

  // 1. the top-surface map, smoothed by a 3x3 median
  std::unordered_map<std::uint64_t, std::size_t> index;
  std::vector<Cell> cells;
  for (std::size_t k : use) {
    const auto i = static_cast<std::int64_t>(std::floor((pos[k].x - x0) / d));
    const auto j = static_cast<std::int64_t>(std::floor((pos[k].y - y0) / d));
    auto [it, inserted] = index.try_emplace(cell_key(i, j), cells.size());
    if (inserted) cells.push_back({i, j});
    Cell& c = cells[it->second];
    c.top = std::max(c.top, pos[k].z + radius[k]);
  }
  auto find = [&](std::int64_t i, std::int64_t j) -> const Cell* {
    const auto it = index.find(cell_key(i, j));
    return it == index.end() ? nullptr : &cells[it->second];
  };
  auto centre_of = [&](const Cell& c) {
    return Vec3{x0 + (static_cast<double>(c.i) + 0.5) * d,
                y0 + (static_cast<double>(c.j) + 0.5) * d, 0};
  };
  std::vector<double> nb, all;
  std::size_t lowest = 0;
  for (std::size_t c = 0; c < cells.size(); ++c) {
    nb.clear();
    for (std::int64_t di = -1; di <= 1; ++di)
      for (std::int64_t dj = -1; dj <= 1; ++dj)
        if (const Cell* n = find(cells[c].i + di, cells[c].j + dj)) nb.push_back(n->top);
    cells[c].smooth = median(nb);
    all.push_back(cells[c].smooth);
    if (cells[c].smooth < cells[lowest].smooth) lowest = c;
  }

  // 2. the undisturbed level
  if (std::isnan(z_ref)) z_ref = median(all);
  if (cells[lowest].smooth > z_ref - d) {
    fit.reason = "no crater: the surface nowhere lies a grain diameter below the bed's top";
    return fit;
  }

  // 3. the centre: the connected cells more than a diameter deep around the lowest one
  if (std::isnan(cx) || std::isnan(cy)) {
    std::vector<const Cell*> stack{&cells[lowest]};
    std::unordered_set<std::uint64_t> seen{cell_key(cells[lowest].i, cells[lowest].j)};
    Vec3 sum;
    double weight = 0;
    while (!stack.empty()) {
      const Cell* c = stack.back();
      stack.pop_back();
      const double w = z_ref - c->smooth;
      sum += centre_of(*c) * w;
      weight += w;
      for (std::int64_t di = -1; di <= 1; ++di)
        for (std::int64_t dj = -1; dj <= 1; ++dj) {
          const Cell* n = find(c->i + di, c->j + dj);
          if (n && n->smooth < z_ref - d && seen.insert(cell_key(n->i, n->j)).second)
            stack.push_back(n);
        }
    }
    cx = sum.x / weight;
    cy = sum.y / weight;
  }
  fit.centre = {cx, cy, z_ref};

  // 4. the radial profile: rings of width d, the median height of each
  std::vector<std::vector<double>> ring_r, ring_h;
  for (const Cell& c : cells) {
    const Vec3 p = centre_of(c);
    const double r = std::hypot(p.x - cx, p.y - cy);
    const auto ring = static_cast<std::size_t>(r / d);
    if (ring >= ring_r.size()) {
      ring_r.resize(ring + 1);
      ring_h.resize(ring + 1);
    }
    ring_r[ring].push_back(r);
    ring_h[ring].push_back(c.smooth);
  }
  struct Point {
    double r, h;
  };
  std::vector<Point> profile;
  for (std::size_t k = 0; k < ring_r.size(); ++k)
    if (!ring_r[k].empty()) profile.push_back({median(ring_r[k]), median(ring_h[k])});

  // 5. depth inside the crater, rim outside it
  std::size_t edge = 0;
  double bottom = profile[0].h;
  while (edge < profile.size() && profile[edge].h < z_ref)
    bottom = std::min(bottom, profile[edge++].h);
  fit.depth = z_ref - bottom;
  if (edge == 0) {
    fit.reason = "no crater: the surface at the centre is not below the bed's top";
    return fit;
  }
  if (edge == profile.size()) {
    fit.reason =
        "no rim: the surface never rises back to the bed's top (a crater wider than the bed?)";
    fit.radius = profile.back().r;
    return fit;
  }
  // where the profile crosses z_ref, between the last point below and the first above
  const Point& a = profile[edge - 1];
  const Point& b = profile[edge];
  fit.radius = a.r + (b.r - a.r) * (z_ref - a.h) / (b.h - a.h);
  fit.rim_height = 0;
  fit.rim_radius = fit.radius;
  for (std::size_t k = edge; k < profile.size() && profile[k].r <= kRimReach * fit.radius; ++k)
    if (profile[k].h - z_ref > fit.rim_height) {
      fit.rim_height = profile[k].h - z_ref;
      fit.rim_radius = profile[k].r;
    }
  fit.ok = true;
  return fit;
}

}  // namespace sandflow
