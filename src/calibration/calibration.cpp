#include "calibration/calibration.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <unordered_map>

#include <fmt/format.h>

#include "analysis/statistics.hpp"
#include "core/error.hpp"
#include "core/hash.hpp"
#include "core/timer.hpp"
#include "sim/world.hpp"

namespace sandflow {

namespace {

// Bumped whenever the rig or the procedure changes, so that no cached angle outlives its method.
// (A change of the DEM's results needs no bump: the key holds dem_fingerprint.)
constexpr std::uint32_t kRigVersion = 1;

struct OnBase {
  std::vector<Vec3> x;
  std::vector<Real> r;
};

// The grains resting on the base: centre above its top (less a radius, for one pressed into it)
// and within its rim.
OnBase grains_on_base(const World& w, Real base_radius) {
  OnBase b;
  const Grains& g = w.grains();
  for (std::size_t i = 0; i < g.size(); ++i)
    if (g.x[i].z > 0 && std::hypot(g.x[i].x, g.x[i].y) <= base_radius + g.r[i]) {
      b.x.push_back(g.x[i]);
      b.r.push_back(g.r[i]);
    }
  return b;
}

// The angle of a cone standing on the base's axis: the top-surface map (the highest grain top in
// each square cell of side d) fitted by a line h = a - tan(θ) ρ over the cells whose top grain
// lies between kFitInner and kFitOuter of the base's radius from the axis, and within 45 degrees
// of `dir` when `wedge` is set. Every cell counts, not ring medians: the small heap of the rig has
// too few rings for those. Heights are in gravity's frame, tilted by `tilt` about x.
constexpr Real kFitInner = 0.25, kFitOuter = 0.9;

ConeFit cone_fit(const OnBase& b, Real d, Real base_radius, Real tilt, bool wedge) {
  const Real c = std::cos(tilt), s = std::sin(tilt);
  std::unordered_map<std::uint64_t, std::pair<Real, Real>> top;  // cell -> (rho, height)
  for (std::size_t i = 0; i < b.x.size(); ++i) {
    const Vec3& p = b.x[i];
    const Vec3 q{p.x, p.y * c + p.z * s, p.z * c - p.y * s};  // in gravity's frame
    const Real rho = std::hypot(q.x, q.y);
    if (rho < kFitInner * base_radius || rho > kFitOuter * base_radius * (wedge ? c : 1)) continue;
    if (wedge && q.y < std::abs(q.x)) continue;  // downhill is +y
    const auto ci = static_cast<std::int32_t>(std::floor(q.x / d));
    const auto cj = static_cast<std::int32_t>(std::floor(q.y / d));
    const std::uint64_t key = (static_cast<std::uint64_t>(static_cast<std::uint32_t>(ci)) << 32) |
                              static_cast<std::uint32_t>(cj);
    const Real h = q.z + b.r[i];
    auto [it, fresh] = top.try_emplace(key, rho, h);
    if (!fresh && h > it->second.second) it->second = {rho, h};
  }
  ConeFit f;
  f.cells = static_cast<int>(top.size());
  if (f.cells < 8) return f;
  // (in cell order, so that the sums do not depend on the map's layout)
  std::vector<std::pair<std::uint64_t, std::pair<Real, Real>>> cells(top.begin(), top.end());
  std::sort(cells.begin(), cells.end());
  std::vector<double> rho, h;
  for (const auto& [k, v] : cells) {
    rho.push_back(v.first);
    h.push_back(v.second);
  }
  const LineFit line = fit_line(rho, h);
  if (!(line.slope < 0)) return f;
  f.ok = true;
  f.angle_deg = line.descent_deg();
  f.se_deg = line.descent_se_deg();
  return f;
}

}  // namespace

std::uint64_t dem_fingerprint(const SceneConfig& scene) {
  // A small rig: a block of grains thrown sideways onto a base of radius 3 d, so that they
  // collide, slide, roll, spin and leave over its rim, for kFingerprintFrames times the grain's
  // time scale sqrt(d / g) (0.19 s for 1 cm grains); speeds and times follow the grain's size, so
  // the probe costs alike at any size. Its state after that is as sensitive to the code
  // that computed it as the calibration is.
  SceneConfig probe = calibration_rig(scene, 1, RigSettings{.base_diameters = 3});
  probe.simulation.threads = 1;
  const Real d = scene.material.diameter, g = norm(scene.simulation.gravity);
  probe.output.fps = std::sqrt(g / d);  // a frame: sqrt(d / g)
  EmitterConfig block;
  block.type = EmitterType::Block;
  block.name = "fingerprint block";
  block.count = 40;
  const Real pitch = block.spacing * scene.material.largest_diameter();  // the block's lattice
  block.center = {0, 0, 3 * pitch};
  block.size = {5.5 * pitch, 5.5 * pitch, 2.5 * pitch};  // 5 x 5 x 2 sites
  block.velocity = Vec3{0.64, 0.32, -0.96} * std::sqrt(g * d);  // (0.2, 0.1, -0.3) m/s at 1 cm
  block.jitter = 0.5;
  probe.emitters = {block};
  World w(probe);
  for (int f = 0; f < kFingerprintFrames; ++f) w.advance_frame();
  return w.state_hash();
}

std::string calibration_key(const SceneConfig& scene, const RigSettings& rig) {
  return calibration_key(scene, rig, dem_fingerprint(scene));
}

std::string calibration_key(const SceneConfig& scene, const RigSettings& rig,
                            std::uint64_t fingerprint) {
  Hasher h;
  const MaterialConfig& m = scene.material;
  for (Real v : {m.density, m.diameter, m.diameter_spread, m.k_t_ratio, m.restitution,
                 m.tangential_damping_ratio, m.friction, m.rolling_friction,
                 m.rolling_stiffness_ratio, m.rolling_damping_ratio, m.wall_friction,
                 m.wall_rolling_friction, norm(scene.simulation.gravity)})
    h.add(v);
  h.add(m.twisting_friction);
  h.add(m.wall_twisting_friction);
  const StiffnessConfig& s = scene.stiffness;
  h.add(s.from_load);
  if (s.from_load) {
    h.add(s.max_overlap);
    h.add(s.impact_overlap);
  } else {
    h.add(m.k_n);
  }
  h.add(scene.simulation.dt_fraction);
  h.add(rig.base_diameters);
  h.add(rig.tilt_rate);
  h.add(kRigVersion);
  h.add(fingerprint);
  return fmt::format("{:016x}", h.value());
}

SceneConfig calibration_rig(const SceneConfig& scene, std::uint64_t seed,
                            const RigSettings& settings) {
  const Real d = scene.material.diameter;
  const Real d_max = scene.material.largest_diameter();
  const Real g = norm(scene.simulation.gravity);
  if (!(g > 0))
    throw InputError(fmt::format("{}: calibration needs gravity (simulation.gravity is zero)",
                                 scene.place({"simulation.gravity"})));
  SceneConfig rig;
  rig.path = scene.path + " (calibration rig)";
  rig.name = "calibration";
  rig.material = scene.material;
  rig.stiffness = scene.stiffness;
  rig.stiffness.impact_speed.reset();
  rig.stiffness.dem_depth.reset();
  rig.stiffness.surface_depth.reset();
  rig.simulation.mode = Mode::Dem;
  rig.simulation.gravity = {0, 0, -g};
  rig.simulation.seed = seed;
  rig.simulation.threads = scene.simulation.threads;
  rig.simulation.dt_fraction = scene.simulation.dt_fraction;
  rig.simulation.dt.reset();

  // the base: a solid cylinder whose top is z = 0
  const Real base_radius = settings.base_diameters * d;
  GeometryConfig base;
  base.type = GeometryType::Cylinder;
  base.name = "base";
  base.radius = base_radius;
  base.height = 4 * d;
  base.center = {0, 0, -2 * d};
  rig.geometry = {base};

  // a heap at 45 degrees at most: the pour starts three diameters above its apex, a stream of
  // radius 2.5 d at 0.5 m/s (what the pattern lets through, 3/4 of its most); 1.5 times the
  // grains of that cone at packing 0.6 reach the rim and overflow it
  const Real apex = base_radius;
  const Real cone = std::numbers::pi / 3 * base_radius * base_radius * apex;
  const Real grain = std::numbers::pi / 6 * d * d * d;
  EmitterConfig pour;
  pour.type = EmitterType::Pour;
  pour.name = "calibration pour";
  pour.shape = PourShape::Disk;
  pour.center = {0, 0, apex + 3 * d};
  pour.radius = 2.5 * d_max;
  pour.velocity = {0, 0, -0.5};
  pour.count = static_cast<std::int64_t>(std::ceil(1.5 * 0.6 * cone / grain));
  pour.jitter = 0.5;
  pour.rate = 1;
  pour.rate = 0.75 * Emitter(pour, rig.material, rig.simulation.gravity, rig.path).max_rate();
  rig.emitters = {pour};

  // grains that overflow fall past the base's bottom and leave: nothing simulates their fall
  const Real side = base_radius + 20 * d;
  rig.simulation.domain =
      std::array<Real, 6>{-side, -side, -4 * d - d_max, side, side, apex + 10 * d};
  rig.simulation.on_leave = OnLeave::Count;
  rig.output.fps = 30;
  rig.output.settle_time = 1.0;
  rig.output.write_frames = false;
  return rig;
}

Calibration calibrate(const SceneConfig& scene, int trials, const CalibrationProgress& progress,
                      const RigSettings& settings) {
  Calibration cal;
  cal.key = calibration_key(scene, settings);
  cal.rig = settings;
  const Stopwatch total;
  std::vector<double> theta_poured, theta_max, theta_stop;
  const Real base_radius = settings.base_diameters * scene.material.diameter;
  for (int k = 0; k < trials; ++k) {
    const Stopwatch timer;
    CalibrationTrial t;
    t.seed = scene.simulation.seed + static_cast<std::uint64_t>(k);
    const SceneConfig rig = calibration_rig(scene, t.seed, settings);
    World w(rig);
    const int pour_frames = w.planned_frames();
    for (int f = 0; f < pour_frames; ++f) {
      w.advance_frame();
      if (progress) progress(k, "pour", w.time());
    }
    OnBase heap = grains_on_base(w, base_radius);
    t.grains_on_base = static_cast<std::int64_t>(heap.x.size());
    t.heap = measure_heap(heap.x, heap.r, 0.0);
    t.poured = cone_fit(heap, scene.material.diameter, base_radius, 0, false);
    if (t.poured.ok) {
      t.theta0_deg = t.poured.angle_deg;
      // tilt gravity about x, a little every step of a frame's worth, until the heap fails
      const Real g = norm(rig.simulation.gravity);
      const Real frame_dt = 1.0 / rig.output.fps;
      const auto lost_enough = [&] {
        return static_cast<Real>(grains_on_base(w, base_radius).x.size()) <
               (1 - kFailureLoss) * static_cast<Real>(t.grains_on_base);
      };
      Real tilt = 0;
      while (tilt < kMaxTilt) {
        tilt = std::min(kMaxTilt, tilt + settings.tilt_rate * frame_dt);
        const Real a = deg_to_rad(tilt);
        w.set_gravity({0, g * std::sin(a), -g * std::cos(a)});
        w.advance_frame();
        if (progress) progress(k, "tilt", w.time());
        if (lost_enough()) {
          t.failed = true;
          break;
        }
      }
      t.tilt_deg = tilt;
      t.theta_max_deg = t.theta0_deg + tilt;
      if (t.failed) {
        // the avalanche runs out at that tilt and stops: its downhill flank is θ_stop
        const int stop_frames = static_cast<int>(std::ceil(kStopTime * rig.output.fps));
        for (int f = 0; f < stop_frames; ++f) {
          w.advance_frame();
          if (progress) progress(k, "stop", w.time());
        }
        t.stop = cone_fit(grains_on_base(w, base_radius), scene.material.diameter, base_radius,
                          deg_to_rad(tilt), true);
        t.theta_stop_deg = t.stop.angle_deg;
      }
      theta_poured.push_back(t.theta0_deg);
      if (t.failed) theta_max.push_back(t.theta_max_deg);
      if (t.failed && t.stop.ok) theta_stop.push_back(t.theta_stop_deg);
    }
    t.seconds = timer.seconds();
    cal.trials.push_back(std::move(t));
  }
  cal.seconds = total.seconds();
  if (theta_poured.empty())
    throw InputError(fmt::format(
        "{}: calibration: no trial made a heap that could be measured ({}); the material does "
        "not pile on a rough base",
        scene.path, cal.trials.empty() ? "no trials" : "too few cells on the flank"));
  if (theta_max.empty())
    throw InputError(fmt::format(
        "{}: calibration: the heap still stood with gravity tilted by {:.0f} degrees: θ_max is "
        "above {:.1f} degrees; set surface.max_angle",
        scene.path, kMaxTilt, mean(theta_poured) + kMaxTilt));
  cal.theta0_deg = mean(theta_poured);
  cal.theta0_sd_deg = standard_deviation(theta_poured);
  cal.theta_stop_deg = theta_stop.empty() ? 0 : mean(theta_stop);
  cal.theta_stop_sd_deg = standard_deviation(theta_stop);
  cal.theta_max_deg = mean(theta_max);
  cal.theta_max_sd_deg = standard_deviation(theta_max);
  return cal;
}

}  // namespace sandflow
