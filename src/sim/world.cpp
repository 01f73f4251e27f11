#include "sim/world.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>

#include <fmt/format.h>

#include "config/emitter_region.hpp"
#include "core/assert.hpp"
#include "core/error.hpp"
#include "core/hash.hpp"
#include "geometry/mesh_sampling.hpp"

namespace sandflow {

TimeStep choose_time_step(const SceneConfig& scene) {
  const MaterialConfig& mat = scene.material;
  const Real r_min = 0.5 * mat.smallest_diameter();
  const Real m_min = mat.density * (4.0 / 3.0) * kPi * r_min * r_min * r_min;
  TimeStep ts;
  ts.t_c = contact_time(m_min / 2, mat.k_n);
  // (each number is in its range, but a product of them can overflow: 1e300 m grains)
  if (!(std::isfinite(m_min) && m_min > 0 && std::isfinite(ts.t_c) && ts.t_c > 0))
    throw InputError(fmt::format(
        "{}: material.density = {:.4g} kg/m^3, diameter = {:.4g} m and k_n = {:.4g} N/m give a "
        "grain mass of {:.4g} kg and a contact time of {:.4g} s: not finite positive numbers",
        scene.place({"material.density", "material.diameter", "material.k_n"}), mat.density,
        mat.diameter, mat.k_n, m_min, ts.t_c));
  // A grain resting on the floor sinks m g / k_n into it; past the guard's overlap the run would
  // stop as soon as the heaviest grain lands (k_n = 1e-300 N/m, or a density of 1e300 kg/m^3).
  const Real r_max = 0.5 * mat.largest_diameter();
  const Real m_max = mat.density * (4.0 / 3.0) * kPi * r_max * r_max * r_max;
  const Real sink = m_max * norm(scene.simulation.gravity) / mat.k_n;
  const Real guard = scene.simulation.max_overlap_stop * 2 * r_max;
  if (!(sink <= guard))
    throw InputError(fmt::format(
        "{}: material.density = {:.4g} kg/m^3, diameter = {:.4g} m and k_n = {:.4g} N/m: the "
        "heaviest grain, resting on the floor under gravity {:.4g} m/s^2, would sink {:.4g} m "
        "into it, more than simulation.max_overlap_stop = {:.0f} % of its diameter ({:.4g} m); "
        "raise k_n or lower the density",
        scene.place({"material.k_n", "material.density", "material.diameter"}), mat.density,
        mat.diameter, mat.k_n, norm(scene.simulation.gravity), sink,
        100 * scene.simulation.max_overlap_stop, guard));
  // Symplectic Euler on one spring is stable below 2/omega = 0.64 t_c; a grain held by many
  // contacts vibrates up to ~3x faster, so the bound keeps that factor: t_c / 5. The explicit
  // dashpot takes c dt / m_eff = 2 beta omega dt of the relative speed in a step: past 1 it
  // overshoots, past 2 it grows; with the same factor of 3 for many contacts, dt <= t_c / (3 pi
  // beta), which binds only for restitutions below about 0.05 (beta > 1.7).
  const Real beta = damping_beta(mat.restitution);
  const Real damping_bound = beta > 0 ? ts.t_c / (3 * kPi * beta) : ts.t_c;
  ts.stable_bound = std::min(ts.t_c / 5, damping_bound);
  Real dt = scene.simulation.dt.value_or(
      std::min(scene.simulation.dt_fraction * ts.t_c, ts.stable_bound));
  if (dt > ts.stable_bound)
    throw InputError(fmt::format(
        "{}: simulation.dt = {:.4g} s is above the stable bound {:.4g} s ({}, with contact time "
        "t_c = {:.4g} s for the smallest grains at k_n = {:.4g} N/m)",
        scene.place({"simulation.dt"}), dt, ts.stable_bound,
        damping_bound < ts.t_c / 5
            ? fmt::format("t_c / (3 pi beta): the dashpot of material.restitution = {:.3g}, "
                          "beta = {:.3g}",
                          mat.restitution, beta)
            : std::string("t_c / 5"),
        ts.t_c, mat.k_n));
  const Real frame_dt = 1.0 / scene.output.fps;
  const Real steps = std::ceil(frame_dt / dt - 1e-9);
  if (!(steps <= kMaxSubsteps))
    throw InputError(fmt::format(
        "{}: a frame of {:.4g} s would take {:.4g} steps of dt = {:.4g} s, more than the limit of "
        "{:.0f}; raise simulation.dt, lower material.k_n or enlarge the grains",
        scene.place({"simulation.dt", "output.fps", "material.k_n"}), frame_dt, steps, dt,
        kMaxSubsteps));
  ts.substeps = std::max(1, static_cast<int>(steps));
  ts.dt = frame_dt / ts.substeps;
  return ts;
}

ContactParams contact_params(const MaterialConfig& m) {
  ContactParams p;
  p.k_n = m.k_n;
  p.beta = damping_beta(m.restitution);
  p.k_t = m.k_t_ratio * m.k_n;
  p.c_t_ratio = m.tangential_damping_ratio;
  p.mu = m.friction;
  p.k_r = m.rolling_stiffness_ratio * p.k_t;
  p.c_r_ratio = m.rolling_damping_ratio;
  p.mu_r = m.rolling_friction;
  p.mu_tw = m.twisting_friction;
  return p;
}

double simulated_fraction(std::span<const FrameStats> frames, std::size_t first) {
  double simulated = 0, all = 0;
  for (std::size_t k = first; k < frames.size(); ++k) {
    simulated += static_cast<double>(frames[k].n_active + frames[k].n_interface);
    all += static_cast<double>(frames[k].n_total);
  }
  return all > 0 ? simulated / all : 1.0;
}

void scale_grain_count(SceneConfig& scene, std::int64_t total) {
  // a bed keeps its region, so its grains: the other emitters make the rest
  std::int64_t beds = 0;
  for (const EmitterConfig& e : scene.emitters)
    if (e.type == EmitterType::Bed) beds += e.count;
  const std::int64_t old_total = scene.total_grains() - beds;
  if (beds > 0 && (old_total > 0 ? total <= beds : total != beds))
    throw InputError(fmt::format(
        "{}: --grains {}: the scene's beds hold {} grains, which --grains does not scale (a bed "
        "keeps its region){}",
        scene.path, total, beds,
        old_total > 0 ? "; ask for more, the other emitters making the rest"
                      : "; the scene has no other emitter"));
  total -= beds;
  if (old_total <= 0 || scene.emitters.empty()) return;
  std::vector<std::int64_t> old_counts;
  for (const EmitterConfig& e : scene.emitters) old_counts.push_back(e.count);
  // largest-remainder rounding, so the counts add up to exactly `total`
  std::vector<std::pair<double, std::size_t>> rem;
  std::int64_t sum = 0;
  for (std::size_t k = 0; k < scene.emitters.size(); ++k) {
    if (scene.emitters[k].type == EmitterType::Bed) continue;
    const double exact = static_cast<double>(scene.emitters[k].count) * static_cast<double>(total) /
                         static_cast<double>(old_total);
    scene.emitters[k].count = static_cast<std::int64_t>(std::floor(exact));
    sum += scene.emitters[k].count;
    rem.emplace_back(-(exact - std::floor(exact)), k);
  }
  std::sort(rem.begin(), rem.end());
  for (std::size_t q = 0; sum < total; ++q, ++sum)
    ++scene.emitters[rem[q % rem.size()].second].count;

  for (std::size_t k = 0; k < scene.emitters.size(); ++k) {
    EmitterConfig& e = scene.emitters[k];
    if (old_counts[k] <= 0 || e.count <= 0 || e.type == EmitterType::Bed) continue;
    const double ratio = static_cast<double>(e.count) / static_cast<double>(old_counts[k]);
    if (e.type == EmitterType::Pour) {
      e.rate *= ratio;
      e.rate_scale *= ratio;
      continue;
    }
    // the same box shape, from the same bottom; a box at least one spacing on every side holds a
    // grain, and growing it by 1 % a time reaches the count in a few dozen tries
    const Real bottom = e.center.z - e.size.z / 2;
    const Real spacing = e.spacing * scene.material.largest_diameter();
    const Vec3 shape = e.size;
    Real scale = std::cbrt(ratio);
    for (int tries = 0;; ++tries) {
      e.size = {std::max(shape.x * scale, spacing), std::max(shape.y * scale, spacing),
                std::max(shape.z * scale, spacing)};
      if (box_slots(e, scene.material) >= static_cast<Real>(e.count) || tries == 10000) break;
      scale *= 1.01;
    }
    e.center.z = bottom + e.size.z / 2;
  }
}

namespace {
DemParams dem_params(const SceneConfig& scene, const TimeStep& ts) {
  DemParams p;
  // five contact times: slow against the dashpot, which damps a contact within about one
  p.preload_relax_time = 5 * ts.t_c;
  p.contact = contact_params(scene.material);
  p.walls_resist_turning =
      scene.material.wall_rolling_friction > 0 || scene.material.wall_twisting_friction > 0;
  p.skin = scene.simulation.skin * scene.material.diameter;
  p.skin_steps = scene.simulation.skin_steps;
  p.skin_max = scene.simulation.skin_max * scene.material.diameter;
  p.sort_every = scene.simulation.sort_every;
  p.gravity = scene.simulation.gravity;
  return p;
}

// The meshes' particle surfaces (MeshObstacle::sample_spacing says how they are sampled).
BoundaryParticles boundary_particles(const Geometry& geometry, const std::string& scene_path) {
  BoundaryParticles b;
  for (std::uint32_t k = 0; k < geometry.meshes().size(); ++k) {
    const MeshObstacle& m = geometry.meshes()[k];
    if (b.radius > 0 && m.particle_radius != b.radius)
      throw InputError(fmt::format("{}: {}: particle_radius must be the same for every mesh of a scene",
                                   scene_path, m.name));
    b.radius = m.particle_radius;
    // (place_mesh has counted them against the scene's limit: sampling cannot refuse them now)
    const std::vector<Vec3> samples = sample_surface(m.mesh, m.sample_spacing(), m.sample_merge());
    for (const Vec3& p : samples) {
      b.x.push_back(p);
      b.group.push_back(k);
    }
    b.friction.push_back(m.friction);
    b.rolling_friction.push_back(m.rolling_friction);
    b.twisting_friction.push_back(m.twisting_friction);
  }
  return b;
}

SceneConfig with_stiffness(SceneConfig scene, const Stiffness& s) {
  scene.material.k_n = s.k_n;
  return scene;
}

// The box the grains must stay in: simulation.domain, or the box of the scene's finite parts
// (solids, meshes, planes' points, emitters, the height field's extent) widened on every side by
// its largest extent, at least 1 m: only a grain flung away by a blow-up, or falling past the end
// of the geometry, reaches a side. A floor (a plane facing up, within 45 degrees) has no end:
// grains may roll on it as far as they go (a bouncing 2 cm grain of a small pour was seen 1.1 m
// out), so x and y are then unbounded, and only falling through it or flying off is caught.
void scene_domain(const SceneConfig& scene, const Geometry& geometry, Vec3& lo, Vec3& hi) {
  if (const auto& d = scene.simulation.domain) {
    lo = {(*d)[0], (*d)[1], (*d)[2]};
    hi = {(*d)[3], (*d)[4], (*d)[5]};
    return;
  }
  lo = hi = Vec3{};  // (a scene of nothing: a box around the origin)
  bool any = geometry.finite_bounds(lo, hi);
  auto add = [&](const Vec3& a, const Vec3& b) {
    lo = any ? min(lo, a) : a;
    hi = any ? max(hi, b) : b;
    any = true;
  };
  for (const GeometryConfig& g : scene.geometry)
    if (g.type == GeometryType::Plane) add(g.point, g.point);
  for (const EmitterConfig& e : scene.emitters) {
    const Vec3 half = emitter_half_extent(e);
    add(e.center - half, e.center + half);
  }
  if (const auto& x = scene.surface.extent) add({(*x)[0], (*x)[1], lo.z}, {(*x)[2], (*x)[3], hi.z});
  const Vec3 ext = hi - lo;
  const Real m = std::max({1.0, ext.x, ext.y, ext.z});
  lo -= Vec3{m, m, m};
  hi += Vec3{m, m, m};
  for (const GeometryConfig& g : scene.geometry)
    if (g.type == GeometryType::Plane && g.normal.z > std::sqrt(0.5) * norm(g.normal)) {
      constexpr Real kInf = std::numeric_limits<Real>::infinity();
      lo.x = lo.y = -kInf;
      hi.x = hi.y = kInf;
    }
}
// The static store's frame (dem/grains.hpp): the height field's columns, the domain's heights
// widened by its height on both sides (as the checkpoint reader allows a grain), the material's
// radii. A frame that cannot hold a grain within 0.1 % of the smallest diameter is refused.
StaticFrame static_store_frame(const SceneConfig& scene, const HeightField& hf, Real lo, Real hi) {
  const MaterialConfig& mat = scene.material;
  const Real height = hi - lo;
  const StaticFrame f = static_frame(hf, lo - height, hi + height, 0.5 * mat.smallest_diameter(),
                                     0.5 * mat.largest_diameter());
  if (const std::string e = f.error(); !e.empty())
    throw InputError(
        fmt::format("{}: the static layer cannot be stored: {} (simulation.domain, "
                    "surface, material.diameter)",
                    scene.place({"simulation.domain", "surface"}), e));
  const Real bound = 1e-3 * mat.smallest_diameter();
  if (!(f.position_error() <= bound && f.radius_error() <= bound))
    throw InputError(fmt::format(
        "{}: the static layer would store a grain's centre within {:.3g} m and its radius within "
        "{:.3g} m, more than 0.1 % of the smallest diameter ({:.3g} m): its {} height steps span "
        "{:.4g} m (simulation.domain along z, {:.4g} m, widened by as much on either side) and its "
        "{} steps across a column {:.4g} m (surface.cell_size); narrow the domain along z, or "
        "the columns",
        scene.place({"simulation.domain", "surface.cell_size"}), f.position_error(),
        f.radius_error(), bound, std::uint64_t{1} << StaticStore::kZBits, f.z_hi - f.z_lo, height,
        1u << StaticStore::kXBits, f.cell));
  return f;
}
}  // namespace

World::World(const SceneConfig& scene)
    : geometry_(Geometry::from_config(scene.geometry, scene.material, scene.path)),
      stiffness_(choose_stiffness(scene, scene.simulation.mode, geometry_)),
      scene_(with_stiffness(scene, stiffness_)),
      ts_(choose_time_step(scene_)),
      dem_(dem_params(scene_, ts_)),
      rng_(scene.simulation.seed) {
  if (!geometry_.meshes().empty()) dem_.set_boundary(boundary_particles(geometry_, scene_.path));
  if (scene_.simulation.mode == Mode::Surface) {
    const SurfaceParams params = surface_params(scene_, geometry_, ts_.dt);
    try {
      surface_ = std::make_unique<SurfaceFlow>(params, geometry_);
    } catch (const InputError& e) {  // (the terrain's tracing budget: its keys are the scene's)
      throw InputError(fmt::format("{}: {}", scene_.path, e.what()));
    }
  }
  for (std::size_t k = 0; k < scene.emitters.size(); ++k) {
    const std::string table = fmt::format("emitter[{}]", k);
    const std::string where = scene.place({table}) + ": " + table;
    emitters_.emplace_back(scene.emitters[k], scene.material, scene.simulation.gravity, where);
    if (scene.emitters[k].type != EmitterType::Bed) continue;
    // a bed is packed again, the same as when the scene was loaded (resolve_beds), on this
    // geometry and seed
    BedPacking bed;
    if (const auto problem = pack_bed_emitter(scene.emitters[k], scene.material, geometry_,
                                              bed_seed(scene.simulation.seed, k), bed,
                                              kMaxBedGrains, scene.simulation.threads))
      throw InputError(fmt::format("{}.{} {}", where, problem->key, problem->what));
    emitters_.back().set_bed(std::move(bed), where);
  }
  scene_domain(scene_, geometry_, domain_lo_, domain_hi_);
  dem_.set_domain(domain_lo_, domain_hi_);
  if (surface_)
    static_ = StaticStore(
        static_store_frame(scene_, surface_->height_field(), domain_lo_.z, domain_hi_.z));
  // a solid removed at time t goes at the first step that starts at or after t
  for (const GeometryConfig& g : scene_.geometry)
    removal_step_.push_back(
        g.remove_at ? static_cast<std::int64_t>(std::ceil(*g.remove_at / ts_.dt - 1e-9)) : -1);
}

void World::remove_due_geometry(std::int64_t before, bool announce) {
  bool changed = false;
  for (std::size_t k = 0; k < removal_step_.size(); ++k)
    if (removal_step_[k] >= 0 && removal_step_[k] < before) {
      geometry_.remove_source(static_cast<int>(k));
      removal_step_[k] = -1;
      changed = true;
    }
  if (!changed) return;
  if (surface_) surface_->retrace_terrain(geometry_);
  if (announce) dem_.invalidate();  // its wall lists name the removed solids
}

std::vector<std::string> World::warnings() const {
  std::vector<std::string> out = geometry_.warnings();
  for (const Emitter& e : emitters_)
    if (!e.warning().empty()) out.push_back(e.warning());
  return out;
}

int World::planned_frames() const {
  if (scene_.output.frames) return *scene_.output.frames;
  Real duration = 0;
  const char* from = "output.duration";
  if (scene_.output.duration) {
    duration = *scene_.output.duration;
  } else {
    for (const Emitter& e : emitters_) duration = std::max(duration, e.end_time());
    duration += scene_.output.settle_time;
    from = "the emission (each emitter's start, count and rate) and output.settle_time";
  }
  // (counted in floating point and checked before the cast: an int would overflow)
  const Real frames = std::ceil(duration * scene_.output.fps - 1e-9);
  if (!(frames <= kMaxFrames))
    throw InputError(fmt::format(
        "{}: {} make a run of {:.4g} s, {:.4g} frames at output.fps = {:.4g}, more than the limit "
        "of {:.0f}; set output.duration, or --frames",
        scene_.place({"output.duration", "output.settle_time", "output.fps"}), from, duration,
        frames, scene_.output.fps, kMaxFrames));
  return std::max(1, static_cast<int>(frames));
}

void World::emit() {
  new_grains_.clear();
  for (Emitter& e : emitters_) {
    // no new grain is placed on one already there: a hot one, a static one, or one placed this
    // step by an earlier emitter
    nearby_x_.clear();
    nearby_r_.clear();
    // new grains need a new pair list: a batch waits for the list's next rebuild, a little
    if (e.due(time_) && !dem_.needs_rebuild() && time_ < e.next_time() + e.max_wait()) continue;
    if (e.due(time_)) {
      auto consider = [&](const Vec3& x, Real r) {
        if (e.near_slots(x, r)) {
          nearby_x_.push_back(x);
          nearby_r_.push_back(r);
        }
      };
      for (std::size_t i = 0; i < grains_.size(); ++i) consider(grains_.x[i], grains_.r[i]);
      // (the static grains of the columns under the pour only: a bed around it costs nothing)
      Vec3 lo, hi;
      e.near_box(static_.frame().r_hi, lo, hi);
      static_.for_each_near_box(lo, hi, [&](const StaticGrain& g) { consider(g.x, g.r); });
      for (const NewGrain& g : new_grains_) consider(g.x, g.r);
    }
    if (e.type() == EmitterType::Bed && surface_) {
      seat_bed(e);
      continue;
    }
    const std::size_t first = new_grains_.size();
    e.emit(time_, rng_, new_grains_, nearby_x_, nearby_r_);
    if (e.type() != EmitterType::Bed)  // (a bed is packed around the solids)
      check_emitted(static_cast<std::size_t>(&e - emitters_.data()), first);
  }
  if (new_grains_.empty()) return;
  for (const NewGrain& g : new_grains_)
    grains_.add(next_id_++, g.x, g.v, g.r, scene_.material.density);
  dem_.invalidate();
}

void World::check_emitted(std::size_t k, std::size_t first) const {
  // A grain born deep in a solid is a misplaced emitter or solid, not soft contacts: say so now,
  // rather than let the overlap guard stop the run with advice about k_n. (One born inside a
  // closed mesh touches none of its particles: the count of grains inside the geometry names it.)
  const Real limit = scene_.simulation.max_overlap_stop;
  auto named = [](const std::string& name, const std::string& fallback) {
    return name.empty() || name == fallback ? std::string() : fmt::format(" ('{}')", name);
  };
  for (std::size_t q = first; q < new_grains_.size(); ++q) {
    const NewGrain& g = new_grains_[q];
    for (const Obstacle& o : geometry_.obstacles()) {
      const Real depth = (g.r - o.solid->closest(g.x).distance) / (2 * g.r);
      if (!(depth > limit)) continue;
      const GeometryConfig& solid = scene_.geometry[static_cast<std::size_t>(o.source)];
      throw InputError(fmt::format(
          "{}: emitter[{}]{} places a grain at ({:.4g}, {:.4g}, {:.4g}) m {:.0f} % of its "
          "diameter inside geometry[{}]{} (more than simulation.max_overlap_stop = {:.0f} %): "
          "move the emitter or the solid",
          scene_.place({fmt::format("emitter[{}]", k)}), k,
          named(scene_.emitters[k].name, fmt::format("emitter {}", k)), g.x.x, g.x.y, g.x.z,
          100 * depth, o.source, named(solid.name, fmt::format("geometry {}", o.source)),
          100 * limit));
    }
  }
}

void World::seat_bed(Emitter& e) {
  std::vector<NewGrain> bed;
  e.emit(time_, rng_, bed, nearby_x_, nearby_r_);
  if (bed.empty()) return;
  std::vector<GrainId> ids(bed.size());
  std::vector<Vec3> x(bed.size());
  std::vector<Real> r(bed.size());
  for (std::size_t k = 0; k < bed.size(); ++k) {
    ids[k] = next_id_++;
    x[k] = bed[k].x;
    r[k] = bed[k].r;
  }
  surface_->seat_bed(grains_, static_, ids, x, r);
  dem_.invalidate();
}

// The step, stage by stage, in the order of docs/design.md §1; each stage is timed (--profile).
void World::step() {
  const bool update = surface_ && step_ % surface_->params().update_steps == 0;
  timed(profile_, Stage::Guards, [&] { begin_step(); });
  timed(profile_, Stage::Emit, [&] { emit(); });
  if (update) {
    timed(profile_, Stage::HeightField, [&] { update_height_field(); });
    timed(profile_, Stage::Impacts, [&] { apply_impacts(); });
  }
  if (surface_) timed(profile_, Stage::Transfer, [&] { transfer(update); });
  if (!leaving_.empty()) timed(profile_, Stage::Guards, [&] { remove_leaving(); });
  if (surface_ && dem_.needs_rebuild()) timed(profile_, Stage::Reach, [&] { hold_invariant(); });
  timed(profile_, Stage::Neighbours, [&] { dem_.update_lists(grains_, geometry_, ts_.dt); });
  // (forces and integration: one fused sweep, so one stage)
  timed(profile_, Stage::Forces, [&] { dem_.advance(grains_, geometry_, ts_.dt); });
  timed(profile_, Stage::Guards, [&] { end_step(); });
  ++step_;
  time_ = static_cast<Real>(step_) * ts_.dt;
}

void World::begin_step() {
  remove_due_geometry(step_ + 1, true);
  check_grains();
}

void World::update_height_field() {
  surface_->update_height_field(grains_, static_, dem_, geometry_,
                                surface_->params().update_interval);
  ++surface_updates_;
}

void World::apply_impacts() {
  surface_->apply_impacts(grains_, surface_->params().update_interval);
}

void World::transfer(bool after_update) {
  apply(after_update ? surface_->transfer(grains_, static_, dem_)
                     : surface_->catch_up(grains_, static_, dem_, geometry_));
}

void World::hold_invariant() {
  apply(surface_->wake_within_reach(grains_, static_, dem_, ts_.dt));
}

void World::apply(const Transitions& t) {
  transitions_ += t.counts;
  dem_.apply(t.changes);
}

void World::end_step() {
  check_overlap(step_ + 1);
  // (assertions) every grain held once, in the store of its state, as many as were emitted less
  // those that left (docs/design.md §2; advance_frame checks the count in every build), and the
  // INTERFACE grains at rest: frozen with v = w = 0, and the DEM moves ACTIVE grains only
  if constexpr (kAssertions) {
    const std::int64_t expected = static_cast<std::int64_t>(next_id_) - left_;
    if (static_.revision() != checked_.static_revision || grains_.id != checked_.ids ||
        grains_.state != checked_.states || next_id_ != checked_.next_id ||
        expected != checked_.expected) {
      const std::string fault = store_error(grains_, static_, next_id_, expected);
      SANDFLOW_ASSERT(fault.empty(), fmt::format("{}: {}", where(step_ + 1), fault));
      checked_ = {static_.revision(), grains_.id, grains_.state, next_id_, expected};
    }
    for (std::size_t i = 0; i < grains_.size(); ++i)
      SANDFLOW_ASSERT(grains_.state[i] == GrainState::Active ||
                          (grains_.v[i] == Vec3{} && grains_.w[i] == Vec3{}),
                      fmt::format("{}: the INTERFACE grain {} is not at rest", where(step_ + 1),
                                  grains_.id[i]));
  }
}

std::string World::where(std::int64_t step) const {
  return fmt::format("step {} (frame {}, t = {:.6f} s)", step, frame_ + 1,
                     static_cast<Real>(step) * ts_.dt);
}

void World::check_grains() {
  const Vec3 lo = domain_lo_, hi = domain_hi_;
  auto fine = [&](std::size_t i) {
    if (grains_.state[i] != GrainState::Active) return true;  // frozen grains do not move
    // (a NaN position fails the box's comparisons: the usual case costs one test per axis)
    return in_box(grains_.x[i], lo, hi) && is_finite(grains_.v[i]);
  };
  // every step: the sweep that moved the grains looked at each ACTIVE one's new position (nothing
  // moves a grain between it and this guard), else a parallel look; the grain-ordered walk below
  // only when something is wrong
  if (dem_.all_inside()) return;
  const std::size_t n = grains_.size();
  int wrong = 0;
#pragma omp parallel for schedule(static) reduction(max : wrong) if (n >= kParallelMinGrains)
  for (std::size_t i = 0; i < n; ++i)
    if (!fine(i)) wrong = 1;
  if (!wrong) return;
  for (std::size_t i = 0; i < n; ++i) {
    if (fine(i)) continue;
    const Vec3& x = grains_.x[i];
    if (!is_finite(x) || !is_finite(grains_.v[i]))
      throw SimulationError(fmt::format(
          "{}: grain {} has a non-finite position or velocity; the time step {:.3g} s may be too "
          "large for the contacts",
          where(step_), grains_.id[i], ts_.dt));
    if (scene_.simulation.on_leave == OnLeave::Count) {
      leaving_.push_back(grains_.id[i]);
      continue;
    }
    throw SimulationError(fmt::format(
        "{}: grain {} left the domain [{:.4g}, {:.4g}] x [{:.4g}, {:.4g}] x [{:.4g}, {:.4g}] m at "
        "({:.4g}, {:.4g}, {:.4g}) m, moving at ({:.4g}, {:.4g}, {:.4g}) m/s; to remove such grains "
        "and count them, set simulation.on_leave = \"count\", or widen simulation.domain",
        where(step_), grains_.id[i], lo.x, hi.x, lo.y, hi.y, lo.z, hi.z, x.x, x.y, x.z,
        grains_.v[i].x, grains_.v[i].y, grains_.v[i].z));
  }
}

void World::remove_leaving() {
  std::sort(leaving_.begin(), leaving_.end());
  std::vector<std::uint32_t> keep;
  keep.reserve(grains_.size());
  for (std::uint32_t i = 0; i < grains_.size(); ++i)
    if (!std::binary_search(leaving_.begin(), leaving_.end(), grains_.id[i])) keep.push_back(i);
  // (a grain the transfer has just put to sleep stays: it no longer moves)
  const auto removed = static_cast<std::int64_t>(grains_.size() - keep.size());
  grains_.permute(keep);
  for (GrainId id : leaving_) dem_.forget_history(id);
  dem_.invalidate();
  left_ += removed;
  left_frame_ += removed;
  leaving_.clear();
}

void World::check_overlap(std::int64_t after_step) {
  const Real limit = scene_.simulation.max_overlap_stop;
  const Real reached = dem_.counters().max_overlap_rel;
  if (!(reached > limit)) return;
  // the counter knows how deep, not where (it saw the state before the step moved it): look for
  // the deepest contact now
  const DeepestOverlap d = dem_.deepest_overlap(grains_, geometry_);
  std::string what;
  const GrainId a = d.kind == DeepestOverlap::kNone ? 0 : grains_.id[d.slot];
  switch (d.kind) {
    case DeepestOverlap::kGrain:
      what = fmt::format("grains {} and {} overlap by {:.0f} % of the smaller diameter", a,
                         grains_.id[d.other], 100 * d.rel);
      break;
    case DeepestOverlap::kWall: {
      const int src = geometry_.obstacles()[d.other].source;
      what = fmt::format("grain {} overlaps geometry[{}] ('{}') by {:.0f} % of its diameter", a,
                         src, scene_.geometry[static_cast<std::size_t>(src)].name, 100 * d.rel);
      break;
    }
    case DeepestOverlap::kBoundary:
      what = fmt::format("grain {} overlaps the boundary particles of a mesh by {:.0f} % of its "
                         "diameter",
                         a, 100 * d.rel);
      break;
    case DeepestOverlap::kNone:
      break;
  }
  if (d.rel < reached)
    what = fmt::format("an overlap reached {:.0f} % of a diameter during the step{}", 100 * reached,
                       what.empty() ? "" : "; the deepest after it: " + what);
  throw SimulationError(fmt::format(
      "{}: {}, above simulation.max_overlap_stop = {:.0f} %; the contacts are too soft for the "
      "impacts (raise k_n) or the time step is too long",
      where(after_step), what, 100 * limit));
}

FrameStats World::advance_frame() {
  Stopwatch wall;
  dem_.counters() = {};
  transitions_ = {};
  surface_updates_ = 0;
  left_frame_ = 0;
  for (int s = 0; s < ts_.substeps; ++s) step();
  // Each step's overlap is measured on the state it starts from: the state the frame's last step
  // leaves, which is written and restarted from, is measured here (a step too long for the
  // contacts can carry grains deep into the geometry in one go).
  dem_.counters().max_overlap_rel =
      std::max(dem_.counters().max_overlap_rel, dem_.deepest_overlap(grains_, geometry_).rel);
  check_overlap(step_);
  ++frame_;

  FrameStats st;
  st.frame = frame_;
  st.time = time_;
  st.substeps = ts_.substeps;
  st.dt = ts_.dt;
  for (GrainState s : grains_.state) {
    if (s == GrainState::Active)
      ++st.n_active;
    else
      ++st.n_interface;
  }
  st.n_static = static_cast<std::int64_t>(static_.size());
  st.n_total = st.n_active + st.n_interface + st.n_static;
  st.transitions = transitions_;
  st.surface_updates = surface_updates_;
  st.left_domain = left_frame_;
  if (st.n_total + left_ != static_cast<std::int64_t>(next_id_))
    throw SimulationError(
        fmt::format("{} grains were emitted and {} left the domain but {} are held at step {}: a "
                    "transition lost or duplicated grains",
                    next_id_, left_, st.n_total, step_));
  st.contacts = dem_.counters().contacts;
  st.wall_contacts = dem_.counters().wall_contacts;
  st.max_overlap_rel = dem_.counters().max_overlap_rel;
  st.rebuilds = dem_.counters().rebuilds;
  st.energy_trapped = transitions_.energy_trapped + dem_.counters().energy_inert;
  st.energy_woken = dem_.counters().energy_released;
  st.energy_preloaded = dem_.counters().energy_preloaded;
  st.energy_inside = dem_.counters().energy_inside;
  st.kinetic_energy = kinetic_energy();
  // (the guards of each step see the positions before it: this one sees the frame's last step)
  for (std::size_t i = 0; i < grains_.size(); ++i)
    if (!is_finite(grains_.x[i]) || !is_finite(grains_.v[i]) || !is_finite(grains_.w[i]))
      throw SimulationError(fmt::format(
          "step {} (frame {}, t = {:.6f} s): grain {} has a non-finite position, velocity or "
          "spin; the time step {:.3g} s may be too large for the contacts",
          step_, frame_, time_, grains_.id[i], ts_.dt));
  st.wall_seconds = wall.seconds();
  return st;
}

void World::set_gravity(const Vec3& g) {
  if (surface_) throw std::logic_error("World::set_gravity: plain DEM only");
  scene_.simulation.gravity = g;
  dem_.set_gravity(g);
}

Real World::kinetic_energy() const {
  Real e = 0;
  for (std::size_t i = 0; i < grains_.size(); ++i)
    e += 0.5 * grains_.m[i] * norm2(grains_.v[i]) + 0.5 / grains_.inv_I[i] * norm2(grains_.w[i]);
  return e;
}

void World::all_grains(std::vector<Vec3>& x, std::vector<Real>& r) const {
  x = grains_.x;
  r = grains_.r;
  x.reserve(x.size() + static_.size());
  r.reserve(r.size() + static_.size());
  static_.for_each([&](const StaticGrain& g) {
    x.push_back(g.x);
    r.push_back(g.r);
  });
}

FrameData World::visible_frame() const {
  FrameData f;
  const std::size_t n = grains_.size();
  f.position = grains_.x;
  f.radius = grains_.r;
  f.velocity = grains_.v;
  f.id = grains_.id;
  f.state.resize(n);
  for (std::size_t i = 0; i < n; ++i) f.state[i] = static_cast<std::uint8_t>(grains_.state[i]);
  return f;
}

FrameData World::all_grains_frame() const {
  FrameData f = visible_frame();
  static_.for_each([&](const StaticGrain& g) {
    f.position.push_back(g.x);
    f.radius.push_back(g.r);
    f.velocity.push_back({});
    f.id.push_back(g.id);
    f.state.push_back(static_cast<std::uint8_t>(GrainState::Static));
  });
  return f;
}

std::uint64_t World::state_hash() const {
  // every grain, hot or static, in id order
  struct Ref {
    GrainId id;
    bool hot;
    std::uint32_t slot;
  };
  std::vector<Ref> refs;
  refs.reserve(total_grains());
  for (std::uint32_t i = 0; i < grains_.size(); ++i) refs.push_back({grains_.id[i], true, i});
  static_.for_each([&](const StaticGrain& g) { refs.push_back({g.id, false, g.slot}); });
  std::sort(refs.begin(), refs.end(), [](const Ref& a, const Ref& b) { return a.id < b.id; });
  Hasher h;
  for (const Ref& ref : refs) {
    h.add(ref.id);
    if (ref.hot) {
      h.add(grains_.x[ref.slot]);
      h.add(grains_.v[ref.slot]);
      h.add(grains_.w[ref.slot]);
    } else {
      h.add(static_.position(ref.slot));
    }
  }
  return h.value();
}

}  // namespace sandflow

