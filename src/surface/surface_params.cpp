#include "surface/surface_params.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <optional>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include "config/emitter_region.hpp"
#include "core/error.hpp"

namespace sandflow {

namespace {
Real gravity_magnitude(const SceneConfig& s) {
  return norm(s.simulation.gravity);
}
}  // namespace

Real rolling_min(const SceneConfig& scene) {
  return scene.surface.rolling_min.value_or(scene.material.diameter);
}

Real flowing_min(const SceneConfig& scene) {
  return scene.surface.flowing_min.value_or(2 * scene.material.diameter);
}

Real interface_thickness(const SceneConfig& scene) {
  // half a diameter: the invariant of the layers, not the band, keeps grains out of the static
  // layer (docs/physics.md), and a thinner band simulates fewer grains
  return scene.surface.interface_thickness.value_or(0.5 * scene.material.diameter);
}

std::optional<Vec3> throw_landing(const SceneConfig& scene, const EmitterConfig& e,
                                  const Geometry& geometry) {
  const Vec3 gravity = scene.simulation.gravity;
  const Vec3 p = e.center;
  const Vec3 v = e.velocity;
  if (e.type == EmitterType::Bed || (v.x == 0 && v.y == 0) || gravity.x != 0 || gravity.y != 0 ||
      !(gravity.z < 0))
    return std::nullopt;
  const Real g = -gravity.z;
  // the ground looked up twice: under the centre, then under the first landing
  Vec3 landing = p;
  for (int pass = 0; pass < 2; ++pass) {
    const Real ground = geometry.top_below(landing.x, landing.y, p.z, p.z - 1e3);
    if (!(ground > p.z - 1e3)) return std::nullopt;
    const Real t = (v.z + std::sqrt(v.z * v.z + 2 * g * (p.z - ground))) / g;
    landing = {p.x + v.x * t, p.y + v.y * t, ground};
  }
  return landing;
}

HeapSize largest_heap(const SceneConfig& scene) {
  const Real d = scene.material.diameter;
  const Real grain_volume = kPi / 6 * d * d * d;
  std::int64_t heaped = 0;
  Real bed_top = 0;
  for (const EmitterConfig& e : scene.emitters) {
    if (e.type == EmitterType::Bed)
      bed_top = std::max(bed_top, e.height);
    else
      heaped += e.count;
  }
  const Real bulk = static_cast<Real>(heaped) * grain_volume / kHeapPacking;
  const Real t = std::tan(scene.surface.repose_angle);
  const Real radius = std::cbrt(3 * bulk / (kPi * t));
  return {radius * t + bed_top, radius};
}

SurfaceParams surface_params(const SceneConfig& scene, const Geometry& geometry, Real dt) {
  const SurfaceConfig& sc = scene.surface;
  const Real d = scene.material.diameter;
  const Real g = gravity_magnitude(scene);
  SurfaceParams p;
  HeightFieldParams& hf = p.grid;
  hf.cell = sc.cell_size.value_or(d);
  // 5 sqrt(g / d): at sqrt(g / d) the deposit lagged a growing heap by a grain or more of rolling
  // layer (floor scene, 20,000 grains: 10,537 grains simulated at the end against 7,429)
  hf.gamma = sc.exchange_rate.value_or(5 * std::sqrt(std::max(g, 1e-12) / d));
  hf.theta0 = sc.repose_angle;
  hf.theta_max = sc.max_angle.value_or(sc.repose_angle + deg_to_rad(6.0));
  hf.rolling_min = rolling_min(scene);
  hf.flowing_min = flowing_min(scene);
  hf.flowing_hold = sc.flowing_hold;
  // a grain that touches the static top: its bottom within half a diameter of it
  hf.erosion_reach = sc.erosion_reach.value_or(0.5 * d);
  hf.close_after = sc.close_after;
  hf.avalanche_depth = d;
  hf.gap = d;  // a quarter of d cut H at gaps left below grains held up from the side
  p.interface.thickness = interface_thickness(scene);
  SeatParams& seat = p.interface.seat;
  seat.gravity = g;
  seat.trap_speed = sc.trap_speed.value_or(-1.0);
  seat.flow_speed = sc.flow_speed.value_or(-1.0);
  // (the seat's bound as a speed, for a grain of the mean size at rest in its seat)
  const Real seat_speed = std::sqrt(2 * g * kSeatRise * d / 2);
  if (sc.trap_speed.value_or(seat_speed) > sc.flow_speed.value_or(seat_speed))
    throw InputError(fmt::format(
        "{}: surface.flow_speed = {:.4g} m/s is less than surface.trap_speed = {:.4g} m/s{}: a "
        "grain would move the static layer while slow enough to be trapped in it; set flow_speed "
        ">= trap_speed",
        scene.place({"surface.flow_speed", "surface.trap_speed"}),
        sc.flow_speed.value_or(seat_speed), sc.trap_speed.value_or(seat_speed),
        sc.flow_speed ? (sc.trap_speed ? "" : " (trap_speed unset: the seat's bound)")
                      : " (flow_speed unset: the seat's bound)"));
  p.interface.density = scene.material.density;
  p.interface.blows = sc.blows;
  p.interface.friction = scene.material.friction;
  p.interface.margin = 0.25 * d;
  // a tenth of the time a grain takes to fall its diameter: the surface moves less than that
  const Real interval = sc.update_interval.value_or(0.1 * std::sqrt(d / std::max(g, 1e-12)));
  p.update_steps = std::max(1, static_cast<int>(std::lround(interval / dt)));
  p.update_interval = p.update_steps * dt;

  // the extent: the scene's finite geometry and every emitter with room for the largest heap
  Real x0 = 0, y0 = 0, x1 = 0, y1 = 0, z_top = 0, z_floor = 0;
  bool have = false;
  auto grow = [&](Real ax, Real ay, Real bx, Real by) {
    x0 = have ? std::min(x0, ax) : ax;
    y0 = have ? std::min(y0, ay) : ay;
    x1 = have ? std::max(x1, bx) : bx;
    y1 = have ? std::max(y1, by) : by;
    have = true;
  };
  const Real heap = largest_heap(scene).radius + 4 * d;
  for (const EmitterConfig& e : scene.emitters) {
    const Vec3 half = emitter_half_extent(e);
    // (a bed lies in its footprint: the heap of every grain around it would be a grid many times
    // its area)
    const Real m = e.type == EmitterType::Bed ? 4 * d : heap;
    grow(e.center.x - half.x - m, e.center.y - half.y - m, e.center.x + half.x + m,
         e.center.y + half.y + m);
    z_top = std::max(z_top, e.center.z + std::max(e.size.z, half.z));
    z_floor = std::min(z_floor, e.center.z - std::max(e.size.z, half.z));
  }
  Vec3 lo, hi;
  if (geometry.finite_bounds(lo, hi)) {
    grow(lo.x, lo.y, hi.x, hi.y);
    z_top = std::max(z_top, hi.z);
    z_floor = std::min(z_floor, lo.z);
  }
  // a throw that comes down beyond all that (a jet, a pour or a block thrown sideways over open
  // ground): room for its heap where it lands and along the way its grains run out on, or they
  // would stay simulated. A grain keeps its speed across the throw, v_h, and rolls on against the
  // ground's rolling resistance mu_r for at most v_h^2 / (2 mu_r g) (ten heaps' radii without it)
  for (const EmitterConfig& e : scene.emitters) {
    const std::optional<Vec3> at = throw_landing(scene, e, geometry);
    if (!at || (have && at->x >= x0 && at->x <= x1 && at->y >= y0 && at->y <= y1)) continue;
    const Vec3 half = emitter_half_extent(e);
    const Real vh = std::hypot(e.velocity.x, e.velocity.y);
    const Real mu_r = scene.material.wall_rolling_friction;
    const Real run = mu_r > 0 ? std::min(vh * vh / (2 * mu_r * g), 10 * heap) : 10 * heap;
    const Real ex = at->x + e.velocity.x / vh * run, ey = at->y + e.velocity.y / vh * run;
    grow(std::min(at->x, ex) - half.x - heap, std::min(at->y, ey) - half.y - heap,
         std::max(at->x, ex) + half.x + heap, std::max(at->y, ey) + half.y + heap);
  }
  if (sc.extent) {
    x0 = (*sc.extent)[0], y0 = (*sc.extent)[1], x1 = (*sc.extent)[2], y1 = (*sc.extent)[3];
    have = true;
  }
  if (!have) x0 = y0 = -heap, x1 = y1 = heap;
  const Real nxf = std::ceil((x1 - x0) / hf.cell), nyf = std::ceil((y1 - y0) / hf.cell);
  if (!(nxf * nyf <= static_cast<Real>(kMaxHeightFieldColumns)))  // NaN too
    throw InputError(fmt::format(
        "{}: the height field would need {:.0f} x {:.0f} columns of {:.4g} m (at most {}){}: set a "
        "larger surface.cell_size or a smaller surface.extent{}",
        scene.place({"surface.extent", "surface.cell_size"}), nxf, nyf, hf.cell,
        kMaxHeightFieldColumns,
        sc.extent ? ""
                  : fmt::format(" to cover the emitters, where they throw, the heap of {} grains "
                                "and the geometry",
                                scene.total_grains()),
        sc.extent ? "" : ", or ask for fewer grains"));
  hf.nx = std::max(1, static_cast<int>(nxf));
  hf.ny = std::max(1, static_cast<int>(nyf));
  // centre the whole columns on the extent
  hf.x0 = 0.5 * (x0 + x1) - 0.5 * hf.nx * hf.cell;
  hf.y0 = 0.5 * (y0 + y1) - 0.5 * hf.ny * hf.cell;
  // ... or centre a bed's footprint (or else the inside of the first box container standing
  // square to the axes) on whole columns, so that every column holding its grains has its centre
  // inside, and the container's walls there run between columns (a footprint a whole number of
  // cells wide) or through the outermost columns, their centres inside: a column whose centre
  // lay on a wall would have the wall's top as its level and leave the grains beside the wall
  // simulated
  std::optional<std::pair<Vec3, Vec3>> footprint;  // centre, size
  for (const EmitterConfig& e : scene.emitters)
    if (e.type == EmitterType::Bed && !footprint) footprint = {e.center, e.size};
  for (const GeometryConfig& box : scene.geometry)
    if (box.type == GeometryType::Box && box.container && box.rotation_deg == Vec3{0, 0, 0} &&
        !footprint)
      footprint = {box.center, box.size};
  if (footprint && !sc.extent) {
    auto align = [&](Real& origin, int& n, Real low_side, Real width) {
      // the columns' edge below the footprint: half of what a whole number of columns has over
      const Real cols = width / hf.cell, whole = std::ceil(cols - 1e-6);
      const Real edge = low_side - (whole > cols ? 0.5 * (whole - cols) * hf.cell : 0.0);
      const Real shift = edge - origin - std::floor((edge - origin) / hf.cell) * hf.cell;
      if (shift == 0 || !std::isfinite(shift)) return;
      origin += shift - hf.cell;  // (one column more keeps the extent covered)
      ++n;
    };
    const auto& [centre, size] = *footprint;
    align(hf.x0, hf.nx, centre.x - size.x / 2, size.x);
    align(hf.y0, hf.ny, centre.y - size.y / 2, size.y);
  }
  p.z_top = z_top + 1;
  p.z_floor = z_floor - 1;
  return p;
}

namespace {

using Intervals = std::vector<std::pair<Real, Real>>;

// Where a wall may stand between two column centres: the columns under a finite solid's
// footprint, and one column around it (the edges from them). The infinite solids, half-spaces,
// make none: where they hold up the sand, their union's top is the highest of planes (or the
// whole line, under a vertical or downward-facing one), and along an edge that highest is a convex
// function, never above both ends; a half-plane holding the whole line holds an end too.
std::vector<std::uint8_t> wall_candidates(const HeightFieldParams& grid, const Geometry& geometry) {
  const std::size_t columns = static_cast<std::size_t>(grid.nx) * grid.ny;
  std::vector<std::uint8_t> near(columns, 0);
  auto mark = [&](const Vec3& lo, const Vec3& hi) {
    if (!(lo.x <= hi.x && lo.y <= hi.y)) return;  // (a removed solid)
    if (!std::isfinite(lo.x) || !std::isfinite(lo.y) || !std::isfinite(hi.x) ||
        !std::isfinite(hi.y))
      return;
    auto first = [&](Real v, Real origin, int n) {
      return std::clamp(static_cast<int>(std::floor((v - origin) / grid.cell)) - 1, 0, n - 1);
    };
    for (int j = first(lo.y, grid.y0, grid.ny);
         j <= first(hi.y, grid.y0, grid.ny) + 1 && j < grid.ny; ++j)
      for (int i = first(lo.x, grid.x0, grid.nx);
           i <= first(hi.x, grid.x0, grid.nx) + 1 && i < grid.nx; ++i)
        near[static_cast<std::size_t>(j) * grid.nx + i] = 1;
  };
  for (const Obstacle& o : geometry.obstacles()) {
    Vec3 lo, hi;
    o.solid->bounds(lo, hi);
    mark(lo, hi);
  }
  for (const MeshObstacle& m : geometry.meshes()) {
    const Aabb box = mesh_bounds(m.mesh);
    const Vec3 pad{m.particle_radius, m.particle_radius, m.particle_radius};
    if (!box.empty()) mark(box.lo - pad, box.hi + pad);
  }
  return near;
}

// The grid's rows traced in parallel by trace(j, row, asked) (filling row, one entry a column,
// adding the solids it asked to asked; it may stop early once `over` is set) and handed to
// keep(row) in order. The queries are counted row by row, in order, so the refusal past `budget`
// does not depend on the threads.
template <class Entry, class Trace, class Keep>
void trace_rows(const HeightFieldParams& grid, std::uint64_t budget, std::uint64_t& queries,
                std::atomic<bool>& over, Trace&& trace, Keep&& keep) {
  std::vector<Entry> row(static_cast<std::size_t>(grid.nx));
#pragma omp parallel for ordered schedule(static, 1) firstprivate(row)
  for (int j = 0; j < grid.ny; ++j) {
    std::uint64_t asked = 0;
    trace(j, row, asked);
#pragma omp ordered
    if (!over) {
      queries += asked;
      if (queries > budget)
        over = true;
      else
        keep(row);
    }
  }
}

// Whether column c of t has a solid whose top lies within `margin` below `top`, reaching up to
// it: a solid on the edge no higher than that is the column's own.
bool holds_up_to(const TerrainColumns& t, std::size_t c, Real top, Real margin) {
  for (std::uint32_t k = t.start[c]; k < t.start[c + 1]; ++k)
    if (t.bottom[k] <= top && t.top[k] >= top - margin) return true;
  return false;
}

// The lines on an edge between two column centres, as fractions of the way: evenly spaced, at
// most half the thinnest finite solid's width apart (so that one of them lies well inside it, not
// on a face where rounding decides: a container's inner face lies on a column edge) and at least
// three; at most kMaxWallLines.
std::vector<Real> wall_lines(const HeightFieldParams& grid, const Geometry& geometry) {
  Real thinnest = std::numeric_limits<Real>::infinity();
  for (const Obstacle& o : geometry.obstacles())
    thinnest = std::min(thinnest, o.solid->least_width());
  for (const MeshObstacle& m : geometry.meshes())  // (its grains rest on particles of this radius)
    thinnest = std::min(thinnest, 2 * m.particle_radius);
  const Real wanted = std::ceil(2 * grid.cell / thinnest) - 1;
  const int n = wanted > kMaxWallLines ? kMaxWallLines : std::max(3, static_cast<int>(wanted));
  std::vector<Real> f;
  for (int k = 1; k <= n; ++k) f.push_back(static_cast<Real>(k) / (n + 1));
  return f;
}

// The walls on each column's +x and +y edges (TerrainColumns): the solids met by the vertical
// lines of wall_lines() between it and the neighbour's centre, where they stand higher than both
// columns' own solids there by more than a quarter of a column (less is a bump the columns' own
// tops already give, to a quarter column).
void add_walls(const SurfaceParams& p, const Geometry& geometry, std::uint64_t budget,
               std::uint64_t& queries, TerrainColumns& t, std::atomic<bool>& over) {
  const HeightFieldParams& grid = p.grid;
  const std::vector<Real> lines = wall_lines(grid, geometry);
  const Real margin = 0.25 * grid.cell;
  const std::vector<std::uint8_t> near = wall_candidates(grid, geometry);
  std::vector<std::uint32_t> wall_start{0};
  std::vector<TerrainColumns::Wall> walls;
  using Found = std::vector<TerrainColumns::Wall>;
  auto trace = [&](int j, std::vector<Found>& row, std::uint64_t& asked) {
    Intervals met;
    for (int i = 0; i < grid.nx && !over.load(std::memory_order_relaxed); ++i) {
      const std::size_t c = static_cast<std::size_t>(j) * grid.nx + i;
      Found& found = row[static_cast<std::size_t>(i)];
      found.clear();
      if (!near[c]) continue;
      const Real x = grid.x0 + (i + 0.5) * grid.cell, y = grid.y0 + (j + 0.5) * grid.cell;
      for (std::uint8_t axis = 0; axis < 2; ++axis) {
        if (axis == 0 ? i + 1 == grid.nx : j + 1 == grid.ny) continue;
        const std::size_t n = axis == 0 ? c + 1 : c + static_cast<std::size_t>(grid.nx);
        met.clear();
        for (const Real f : lines) {
          const Intervals s = geometry.solid_intervals(x + (axis == 0 ? f * grid.cell : 0),
                                                       y + (axis == 1 ? f * grid.cell : 0), p.z_top,
                                                       p.z_floor, &asked);
          met.insert(met.end(), s.begin(), s.end());
        }
        std::sort(met.begin(), met.end());
        for (std::size_t k = 0; k < met.size();) {
          // the union of what the lines met: one solid on the edge
          Real bottom = met[k].first, top = met[k].second;
          for (++k; k < met.size() && met[k].first <= top; ++k) top = std::max(top, met[k].second);
          if (!holds_up_to(t, c, top, margin) && !holds_up_to(t, n, top, margin))
            found.push_back({axis, bottom, top});
        }
      }
    }
  };
  trace_rows<Found>(grid, budget, queries, over, trace, [&](const std::vector<Found>& row) {
    for (const Found& w : row) {
      walls.insert(walls.end(), w.begin(), w.end());
      wall_start.push_back(static_cast<std::uint32_t>(walls.size()));
    }
  });
  t.wall_start = std::move(wall_start);
  t.walls = std::move(walls);
}

}  // namespace

TerrainColumns terrain_columns(const SurfaceParams& p, const Geometry& geometry,
                               std::uint64_t budget) {
  const HeightFieldParams& grid = p.grid;
  TerrainColumns t;
  // each column asks every solid, so this is the slow part of building a large field
  std::uint64_t queries = 0;
  std::atomic<bool> over{false};
  auto trace = [&](int j, std::vector<Intervals>& row, std::uint64_t& asked) {
    for (int i = 0; i < grid.nx && !over.load(std::memory_order_relaxed); ++i) {
      Intervals& solids = row[static_cast<std::size_t>(i)];
      solids =
          geometry.solid_intervals(grid.x0 + (i + 0.5) * grid.cell, grid.y0 + (j + 0.5) * grid.cell,
                                   p.z_top, p.z_floor, &asked);
      if (solids.empty()) solids.push_back({-std::numeric_limits<Real>::infinity(), p.z_floor});
    }
  };
  trace_rows<Intervals>(grid, budget, queries, over, trace, [&](const std::vector<Intervals>& row) {
    for (const Intervals& solids : row) t.add_column(solids);
  });
  if (!over) add_walls(p, geometry, budget, queries, t, over);
  if (over)
    throw InputError(fmt::format(
        "tracing the height field's {} x {} columns of {:.4g} m down through the scene's {} "
        "solids asked them more than {} times: set a larger "
        "surface.cell_size or a smaller surface.extent, or use fewer or fewer layered solids",
        grid.nx, grid.ny, grid.cell, geometry.obstacles().size() + geometry.meshes().size(),
        budget));
  return t;
}

}  // namespace sandflow
