#include "analysis/crater.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <optional>
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

/// Step 1: the top-surface map of the grains, each cell's top and its 3x3 median.
struct TopMap {
  GrainCells grid;
  std::unordered_map<std::uint64_t, std::size_t> index;
  std::vector<Cell> cells;
  const Cell* find(std::int64_t i, std::int64_t j) const {
    const auto it = index.find(cell_key(i, j));
    return it == index.end() ? nullptr : &cells[it->second];
  }
};

TopMap top_map(const std::vector<Vec3>& pos, const std::vector<Real>& radius) {
  if (pos.size() != radius.size())
    throw std::invalid_argument("measure_crater: positions and radii have different lengths");
  TopMap m;
  m.grid = grain_cells(pos, radius);
  if (!m.grid.problem.empty()) return m;
  const double d = m.grid.d, x0 = m.grid.x0, y0 = m.grid.y0;
  for (std::size_t k : m.grid.use) {
    const auto i = static_cast<std::int64_t>(std::floor((pos[k].x - x0) / d));
    const auto j = static_cast<std::int64_t>(std::floor((pos[k].y - y0) / d));
    auto [it, inserted] = m.index.try_emplace(cell_key(i, j), m.cells.size());
    if (inserted) m.cells.push_back({i, j});
    Cell& c = m.cells[it->second];
    c.top = std::max(c.top, pos[k].z + radius[k]);
  }
  std::vector<double> nb;
  for (Cell& c : m.cells) {
    nb.clear();
    for (std::int64_t di = -1; di <= 1; ++di)
      for (std::int64_t dj = -1; dj <= 1; ++dj)
        if (const Cell* n = m.find(c.i + di, c.j + dj)) nb.push_back(n->top);
    c.smooth = median(nb);
  }
  return m;
}

/// The first time t > 0 at which z0 + vz t + gz t^2 / 2 comes down to `z` (0 when z0 is at or below
/// it already), if it ever does.
std::optional<double> time_to_reach(double z0, double vz, double gz, double z) {
  const double c = z0 - z;
  if (c <= 0) return 0.0;
  if (gz == 0) return vz < 0 ? std::optional<double>(c / -vz) : std::nullopt;
  const double disc = vz * vz - 2 * gz * c;
  if (disc < 0) return std::nullopt;
  double best = std::numeric_limits<double>::infinity();
  for (double t : {(-vz + std::sqrt(disc)) / gz, (-vz - std::sqrt(disc)) / gz})
    if (t > 0) best = std::min(best, t);
  return std::isfinite(best) ? std::optional<double>(best) : std::nullopt;
}

bool over(const EmitterConfig& bed, double x, double y) {
  return std::abs(x - bed.center.x) <= 0.5 * bed.size.x &&
         std::abs(y - bed.center.y) <= 0.5 * bed.size.y;
}

}  // namespace

CraterSite crater_site(const SceneConfig& scene) {
  CraterSite site;
  std::vector<const EmitterConfig*> beds, thrown;
  for (const EmitterConfig& e : scene.emitters)
    (e.type == EmitterType::Bed ? beds : thrown).push_back(&e);
  if (beds.empty()) return site;
  site.bed = true;
  const EmitterConfig* bed = beds.front();

  // where the one thrown emitter's sand comes down to the top of the bed under it
  site.centre_from = thrown.empty() ? "found from the grains (no emitter besides the bed)"
                     : thrown.size() > 1
                         ? "found from the grains (several emitters besides the bed)"
                         : "";
  if (thrown.size() == 1) {
    const EmitterConfig& e = *thrown.front();
    const std::string who = e.name.empty() ? "the thrown sand" : "'" + e.name + "'";
    const Vec3 g = scene.simulation.gravity;
    const Vec3 start{e.center.x, e.center.y,
                     e.center.z - (e.type == EmitterType::Pour ? 0 : 0.5 * e.size.z)};
    // the bed it comes down on: of the beds whose top it crosses over their footprint, the first
    double first = std::numeric_limits<double>::infinity();
    for (const EmitterConfig* b : beds) {
      const auto t = time_to_reach(start.z, e.velocity.z, g.z, b->height);
      if (!t || *t >= first) continue;
      const double x = start.x + e.velocity.x * *t + 0.5 * g.x * *t * *t;
      const double y = start.y + e.velocity.y * *t + 0.5 * g.y * *t * *t;
      if (!over(*b, x, y)) continue;
      first = *t;
      bed = b;
      site.cx = x;
      site.cy = y;
    }
    site.centre_from = std::isnan(site.cx)
                           ? "found from the grains (" + who + " comes down on no bed's top)"
                           : "where " + who + " lands";
  }
  site.bed_index = static_cast<std::size_t>(bed - scene.emitters.data());
  site.height = bed->height;
  site.x0 = bed->center.x - 0.5 * bed->size.x;
  site.x1 = bed->center.x + 0.5 * bed->size.x;
  site.y0 = bed->center.y - 0.5 * bed->size.y;
  site.y1 = bed->center.y + 0.5 * bed->size.y;
  return site;
}

double bed_level(const std::vector<Vec3>& pos, const std::vector<Real>& radius) {
  const TopMap map = top_map(pos, radius);
  if (!map.grid.problem.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::vector<double> all;
  for (const Cell& c : map.cells) all.push_back(c.smooth);
  return median(all);
}

CraterFit measure_crater(const CraterSite& site, double z_ref, const std::vector<Vec3>& pos,
                         const std::vector<Real>& radius) {
  if (pos.size() != radius.size())
    throw std::invalid_argument("measure_crater: positions and radii have different lengths");
  if (!site.bed) {
    CraterFit fit;
    fit.reason = "no bed: the scene has no bed emitter to make a crater in";
    return fit;
  }
  std::vector<Vec3> p;
  std::vector<Real> r;
  for (std::size_t k = 0; k < pos.size(); ++k)
    if (pos[k].x >= site.x0 && pos[k].x <= site.x1 && pos[k].y >= site.y0 && pos[k].y <= site.y1) {
      p.push_back(pos[k]);
      r.push_back(radius[k]);
    }
  return measure_crater(p, r, z_ref, site.cx, site.cy);
}

CraterFit measure_crater(const std::vector<Vec3>& pos, const std::vector<Real>& radius,
                         double z_ref, double cx, double cy) {
  CraterFit fit;
  // 1. the top-surface map, smoothed by a 3x3 median
  const TopMap map = top_map(pos, radius);
  if (!map.grid.problem.empty()) {
    fit.reason = map.grid.problem;
    return fit;
  }
  const std::vector<Cell>& cells = map.cells;
  const double d = map.grid.d, x0 = map.grid.x0, y0 = map.grid.y0;
  auto find = [&](std::int64_t i, std::int64_t j) { return map.find(i, j); };
  auto centre_of = [&](const Cell& c) {
    return Vec3{x0 + (static_cast<double>(c.i) + 0.5) * d,
                y0 + (static_cast<double>(c.j) + 0.5) * d, 0};
  };
  std::vector<double> all;
  std::size_t lowest = 0;
  for (std::size_t c = 0; c < cells.size(); ++c) {
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