namespace sandflow {

WorldState World::save_state() const {
  WorldState s;
  s.grains = grains_;
  s.statics = static_.save_state();
  s.dem = dem_.save_state();
  if (surface_) s.surface = surface_->save_state();
  for (const Emitter& e : emitters_) s.emitters.push_back(e.progress());
  for (int k = 0; k < 4; ++k) s.rng[k] = rng_.state()[k];
  s.next_id = next_id_;
  s.step = step_;
  s.frame = frame_;
  s.left = left_;
  s.profile = profile_;
  return s;
}

void World::restore_state(WorldState s) {
  grains_ = std::move(s.grains);
  // (slot for slot, as the run had it: the same grains wake in the same order)
  static_.restore(std::move(s.statics));
  checked_ = {};
  // the solids removed before the checkpoint (at its step, the next step() removes them, as the
  // run did), before the DEM's lists and the height field are restored over them
  remove_due_geometry(s.step, false);
  dem_.restore_state(std::move(s.dem), geometry_);
  if (surface_ && s.surface) surface_->restore_state(std::move(*s.surface));
  for (std::size_t k = 0; k < emitters_.size() && k < s.emitters.size(); ++k)
    emitters_[k].restore(s.emitters[k]);
  rng_.set_state(s.rng.data());
  next_id_ = s.next_id;
  step_ = s.step;
  time_ = static_cast<Real>(step_) * ts_.dt;  // as step() computes it
  frame_ = s.frame;
  left_ = s.left;
  profile_ = s.profile;
}

}  // namespace sandflow
