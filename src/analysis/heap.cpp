#include "analysis/heap.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include <fmt/format.h>

#include "analysis/grain_cells.hpp"
#include "analysis/statistics.hpp"

namespace sandflow {
namespace {

// The flank band must span two grain layers: across one, the profile is the staircase of single
// grains (a spread-out layer, a pancake), whatever line fits it.
constexpr double kMinBandDiameters = 2.0;
constexpr int kMinFlankPoints = 4;

struct Cell {
  std::int64_t i = 0, j = 0;
  double h = 0;       // highest grain top above the floor [m]
  double smooth = 0;  // 3x3 median of h
};

struct ProfilePoint {
  double r = 0;  // median distance from the apex [m]
  double h = 0;  // median cell height [m]
};

}  // namespace

HeapFit measure_heap(const std::vector<Vec3>& pos, const std::vector<Real>& radius, double floor_z,
                     double band_low, double band_high) {
  if (pos.size() != radius.size()) {
    throw std::invalid_argument("measure_heap: positions and radii have different lengths");
  }
  if (!(band_low >= 0 && band_low < band_high && band_high <= 1)) {
    throw std::invalid_argument("measure_heap: need 0 <= band_low < band_high <= 1");
  }
  HeapFit fit;

  // Usable grains and the cells over them.
  const GrainCells map = grain_cells(pos, radius);
  if (!map.problem.empty()) {
    fit.reason = map.problem;
    return fit;
  }
  const std::vector<std::size_t>& use = map.use;
  const double d = map.d, x0 = map.x0, y0 = map.y0;
  if (std::isnan(floor_z)) {
    floor_z = pos[use[0]].z - radius[use[0]];
    for (std::size_t k : use) floor_z = std::min(floor_z, pos[k].z - radius[k]);
  }

  // 1. Top-surface map: highest grain top per occupied cell.
  std::unordered_map<std::uint64_t, std::size_t> index;  // cell key -> position in `cells`
  std::vector<Cell> cells;
  for (std::size_t k : use) {
    const auto i = static_cast<std::int64_t>(std::floor((pos[k].x - x0) / d));
    const auto j = static_cast<std::int64_t>(std::floor((pos[k].y - y0) / d));
    const double top = pos[k].z + radius[k] - floor_z;
    auto [it, inserted] = index.try_emplace(cell_key(i, j), cells.size());
    if (inserted) {
      cells.push_back({i, j, top, 0});
    } else {
      cells[it->second].h = std::max(cells[it->second].h, top);
    }
  }
  auto find = [&](std::int64_t i, std::int64_t j) -> const Cell* {
    const auto it = index.find(cell_key(i, j));
    return it == index.end() ? nullptr : &cells[it->second];
  };
  auto centre = [&](const Cell& c) {
    return Vec3{x0 + (static_cast<double>(c.i) + 0.5) * d,
                y0 + (static_cast<double>(c.j) + 0.5) * d, 0};
  };

  // 2. Apex: highest cell after a 3x3 median over occupied neighbours.
  std::vector<double> nb;
  std::size_t top = 0;
  for (std::size_t c = 0; c < cells.size(); ++c) {
    nb.clear();
    for (std::int64_t di = -1; di <= 1; ++di) {
      for (std::int64_t dj = -1; dj <= 1; ++dj) {
        if (const Cell* n = find(cells[c].i + di, cells[c].j + dj)) nb.push_back(n->h);
      }
    }
    cells[c].smooth = median(nb);
    if (cells[c].smooth > cells[top].smooth) top = c;
  }
  const double h_max = cells[top].smooth;
  // Refine x, y: centroid of the connected cells within half a diameter of the summit.
  {
    std::vector<const Cell*> stack{&cells[top]};
    std::unordered_set<std::uint64_t> seen{cell_key(cells[top].i, cells[top].j)};
    Vec3 sum;
    int count = 0;
    while (!stack.empty()) {
      const Cell* c = stack.back();
      stack.pop_back();
      sum += centre(*c);
      ++count;
      for (std::int64_t di = -1; di <= 1; ++di) {
        for (std::int64_t dj = -1; dj <= 1; ++dj) {
          const Cell* n = find(c->i + di, c->j + dj);
          if (n && n->smooth >= h_max - 0.5 * d && seen.insert(cell_key(n->i, n->j)).second) {
            stack.push_back(n);
          }
        }
      }
    }
    fit.apex = sum / count;
    fit.apex.z = floor_z + h_max;
  }

  // 3. Radial profile: rings of width d, median distance and median height per ring.
  struct Sample {
    std::int64_t ring;
    double r, h;
  };
  std::vector<Sample> samples;
  samples.reserve(cells.size());
  for (const Cell& c : cells) {
    const Vec3 p = centre(c);
    const double r = std::hypot(p.x - fit.apex.x, p.y - fit.apex.y);
    samples.push_back({static_cast<std::int64_t>(r / d), r, c.h});
  }
  std::sort(samples.begin(), samples.end(),
            [](const Sample& a, const Sample& b) { return a.ring < b.ring; });
  std::vector<ProfilePoint> profile;
  std::vector<double> rs, hs;
  for (std::size_t a = 0; a < samples.size();) {
    std::size_t b = a;
    rs.clear();
    hs.clear();
    for (; b < samples.size() && samples[b].ring == samples[a].ring; ++b) {
      rs.push_back(samples[b].r);
      hs.push_back(samples[b].h);
    }
    profile.push_back({median(rs), median(hs)});
    a = b;
  }
  fit.base_radius = profile.back().r;

  // 4. Heap height: the profile's maximum.
  std::size_t i_max = 0;
  for (std::size_t k = 0; k < profile.size(); ++k) {
    if (profile[k].h > profile[i_max].h) i_max = k;
  }
  fit.height = profile[i_max].h;
  if ((band_high - band_low) * fit.height < kMinBandDiameters * d) {
    fit.reason = fmt::format(
        "no flank: the heap is {:.1f} grain diameters high, and its flank ({:.0f}-{:.0f} % of the "
        "height) spans less than {:.0f} grain layers (a spread-out layer, not a heap: too few "
        "grains, or they landed too fast)",
        fit.height / d, 100 * band_low, 100 * band_high, kMinBandDiameters);
    return fit;
  }

  // 5. Flank: between the band limits, and before the profile first drops below the band.
  const double h_low = band_low * fit.height, h_high = band_high * fit.height;
  std::vector<ProfilePoint> flank;
  for (std::size_t k = i_max; k < profile.size() && profile[k].h >= h_low; ++k) {
    if (profile[k].h <= h_high) flank.push_back(profile[k]);
  }
  fit.points_used = static_cast<int>(flank.size());
  if (fit.points_used < kMinFlankPoints) {
    fit.reason = "only " + std::to_string(fit.points_used) + " profile points on the flank (need " +
                 std::to_string(kMinFlankPoints) + ")";
    return fit;
  }

  // 6. Least-squares line through the flank.
  std::vector<double> flank_r, flank_h;
  for (const auto& q : flank) {
    flank_r.push_back(q.r);
    flank_h.push_back(q.h);
  }
  const LineFit line = fit_line(flank_r, flank_h);
  fit.fit_rms = line.rms();
  if (!(line.slope < 0)) {
    fit.reason = "the flank does not descend away from the apex";
    return fit;
  }
  fit.repose_angle_deg = line.descent_deg();
  fit.repose_angle_se_deg = line.descent_se_deg();
  fit.base_radius = -line.intercept / line.slope;
  fit.ok = true;
  return fit;
}

}  // namespace sandflow
