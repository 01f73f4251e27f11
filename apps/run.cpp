// `sandflow run` and `sandflow measure`, and the run driver that `compare` and `table1` share.
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <numeric>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>

#include "analysis/crater.hpp"
#include "calibration/calibration.hpp"
#include "commands.hpp"
#include "console.hpp"
#include "core/atomic_file.hpp"
#include "core/counted.hpp"
#include "core/error.hpp"
#include "core/file_kind.hpp"
#include "core/memory.hpp"
#include "core/read_file.hpp"
#include "core/threads.hpp"
#include "frames_spec.hpp"
#include "geometry/heightmap.hpp"
#include "geometry/mesh.hpp"
#include "io/export_formats.hpp"
#include "io/folder_lock.hpp"
#include "io/frame_exporter.hpp"
#include "io/height_export.hpp"
#include "io/ply.hpp"
#include "io/run_output.hpp"
#include "progress.hpp"
#include "report/run_data.hpp"
#include "scene/scene_loader.hpp"
#include "sim/emitters.hpp"
#include "sim/world.hpp"
#include "stop_signals.hpp"

namespace fs = std::filesystem;

namespace sandflow {

std::string mode_name(Mode m) {
  return m == Mode::Dem ? "dem" : "surface";
}

namespace {

std::vector<Override> run_overrides(const RunOptions& o) {
  std::vector<Override> overrides;
  for (const auto& s : o.sets) overrides.push_back(parse_override(s));
  if (!o.mode.empty()) overrides.push_back({"simulation.mode", fmt::format("\"{}\"", o.mode)});
  return overrides;
}

SceneConfig apply_run_options(SceneConfig scene, const RunOptions& o) {
  if (o.grains > 0) scale_grain_count(scene, o.grains);
  if (o.frames > 0) scene.output.frames = o.frames;
  if (o.threads > 0) scene.simulation.threads = o.threads;
  if (o.exports) scene.output.exports = parse_export_list(*o.exports, "--export");
  if (!o.up_axis.empty()) scene.output.up_axis = o.up_axis == "y" ? UpAxis::Y : UpAxis::Z;
  return scene;
}

}  // namespace

SceneConfig load_for_run(const RunOptions& o) {
  return apply_run_options(load_scene(o.scene, run_overrides(o)), o);
}

namespace {

nlohmann::json heap_json(const HeapFit& fit) {
  return {
      {"ok", fit.ok},
      {"repose_angle_deg", fit.ok ? nlohmann::json(fit.repose_angle_deg) : nlohmann::json()},
      {"height", fit.height},
      {"base_radius", fit.base_radius},
      {"apex", {fit.apex.x, fit.apex.y, fit.apex.z}},
      {"points_used", fit.points_used},
      {"fit_rms", fit.fit_rms},
      {"repose_angle_se_deg", fit.ok ? nlohmann::json(fit.repose_angle_se_deg) : nlohmann::json()},
      {"reason", fit.reason}};
}

nlohmann::json stiffness_json(const Stiffness& s) {
  nlohmann::json j = {{"k_n", s.k_n}, {"from_load", s.from_load}};
  if (s.from_load) {
    j["depth"] = s.depth;
    j["impact_speed"] = s.impact_speed;
    j["impact_mass_ratio"] = s.impact_mass_ratio;
    j["k_static"] = s.k_static;
    j["k_impact"] = s.k_impact;
  }
  return j;
}

/// What `render` checks the meshes it draws against (a mesh file edited since the run): a digest
/// of each mesh as placed, by [[geometry]] table.
nlohmann::json mesh_digests(const Geometry& geometry) {
  nlohmann::json out = nlohmann::json::array();
  for (const MeshObstacle& m : geometry.meshes())
    out.push_back(
        {{"geometry", m.source}, {"digest", fmt::format("{:016x}", mesh_digest(m.mesh))}});
  return out;
}

/// Adds the meshes' digests to a new run's run.json, so that `render` can check its meshes
/// before the run has a summary.json (a run stopped, killed or still going).
void record_mesh_digests(const std::string& out, const Geometry& geometry) {
  if (geometry.meshes().empty()) return;
  const std::string path = (fs::path(out) / "run.json").string();
  nlohmann::json record;
  try {
    record = nlohmann::json::parse(read_whole_file(path, "run record", kAnyFileSize));
  } catch (const nlohmann::json::exception& e) {
    throw OutputError(fmt::format("{}: cannot be read back ({})", path, e.what()));
  } catch (const InputError& e) {
    throw OutputError(fmt::format("{} (the run record just written)", e.what()));
  }
  record["mesh_digests"] = mesh_digests(geometry);
  write_file_atomic(path, record.dump(2) + "\n");
}

}  // namespace

void warn_once(const std::string& text) {
  static std::set<std::string> printed;
  if (printed.insert(text).second) print_to_stderr("warning: {}\n", text);
}

int thread_count(const SceneConfig& scene) {
  const int limit = omp_get_thread_limit();
  const int asked =
      scene.simulation.threads > 0 ? scene.simulation.threads : omp_num_threads().value_or(0);
  // (OpenMP would run the regions on fewer threads than the run says it has)
  if (asked > limit)
    warn_once(fmt::format("OMP_THREAD_LIMIT={} holds this job to {} ({} asked)", limit,
                          counted(limit, "thread"), asked));
  return scene.simulation.threads > 0 ? std::min(scene.simulation.threads, limit)
                                      : default_thread_count();
}

/// Runs a scene into `out` (prepared by the caller), writing stats.csv, frames and summary.json.
/// `label` prefixes the progress line (table1's "scene k of n: ").
RunResult run_scene(const SceneConfig& scene, const std::string& out, const std::string& label,
                    const RunControl& control) {
  for (const std::string& w : scene.warnings) warn_once(w);
  World world(scene);
  for (const std::string& w : world.warnings()) warn_once(w);
  const int frames = world.planned_frames();
  const TimeStep& ts = world.time_step();
  const int threads = thread_count(scene);
  omp_set_num_threads(threads);
  print_to_stderr("sandflow {}: {} ({}, mode {}), {}, k_n = {:.4g} N/m, dt = {:.3g} s, {} -> {}\n",
                  SANDFLOW_VERSION, scene.path, counted(scene.total_grains(), "grain"),
                  mode_name(scene.simulation.mode), counted(frames, "frame"),
                  world.scene().material.k_n, ts.dt, counted(threads, "thread"), out);

  RunResult res;
  // a resumable run: checkpoints carry the hash of its scene; a resumed one starts from one
  const bool resumable = !control.start_record.empty();
  const std::uint64_t hash = resumable ? scene_hash(world, control.start_record) : 0;
  const std::string checkpoint_path = (fs::path(out) / "checkpoint.bin").string();
  if (control.resume) {
    res.frames = control.resume->frames;
    restore_checkpoint(world, std::move(*control.resume), hash, checkpoint_path);
    if (world.frame() > frames)
      throw InputError(fmt::format("{}: frame {} is past the run's last frame {}",
                                   checkpoint_path, world.frame(), frames));
  }
  if (control.resumed) prepare_resumed_dir(out, world.frame());
  if (resumable && !control.resume) record_mesh_digests(out, world.geometry());
  StatsWriter stats(fs::path(out) / "stats.csv", res.frames);
  FrameExporter exporter(world, out);  // the per-frame files of --export
  for (const std::string& w : exporter.warnings()) warn_once(w);
  exporter.continue_after(res.frames);  // a resumed run's frames.pvd lists the frames before it
  Progress progress(fmt::format("{}{} [{}]", label, scene.name, mode_name(scene.simulation.mode)),
                    frames, world.frame());
  std::vector<std::string> unsynced;  // frames written since the last checkpoint
  if (world.frame() == 0) {
    exporter.write_start(world);  // Houdini's frame 1 is the start (export_formats.hpp)
    unsynced = exporter.written();
  }
  auto write_checkpoint = [&] {
    // the frames it vouches for reach the disk before it does
    std::set<std::string> folders;
    for (const std::string& p : unsynced) {
      sync_file(p);
      folders.insert(fs::path(p).parent_path().string());
    }
    for (const std::string& d : folders) sync_dir(d);
    unsynced.clear();
    Checkpoint c;
    c.scene_hash = hash;
    c.world = world.save_state();
    c.frames = res.frames;
    write_file_atomic(checkpoint_path, encode_checkpoint(c));
  };
  CoreShareWarning core_share(threads);
  for (int f = world.frame(); f < frames; ++f) {
    FrameStats st = world.advance_frame();
    Stopwatch io;
    exporter.write(world);
    unsynced.insert(unsynced.end(), exporter.written().begin(), exporter.written().end());
    st.wall_seconds += io.seconds();
    stats.write(st);
    res.frames.push_back(st);
    progress.update(st.frame, st.n_total, st.n_active + st.n_interface);
    if (const std::optional<std::string> warning = core_share.poll()) progress.note(*warning);
    const bool stop = control.stop && *control.stop != 0;
    const int every = control.checkpoint_every;
    if (resumable && (stop || (every > 0 && (st.frame % every == 0 || st.frame == frames))))
      write_checkpoint();
    if (stop && st.frame < frames) throw RunInterrupted{st.frame, *control.stop};
  }
  // (a safety cap no test grid reaches: said when it was, not counted in summary.json, which a
  // resume must write the same)
  for (const Obstacle& o : world.geometry().obstacles())
    if (const auto* h = dynamic_cast<const SolidHeightmap*>(o.solid.get());
        h && h->capped_queries() > 0)
      fmt::print(
          stderr,
          "warning: geometry[{}]: {} contact queries on this heightmap stopped at the cap on "
          "the pieces examined, with a lower bound of the distance: grains there may rest a "
          "little above it (a grid much finer than the grains; coarsen it)\n",
          o.source, h->capped_queries());
  double simulated_sum = 0;
  Real max_overlap = 0;
  std::int64_t max_overlap_frame = 0;
  TransitionCounts transitions;
  Real energy_trapped = 0, energy_woken = 0, energy_preloaded = 0, energy_inside = 0;
  for (const FrameStats& st : res.frames) {
    simulated_sum += static_cast<double>(st.n_active + st.n_interface);
    res.wall_seconds += st.wall_seconds;
    if (st.max_overlap_rel > max_overlap) {
      max_overlap = st.max_overlap_rel;
      max_overlap_frame = st.frame;
    }
    transitions += st.transitions;
    energy_trapped += st.energy_trapped;
    energy_woken += st.energy_woken;
    energy_preloaded += st.energy_preloaded;
    energy_inside += st.energy_inside;
  }

  // the heap of the final state, and what ended up where it must not be
  world.all_grains(res.x, res.r);
  // every grain of the final state, the static ones too (state 2): nothing is lost with the run
  write_ply((fs::path(out) / "final_grains.ply").string(), world.all_grains_frame(),
            scene.output.up_axis);
  res.heap = measure_heap(res.x, res.r);
  if (std::any_of(scene.emitters.begin(), scene.emitters.end(),
                  [](const EmitterConfig& e) { return e.type == EmitterType::Bed; })) {
    res.heap.ok = false;
    res.heap.reason = kNoHeapInABed;
  }
  const HeapFit& fit = res.heap;
  const auto inside = world.geometry().count_inside(res.x);
  const FrameStats& last = res.frames.back();
  // the scene file as an absolute path: `render` and `report` find it from any folder
  const std::string scene_file = fs::absolute(scene.path).lexically_normal().string();
  nlohmann::json summary = {
      {"sandflow_version", SANDFLOW_VERSION},
      {"scene", scene.name},
      {"scene_file", scene_file},
      {"mode", mode_name(scene.simulation.mode)},
      {"frames", frames},
      {"fps", scene.output.fps},
      {"n_total", world.total_grains()},
      {"n_simulated_mean", simulated_sum / frames},
      {"n_simulated_final", last.n_active + last.n_interface},
      {"n_active_final", last.n_active},
      {"n_interface_final", last.n_interface},
      {"n_static_final", last.n_static},
      {"seconds_per_frame", res.wall_seconds / frames},
      {"wall_seconds", res.wall_seconds},
      {"dt_mean", ts.dt},
      {"substeps_per_frame", ts.substeps},
      {"t_c", ts.t_c},
      {"k_n", world.scene().material.k_n},
      {"stiffness", stiffness_json(world.stiffness())},
      {"threads", threads},
      {"max_overlap_rel", max_overlap},
      {"max_overlap_frame", max_overlap_frame},
      {"repose_angle_deg", fit.ok ? nlohmann::json(fit.repose_angle_deg) : nlohmann::json()},
      {"heap", heap_json(fit)},
      {"grains_inside_geometry", inside},
      {"grains_left_domain", world.left_domain()},
      {"state_hash", fmt::format("{:016x}", world.state_hash())},
      // the static store's allocated bytes per static grain (dem/grains.hpp), and the process's
      // peak resident memory
      {"bytes_per_static_grain",
       world.static_grains().size() > 0
           ? static_cast<double>(world.static_grains().allocated_bytes()) /
                 static_cast<double>(world.static_grains().size())
           : 0.0},
      {"peak_memory_bytes", peak_memory_bytes()},
      {"exports", exporter.summary()},
  };
  summary["mesh_digests"] = mesh_digests(world.geometry());
  if (const SurfaceFlow* sf = world.surface()) {
    const HeightField& hf = sf->height_field();
    Real r_sum = 0, r_max = 0;
    const std::size_t sand = hf.sand_columns();
    for (std::size_t c = 0; c < hf.columns(); ++c)
      if (hf.surface()[c] > hf.terrain()[c]) {
        r_sum += hf.rolling()[c];
        r_max = std::max(r_max, hf.rolling()[c]);
      }
    const SeatParams& seat = sf->params().interface.seat;
    summary["height_field"] = {
        {"cells", hf.columns()},
        {"nx", hf.nx()},
        {"ny", hf.ny()},
        {"cell_size", hf.cell()},
        {"sand_cells", sand},
        {"rolling_mean", sand ? r_sum / static_cast<Real>(sand) : 0.0},
        {"rolling_max", r_max},
        {"static_volume", hf.static_volume()},
        {"update_interval", sf->params().update_interval},
        {"repose_angle_deg", rad_to_deg(hf.params().theta0)},
        {"max_angle_deg", rad_to_deg(hf.params().theta_max)},
        {"angles_source", scene.surface.angles_source.empty() ? "scene, or the built-in defaults"
                                                              : scene.surface.angles_source},
        {"exchange_rate", hf.params().gamma},
        {"rolling_min", hf.params().rolling_min},
        {"flowing_min", hf.params().flowing_floor()},
        // as used: never longer than close_after
        {"flowing_hold", hf.params().hold_time()},
        {"erosion_reach", hf.params().erosion_reach},
        {"close_after", hf.params().close_after},
        {"interface_thickness", sf->params().interface.thickness},
        // as speeds of a grain of the mean size without rotation (seat.hpp)
        {"trap_speed", std::sqrt(2 * seat.hold_energy(scene.material.diameter / 2))},
        {"flow_speed", std::sqrt(2 * seat.move_energy(scene.material.diameter / 2))},
        {"thresholds_source", seat.trap_speed >= 0 || seat.flow_speed >= 0
                                  ? "scene (surface.trap_speed, flow_speed)"
                                  : "the seat: a grain held in the hollow of three"},
    };
    summary["transitions"] = {{"trapped", transitions.trapped},
                              {"dislodged", transitions.dislodged},
                              {"slept", transitions.slept},
                              {"woken", transitions.woken},
                              {"woken_by_reach", transitions.woken_by_reach}};
    summary["transition_energy"] = {{"removed_by_trapping_j", energy_trapped},
                                    {"added_by_waking_j", energy_woken},
                                    {"opened_inside_active_j", energy_inside},
                                    {"preloaded_j", energy_preloaded}};
  }
  nlohmann::json emitters = nlohmann::json::array();
  for (const Emitter& e : world.emitters()) {
    emitters.push_back({{"name", e.name()},
                        {"count", e.count()},
                        {"emitted", e.emitted()},
                        {"delayed_by_occupied_slots", e.delayed()},
                        {"left_out_by_occupied_slots", e.left_out()}});
    if (e.type() == EmitterType::Pour) {
      emitters.back()["facing"] = e.facing() == PourFacing::Velocity ? "velocity" : "up";
      emitters.back()["stream_lead"] = e.stream_lead();
    }
  }
  summary["emitters"] = emitters;
  nlohmann::json prof;
  for (int s = 0; s < static_cast<int>(Stage::kCount); ++s)
    prof[std::string(stage_name(static_cast<Stage>(s)))] = world.profile().seconds[s];
  summary["stage_seconds"] = prof;
  write_file_atomic((fs::path(out) / "summary.json").string(), summary.dump(2) + "\n");
  res.summary = summary;
  return res;
}

std::string shell_quote(const std::string& a) {
  if (!a.empty() && a.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ"
                                        "0123456789_-+./=:,@%") == std::string::npos)
    return a;
  std::string q = "'";
  for (char ch : a) q += ch == '\'' ? std::string("'\\''") : std::string(1, ch);
  return q + "'";
}

std::string folder_problem(const std::string& dir) {
  std::error_code ec;
  if (fs::is_directory(dir, ec)) return "";
  return fs::exists(dir, ec) ? "a file, not a folder" : "no such folder";
}

/// The options a run folder's run.json records (its scene file made absolute from the folder the
/// run was started in), the record itself and the scene text it was started with.
RunOptions read_run_record(const std::string& dir, nlohmann::json& record, std::string& text) {
  const fs::path record_path = fs::path(dir) / "run.json";
  std::error_code ec;
  if (const std::string problem = folder_problem(dir); !problem.empty())
    throw InputError(dir + ": " + problem + " (expected a run folder)");
  refuse_broken_link(record_path.string(), "run record");
  if (!fs::exists(record_path, ec))
    throw InputError(fmt::format(
        "{}: no run.json: not a sandflow run folder, or its run stopped before it started; start "
        "it again with: sandflow run SCENE --out {} --force",
        dir, shell_quote(dir)));
  RunOptions r;
  // a count the record holds: an integer in [lo, hi], never a float cast out of range
  auto whole = [&](const nlohmann::json& v, const char* name, std::int64_t lo,
                   std::int64_t hi) -> std::int64_t {
    const bool integer = v.is_number_integer() &&
                         (v.is_number_unsigned() ? v.get<std::uint64_t>() <= std::uint64_t(hi)
                                                 : v.get<std::int64_t>() <= hi);
    if (!integer || v.get<std::int64_t>() < lo)
      throw InputError(
          fmt::format("{}: {} {} is not a whole number from {} to {}: the record was "
                      "edited or damaged",
                      record_path.string(), name, v.dump(), lo, hi));
    return v.get<std::int64_t>();
  };
  try {
    record =
        nlohmann::json::parse(read_whole_file(record_path.string(), "run record", kAnyFileSize));
    text = record.at("start").at("scene_text").get<std::string>();
    r.scene = record.at("scene_file").get<std::string>();
    if (r.scene.empty() || r.scene.find('\0') != std::string::npos)
      throw InputError(
          fmt::format("{}: scene_file {} names no file: the record was edited or "
                      "damaged",
                      record_path.string(), nlohmann::json(r.scene).dump()));
    r.sets = record.at("start").at("sets").get<std::vector<std::string>>();
    r.mode = record.at("start").at("mode").get<std::string>();
    if (!r.mode.empty() && r.mode != "surface" && r.mode != "dem")
      throw InputError(
          fmt::format("{}: mode \"{}\" is not surface or dem: the record was edited "
                      "or damaged",
                      record_path.string(), r.mode));
    r.grains = whole(record.at("start").at("grains"), "grains", 0, 2'000'000'000);
    if (const auto& e = record.at("start").at("exports"); !e.is_null())
      r.exports = e.get<std::string>();
    r.up_axis = record.at("start").at("up_axis").get<std::string>();
    const auto max_frames = static_cast<std::int64_t>(kMaxFrames);
    r.frames = static_cast<int>(whole(record.at("frames"), "frames", 0, max_frames));
    r.threads = static_cast<int>(whole(record.at("threads"), "threads", 0, kMaxThreads));
    r.checkpoint_every =
        static_cast<int>(whole(record.at("checkpoint_every"), "checkpoint_every", 0, max_frames));
    if (record.contains("run_to_frame"))
      whole(record["run_to_frame"], "run_to_frame", 1, max_frames);
    const std::string wd = record.at("working_directory").get<std::string>();
    // a relative scene path names a file from the folder the run was started in
    if (fs::path(r.scene).is_relative() && fs::current_path(ec) != fs::path(wd))
      r.scene = (fs::path(wd) / r.scene).lexically_normal().string();
  } catch (const nlohmann::json::exception& e) {
    throw InputError(fmt::format("{}: not a run record sandflow can read: {}", record_path.string(),
                                 without_library_tag(e.what())));
  }
  return r;
}

namespace {
/// The last frame `sandflow run --resume DIR --frames N` set for a run (0: the run's own). It is
/// not part of what the checkpoints' seal covers: a run's frames do not depend on how many follow.
int run_to_frame(const nlohmann::json& record) {
  return record.contains("run_to_frame") ? record["run_to_frame"].get<int>() : 0;
}
}  // namespace

/// The scene of a recorded run, `r` and `text` as read_run_record returned them: its file's text
/// with its options, and the surface angles it ran with (measured or cached when it started).
SceneConfig recorded_scene(const RunOptions& r, const std::string& text,
                           const nlohmann::json& record) {
  SceneConfig scene = apply_run_options(load_scene_from_string(text, r.scene, run_overrides(r)), r);
  if (record.contains("surface_angles")) apply_surface_angles(scene, record["surface_angles"]);
  if (const int last = run_to_frame(record); last > 0) scene.output.frames = last;
  return scene;
}

// ---- Resumable runs (docs/checkpoints.md) -------------------------------------------------------

std::string resume_command(const std::string& dir) {
  return "sandflow run --resume " + shell_quote(dir);
}

namespace {

/// "the last checkpoint (frame K)", or what there is instead, for the messages of a failed run.
std::string last_checkpoint(const std::string& dir) {
  const std::string path = (fs::path(dir) / "checkpoint.bin").string();
  std::error_code ec;
  if (!fs::exists(path, ec)) return "the start (there is no checkpoint yet)";
  try {
    return fmt::format("the last checkpoint (frame {})", read_checkpoint(path).world.frame);
  } catch (const InputError& e) {
    return fmt::format("the start: the checkpoint cannot be read ({})", e.what());
  }
}

/// What DIR/run.json records: everything that decides the run (hashed into its checkpoints),
/// and the rest a resumed run needs.
nlohmann::json run_record(const RunOptions& o, const std::string& scene_text, int every) {
  std::error_code ec;
  return {{"sandflow_version", SANDFLOW_VERSION},
          {"working_directory", fs::current_path(ec).string()},
          {"scene_file", o.scene},
          {"start",
           {{"scene_text", scene_text},
            {"sets", o.sets},
            {"mode", o.mode},
            {"grains", o.grains},
            {"exports", o.exports ? nlohmann::json(*o.exports) : nlohmann::json()},
            {"up_axis", o.up_axis}}},
          {"frames", o.frames},
          {"threads", o.threads},
          {"checkpoint_every", every},
          {"resume_with", resume_command(o.out)}};
}

/// A run about to go: its scene, folder and record, and the checkpoint it resumes from.
struct Started {
  std::shared_ptr<FolderLock> lock;  ///< held until the run ends: no other run writes there
  SceneConfig scene;
  std::string out;
  nlohmann::json record;
  std::optional<Checkpoint> checkpoint;
  bool resumed = false;  ///< `out` holds a stopped run
  bool done = false;     ///< nothing to run (--check, or a finished run)
  bool report_missing = false;  ///< a finished run killed before its report.html was written
};

/// How a run was started and how long it is, from its run.json: what its checkpoints' seal covers
/// (an edited run.json cannot resume into another run).
std::string start_record(const nlohmann::json& record) {
  return record["start"].dump() + " frames " + record["frames"].dump();
}

/// Runs `run` with checkpoints and the stop signals into `res`; returns the exit status of an
/// interrupted run (128 + the signal), 0 otherwise. `resume_with` is the command that continues
/// it, for the messages; `label` prefixes the progress line.
int run_resumable(Started& run, RunResult& res, const std::string& resume_with,
                  const std::string& label = "") {
  RunControl control;
  control.start_record = start_record(run.record);
  control.checkpoint_every = run.record["checkpoint_every"].get<int>();
  control.resume = run.checkpoint ? &*run.checkpoint : nullptr;
  control.resumed = run.resumed;
  control.stop = &g_stop_signal;
  try {
    const StopSignals signals;
    res = run_scene(run.scene, run.out, label, control);
  } catch (const RunInterrupted& e) {
    print_to_stderr("\ninterrupted at frame {}; resume with: {}\n", e.frame, resume_with);
    return 128 + e.signal;
  } catch (const SimulationError& e) {
    throw SimulationError(fmt::format("{}\n  reproduce it from {}: {}", e.what(),
                                      last_checkpoint(run.out), resume_with));
  } catch (const OutputError& e) {
    throw OutputError(fmt::format("{}\n  the run can go on from {}: make room (or make the folder "
                                  "writable), then: {}",
                                  e.what(), last_checkpoint(run.out), resume_with));
  }
  return 0;
}

/// `sandflow run --resume DIR`. A finished run has nothing to resume, unless `reload_finished`
/// (compare and table1): it is then read back from its last checkpoint.
Started start_resumed(const RunOptions& o, bool reload_finished = false) {
  if (!o.scene.empty() || !o.mode.empty() || o.grains > 0 || !o.sets.empty() || !o.out.empty() ||
      o.force || o.check || o.exports || !o.up_axis.empty())
    throw InputError(
        "--resume DIR continues a run exactly as it was started (DIR/run.json): it takes no "
        "scene, --mode, --grains, --set, --export, --up-axis, --out, --force or --check; only "
        "--frames (another last frame), --threads, --checkpoint-every and --profile");
  const std::string dir = o.resume;
  Started run;
  std::error_code ec;
  // (a folder that is not there is not created: read_run_record says what is missing)
  if (fs::is_directory(dir, ec)) run.lock = std::make_shared<FolderLock>(dir);
  nlohmann::json record;
  std::string text;
  RunOptions r = read_run_record(dir, record, text);
  // finished: its summary is written whole (one edited into something else is written again)
  const bool finished = [&] {
    const std::optional<std::string> written =
        read_file_if_present((fs::path(dir) / "summary.json").string(), "summary", kAnyFileSize);
    if (!written) return false;
    const nlohmann::json summary =
        nlohmann::json::parse(*written, nullptr, /*allow_exceptions=*/false);
    return summary.is_object() && summary.contains("frames") && summary.contains("state_hash");
  }();
  if (finished && !reload_finished && o.frames == 0) {
    print_to_stderr("{}: this run is finished (its summary.json is written); nothing to resume\n",
                    dir);
    // killed after its summary was written: what it was writing then is finished here
    remove_partial_files(dir);
    run.report_missing = !fs::exists(fs::path(dir) / "report.html", ec);
    run.out = dir;
    run.done = true;
    return run;
  }
  if (o.threads > 0) r.threads = o.threads;
  run.scene = recorded_scene(r, text, record);
  run.out = dir;
  run.resumed = true;
  const std::string path = (fs::path(dir) / "checkpoint.bin").string();
  refuse_broken_link(path, "checkpoint");  // (else taken for none, and the run started over)
  if (fs::exists(path, ec)) {
    try {
      run.checkpoint = read_checkpoint(path);
    } catch (const InputError& e) {
      throw InputError(fmt::format(
          "{}\n  the run cannot go on from it (without it, --resume runs it again from the start)",
          e.what()));
    }
  }
  const int frame = run.checkpoint ? run.checkpoint->world.frame : 0;
  // frames deleted by hand before the checkpoint cannot be written again: say which
  if (frame > 0 &&
      has_export(run_exports(run.scene.output, run.scene.simulation.mode), ExportFormat::Ply)) {
    std::vector<int> missing;
    for (int f = 1; f <= frame; ++f)
      if (!fs::exists(frame_path(dir, f), ec)) missing.push_back(f);
    if (!missing.empty())
      print_to_stderr(
          "warning: {}: {} of its {} before the checkpoint {} missing from frames/ ({}): "
          "the run goes on from frame {} and cannot write {} again\n",
          dir, missing.size(), counted(frame, "frame"), missing.size() == 1 ? "is" : "are",
          missing.size() == 1
              ? fmt::format("frame {}", missing.front())
              : fmt::format("the first {}, the last {}", missing.front(), missing.back()),
          frame + 1, missing.size() == 1 ? "it" : "them");
  }
  if (o.frames > 0) {
    // another last frame: the run goes on from its checkpoint, so not one before it. The summary
    // goes first: a folder stopped between the two is an unfinished run of its old length
    if (o.frames < frame)
      throw InputError(fmt::format(
          "{}: --frames {} is before the run's checkpoint at frame {}: a run goes on from its last "
          "checkpoint, so it can end at frame {} or later",
          dir, o.frames, frame, frame));
    if (std::error_code rm; finished && (fs::remove(fs::path(dir) / "summary.json", rm), rm))
      throw OutputError(
          fmt::format("{}: cannot remove summary.json to run on: {}", dir, rm.message()));
    record["run_to_frame"] = o.frames;
    write_file_atomic((fs::path(dir) / "run.json").string(), record.dump(2) + "\n");
    run.scene.output.frames = o.frames;
    print_to_stderr("{}: running on to frame {}\n", dir, o.frames);
  }
  // (for this sitting only: run.json keeps the run's own)
  if (o.checkpoint_every >= 0) record["checkpoint_every"] = o.checkpoint_every;
  run.record = record;
  if (finished && run.checkpoint && o.frames == 0)
    print_to_stderr("{} is finished: reading it back from its checkpoint at frame {}\n", dir,
                    frame);
  else if (run.checkpoint)
    print_to_stderr("resuming {} from its checkpoint at frame {}\n", dir, frame);
  else
    print_to_stderr("{} has no checkpoint yet: running it again from the start\n", dir);
  return run;
}

/// A new run of `text`, the scene file o.scene as read: the scene, its plan (--check), or its
/// prepared folder with its run.json.
Started start_new(const RunOptions& o, const std::string& text) {
  Started run;
  run.scene = apply_run_options(load_scene_from_string(text, o.scene, run_overrides(o)), o);
  const SceneConfig& scene = run.scene;
  if (o.check) {
    run.done = true;
    for (const std::string& w : scene.warnings) warn_once(w);
    World world(scene);
    for (const std::string& w : world.warnings()) warn_once(w);
    const TimeStep& ts = world.time_step();
    if (!world.dem().boundary().x.empty())
      fmt::print("{}: {} boundary particles of radius {:.3g} m on its meshes\n", scene.path,
                 world.dem().boundary().size(), world.dem().boundary().radius);
    fmt::print(
        "{}: ok — {}, mode {}, {} at {} fps, k_n = {:.4g} N/m, dt = {:.3g} s "
        "({} substeps/frame, t_c = {:.3g} s)\n",
        scene.path, counted(scene.total_grains(), "grain"), mode_name(scene.simulation.mode),
        counted(world.planned_frames(), "frame"), scene.output.fps, world.scene().material.k_n,
        ts.dt, ts.substeps, ts.t_c);
    std::vector<std::string> exports;
    std::vector<ExportFormat> dropped;
    for (const ExportFormat f : run_exports(scene.output, scene.simulation.mode, &dropped))
      exports.emplace_back(export_name(f));
    if (!dropped.empty()) warn_once(dropped_exports_warning(scene.path, dropped));
    fmt::print("{}: exports {} each frame (up axis {})\n", scene.path,
               exports.empty() ? "nothing" : fmt::format("{}", fmt::join(exports, ", ")),
               up_axis_name(scene.output.up_axis));
    if (needs_calibration(scene)) {
      const std::string key = calibration_key(scene);
      const auto cal = cached_calibration(key);
      fmt::print("{}: angles of repose {}\n", scene.path,
                 calibration_disabled() ? "unset: the built-in defaults (SANDFLOW_NO_CALIBRATION)"
                 : cal ? fmt::format("from the material's calibration {} (cached): theta0 {:.2f}, "
                                     "theta_max {:.2f} deg",
                                     key, (*cal)["theta0_deg"].get<double>(),
                                     (*cal)["theta_max_deg"].get<double>())
                       : fmt::format("unset: the run first measures them (sandflow calibrate, "
                                     "about a minute; cached as {})",
                                     key));
    }
    return run;
  }
  RunOptions started = o;
  started.out =
      o.out.empty() ? fmt::format("out/{}-{}", scene.name, mode_name(scene.simulation.mode))
                    : o.out;
  run.lock = std::make_shared<FolderLock>(started.out);
  prepare_output_dir(started.out, o.force);
  run.out = started.out;
  run.record = run_record(started, text,
                          o.checkpoint_every < 0 ? kDefaultCheckpointEvery : o.checkpoint_every);
  // the angles the run uses, kept so that a resumed run uses the same whatever the cache holds
  if (scene.simulation.mode == Mode::Surface)
    run.record["surface_angles"] = resolve_surface_angles(run.scene);
  write_file_atomic((fs::path(run.out) / "run.json").string(), run.record.dump(2) + "\n");
  return run;
}

}  // namespace

int check_resumable(const RunOptions& o, const std::string& text, bool run_on) {
  std::error_code ec;
  if (!fs::exists(fs::path(o.out) / "run.json", ec)) return 0;
  nlohmann::json record;
  std::string recorded_text;
  read_run_record(o.out, record, recorded_text);
  const nlohmann::json expected = run_record(o, text, 0);
  if (record["start"] != expected["start"] || record["frames"] != expected["frames"] ||
      (!run_on && run_to_frame(record) > 0))
    throw InputError(fmt::format(
        "{}: holds a run started otherwise (its run.json records another scene text, --set, "
        "--grains, --frames, --export or --up-axis than now, or it was run on to another frame); "
        "it cannot be resumed as this one: start it again with the command that made it, given "
        "--force in place of --resume",
        o.out));
  return run_to_frame(record);
}

int run_part(const RunOptions& o, bool resume, const std::string* scene_text,
             const std::string& resume_with, const std::string& label, RunResult& res,
             SceneConfig& scene, int run_to) {
  const std::string text = scene_text ? *scene_text : read_scene_file(o.scene);
  std::error_code ec;
  Started run;
  if (resume && fs::exists(fs::path(o.out) / "run.json", ec)) {
    RunOptions r;
    r.resume = o.out;
    r.threads = o.threads;
    r.checkpoint_every = o.checkpoint_every;
    // (run on only when it is set to end elsewhere: a finished run is then read back as it is)
    if (const int recorded = check_resumable(o, text, run_to > 0); run_to > 0 && recorded != run_to)
      r.frames = run_to;
    run = start_resumed(r, true);
  } else {
    RunOptions n = o;
    n.force = true;  // the caller's folder, empty or left by a start that never got going
    if (n.checkpoint_every < 0) n.checkpoint_every = kDefaultCheckpointEvery;
    try {
      run = start_new(n, text);
    } catch (const CalibrationInterrupted& e) {
      print_to_stderr(
          "\ninterrupted while measuring the material's angles: nothing measured was "
          "kept; resume with: {}\n",
          resume_with);
      return 128 + e.signal;
    }
    if (run_to > 0) {  // as if started, then run on to run_to
      run.record["run_to_frame"] = run_to;
      write_file_atomic((fs::path(run.out) / "run.json").string(), run.record.dump(2) + "\n");
      run.scene.output.frames = run_to;
    }
  }
  const int status = run_resumable(run, res, resume_with, label);
  scene = run.scene;
  return status;
}

namespace {
/// The largest overlap of the run; where k_n was sized from the load, whether it stayed within
/// stiffness.impact_overlap, and if not, the impact speed that sizes k_n to hold it (a spring's
/// overlap at a given impact goes as 1 / sqrt(k_n); 5 % more, as another run's impacts differ).
void print_overlap(const nlohmann::json& s, const SceneConfig& scene) {
  const double reached = s["max_overlap_rel"].get<double>();
  const auto frame = s.value("max_overlap_frame", std::int64_t{0});
  const nlohmann::json& k = s["stiffness"];
  const double limit = scene.stiffness.impact_overlap;
  if (!k["from_load"].get<bool>() || !(reached > limit)) {
    fmt::print("max overlap      {:.2f} % of a diameter\n", 100 * reached);
    return;
  }
  fmt::print(
      "max overlap      {:.2f} % of a diameter (frame {}), above stiffness.impact_overlap = "
      "{:.4g} %\n",
      100 * reached, frame, 100 * limit);
  const double speed = k["impact_speed"].get<double>(), k_impact = k["k_impact"].get<double>();
  const std::string remedy =
      speed > 0 && k_impact > 0
          ? fmt::format(
                ": set stiffness.impact_speed = {:.3g} (k_n was sized for {:.3g} m/s) to "
                "size the spring for it",
                1.05 * speed * reached / limit * std::sqrt(k["k_n"].get<double>() / k_impact),
                speed)
          : ": set stiffness.impact_speed to the speed of the scene's hardest impact";
  print_to_stderr(
      "warning: the largest overlap, {:.1f} % of a diameter in frame {}, passed "
      "stiffness.impact_overlap = {:.4g} %: an impact harder than the one k_n was sized for (a "
      "grain landing on one the ground or a wall backs, a wave piling against a wall: "
      "docs/known-issues.md){}\n",
      100 * reached, frame, 100 * limit, remedy);
}
}  // namespace

int run_command(const RunOptions& o) {
  if (o.resume.empty() && o.scene.empty())
    throw InputError("run: give a scene file (sandflow run SCENE), or --resume DIR to continue a run");
  Started run;
  try {
    run = o.resume.empty() ? start_new(o, read_scene_file(o.scene)) : start_resumed(o);
  } catch (const CalibrationInterrupted& e) {
    // (before run.json: the folder holds an empty frames/, which the same command takes as empty)
    print_to_stderr(
        "\ninterrupted while measuring the material's angles, before the run's first "
        "frame: nothing measured was kept; the same command starts it again\n");
    return 128 + e.signal;
  }
  if (run.done) {
    if (run.report_missing)
      fmt::print("report           {} (written now: the run was stopped before it)\n",
                 write_report({run.out, 6, false}));
    return 0;
  }
  const SceneConfig& scene = run.scene;
  const std::string& out = run.out;
  RunResult res;
  if (const int interrupted = run_resumable(run, res, resume_command(out))) return interrupted;
  const nlohmann::json& s = res.summary;
  const HeapFit& fit = res.heap;
  const int frames = s["frames"].get<int>();
  fmt::print("scene            {} ({})\n", scene.name, scene.path);
  fmt::print("mode             {}\n", mode_name(scene.simulation.mode));
  fmt::print("grains           {} ({} simulated at the end, {:.0f} on average)\n",
             s["n_total"].get<std::int64_t>(), s["n_simulated_final"].get<std::int64_t>(),
             s["n_simulated_mean"].get<double>());
  fmt::print("frames           {} ({:.2f} s simulated, k_n = {:.4g} N/m, dt = {:.3g} s)\n", frames,
             frames / scene.output.fps, s["k_n"].get<double>(), s["dt_mean"].get<double>());
  fmt::print("time per frame   {:.3f} s  (total {:.1f} s, {} threads)\n", res.wall_seconds / frames,
             res.wall_seconds, s["threads"].get<int>());
  if (fit.ok)
    fmt::print(
        "repose angle     {:.1f} +- {:.1f} deg (the fit's standard error; heap height {:.3f} "
        "m, base radius {:.3f} m)\n",
        fit.repose_angle_deg, fit.repose_angle_se_deg, fit.height, fit.base_radius);
  else
    fmt::print("repose angle     n/a ({})\n", fit.reason);
  if (s.contains("transitions")) {
    const auto& t = s["transitions"];
    fmt::print("transitions      trapped {}, dislodged {}, slept {}, woken {} (and {} within reach "
               "of a moving grain)\n",
               t["trapped"].get<std::int64_t>(), t["dislodged"].get<std::int64_t>(),
               t["slept"].get<std::int64_t>(), t["woken"].get<std::int64_t>(),
               t["woken_by_reach"].get<std::int64_t>());
    const auto& e = s["transition_energy"];
    fmt::print("energy           {:.3g} J removed by trapping, {:.3g} J added by waking ({:.3g} J "
               "of it inside moving grains)\n",
               e["removed_by_trapping_j"].get<double>(), e["added_by_waking_j"].get<double>(),
               e["opened_inside_active_j"].get<double>());
  }
  for (const auto& e : s["emitters"]) {
    const auto emitted = e["emitted"].get<std::int64_t>(), count = e["count"].get<std::int64_t>();
    const auto delayed = e["delayed_by_occupied_slots"].get<std::int64_t>();
    const auto left_out = e.value("left_out_by_occupied_slots", std::int64_t{0});
    if (left_out > 0)
      print_to_stderr(
          "warning: emitter '{}' left out {} of its {}: grains already there took "
          "their places (start it earlier, or move it)\n",
          e["name"].get<std::string>(), left_out, counted(count, "grain"));
    if (emitted + left_out < count)
      print_to_stderr("warning: emitter '{}' emitted {} of its {} before the run ended{}\n",
                      e["name"].get<std::string>(), emitted, counted(count, "grain"),
                      delayed > 0 ? fmt::format("; {} waited for slots taken by grains below it: "
                                                "raise it or add frames",
                                                counted(delayed, "grain"))
                                  : std::string(": add frames"));
    else if (delayed > 0)
      fmt::print("emitter          '{}': {} waited for a free slot\n", e["name"].get<std::string>(),
                 counted(delayed, "grain"));
  }
  fmt::print("inside geometry  {}\n", s["grains_inside_geometry"].get<std::int64_t>());
  print_overlap(s, scene);
  fmt::print("memory           {:.1f} bytes per static grain, peak {:.1f} MB\n",
             s["bytes_per_static_grain"].get<double>(),
             static_cast<double>(s["peak_memory_bytes"].get<std::int64_t>()) / 1e6);
  fmt::print("state hash       {}\n", s["state_hash"].get<std::string>());
  fmt::print("output           {}/ (stats.csv, summary.json, frames/)\n", out);
  std::vector<std::string> exports;
  for (const auto& f : s["exports"]["formats"]) exports.push_back(f.get<std::string>());
  fmt::print("exports          {} (up axis {})\n",
             exports.empty() ? "none" : fmt::format("{}", fmt::join(exports, ", ")),
             s["exports"]["up_axis"].get<std::string>());
  fmt::print("report           {} (plots; `sandflow report {}` adds pictures)\n",
             write_report({out, 6, false}), out);
  if (o.profile) {
    // in the order of the step (summary.json has them by name); forces+integration is one sweep
    fmt::print("stage seconds   ");
    for (int k = 0; k < static_cast<int>(Stage::kCount); ++k) {
      const std::string name(stage_name(static_cast<Stage>(k)));
      fmt::print(" {} {:.2f}", name, s["stage_seconds"].value(name, 0.0));
    }
    fmt::print("\n");
  }
  // (the overlap guard sees a grain crossing a surface, not one that went right through a mesh's
  // particles: counted here on the final state, which is written either way)
  if (const auto inside = s["grains_inside_geometry"].get<std::int64_t>(); inside > 0) {
    print_to_stderr(
        "error: {}: {} ended inside the geometry: they went through its surface "
        "(the contacts are too soft for the impacts, or the time step too long); the run "
        "is written, but its result is not to be trusted\n",
        scene.path, counted(inside, "grain"));
    return 3;
  }
  return 0;
}

namespace {

/// Refuses what is not one run's folder: missing, not a folder, or a comparison's (name one of its
/// runs).
void check_run_folder(const std::string& dir) {
  if (const std::string problem = folder_problem(dir); !problem.empty())
    throw InputError(dir + ": " + problem + " (expected a run folder)");
  for (const char* inside : {"surface", "dem"})
    if (fs::is_regular_file(fs::path(dir) / "compare.json") &&
        fs::is_directory(fs::path(dir) / inside / "frames"))
      throw InputError(fmt::format("{}: a comparison's folder: measure one of its runs, {}", dir,
                                   (fs::path(dir) / inside).string()));
}

/// Why a folder gives no frame to measure.
constexpr const char* kNoFrames =
    "no frames/NNNN.ply in this folder (a run writes them unless --export leaves out ply)";

}  // namespace

/// The last frame file of a run folder.
std::string last_frame(const std::string& dir) {
  check_run_folder(dir);
  const std::vector<int> frames = list_frames(dir);  // (by number: 10000 follows 9999)
  if (frames.empty()) throw InputError(fmt::format("{}: {}", dir, kNoFrames));
  return frame_path(dir, frames.back());
}

double packed_bed_level(const SceneConfig& scene, const Geometry& geometry, const CraterSite& site,
                        std::uint64_t seed) {
  BedPacking bed;
  const bool packed = !pack_bed_emitter(scene.emitters[site.bed_index], scene.material, geometry,
                                        bed_seed(seed, site.bed_index), bed);
  return packed ? bed_level(bed.x, bed.r) : std::nan("");
}

/// The crater of a finished run of a scene with a bed (`site`), measured as `compare` measures it:
/// from the bed's top as packed for the run's seed.
void print_crater(const SceneConfig& scene, const CraterSite& site, const FrameData& f) {
  const Geometry geometry = Geometry::from_config(scene.geometry, scene.material);
  const double z_ref = packed_bed_level(scene, geometry, site, scene.simulation.seed);
  const CraterFit c = measure_crater(site, z_ref, f.position, f.radius);
  fmt::print("bed's top        {:.4f} m (as packed, seed {})\n", z_ref, scene.simulation.seed);
  fmt::print("crater centre    {:.4f}, {:.4f} m ({})\n", c.centre.x, c.centre.y, site.centre_from);
  if (!c.ok) {
    fmt::print("crater           n/a ({})\n", c.reason);
    return;
  }
  fmt::print("crater_depth     {:.4f} m\n", c.depth);
  fmt::print("crater radius    {:.4f} m\n", c.radius);
  fmt::print("rim_height       {:.4f} m\n", c.rim_height);
  fmt::print("rim radius       {:.4f} m\n", c.rim_radius);
}

/// Every grain of a run at its last checkpoint, hot and static: the World rebuilt from its run.json
/// and the checkpoint restored into it (which checks that the two belong together).
FrameData grains_at_checkpoint(const SceneConfig& scene, const nlohmann::json& record,
                               const std::string& path, int& frame) {
  World world(scene);
  Checkpoint c = read_checkpoint(path);
  restore_checkpoint(world, std::move(c), scene_hash(world, start_record(record)), path);
  frame = world.frame();
  return world.all_grains_frame();
}

namespace {

/// DIR/frames/N.ply, refused with the frames the folder holds when it is not there.
FrameData read_frame(const std::string& dir, int n) {
  const std::string path = frame_path(dir, n);
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) {
    const std::vector<int> frames = list_frames(dir);
    throw InputError(frames.empty() ? fmt::format("{}: no such frame; {}", path, kNoFrames)
                                    : fmt::format("{}: no such frame; this folder's frames are "
                                                  "{} to {}",
                                                  path, frames.front(), frames.back()));
  }
  return read_ply(path);
}

/// A frame of a run, every grain in it or standing in for it, and the height the heap stands on.
struct MeasuredFrame {
  FrameData grains;
  double floor_z = std::nan("");   ///< NaN: the lowest grain's bottom (measure_heap's default)
  std::size_t static_columns = 0;  ///< columns of static sand, each standing in as one grain
};

/// The frames of one run, for `measure`. A plain-DEM frame holds every grain. A surface run's holds
/// only the grains it simulates: the sand asleep under them is its height field's static top h,
/// which the run writes beside the frame (heightfield/h_NNNN.png, the `height` export, on by
/// default in surface mode). Each column that holds static sand (h a quarter of a grain above the
/// solid under it, the rule `render` draws it by) then stands in as one grain of the mean diameter
/// whose top is h: the heap fit reads only each cell's highest top, and a column is a grain wide.
/// The heap then stands on the lowest of the grains' bottoms and the solid under the static sand.
/// The height images' grid and the scene's solids are read once, at the first surface frame, for
/// all the frames of a series.
class RunFrames {
 public:
  RunFrames(const std::string& dir, const std::optional<SceneConfig>& scene)
      : dir_(dir), scene_(scene) {
    check_run_folder(dir);
  }

  MeasuredFrame operator()(int n) {
    MeasuredFrame m;
    m.grains = read_frame(dir_, n);
    // (a folder without its run.json: an INTERFACE grain is only in a surface run's frames)
    const bool surface =
        (scene_ && scene_->simulation.mode == Mode::Surface) ||
        std::any_of(m.grains.state.begin(), m.grains.state.end(), [](std::uint8_t s) {
          return s != static_cast<std::uint8_t>(GrainState::Active);
        });
    if (!surface) return m;
    const std::string why = fmt::format(
        "{}: a surface run's frames hold only the grains it simulates; the sand asleep under them "
        "is the static top of its height field",
        dir_);
    const std::string instead = fmt::format(
        "Without --frame, measure reads the final state or last checkpoint: run it to frame {} "
        "(sandflow run ... --frames {}) and measure that",
        n, n);
    if (!scene_)
      throw InputError(
          fmt::format("{}, and without the run's run.json the solid under it is not "
                      "known. {}",
                      why, instead));
    if (!solids_) {
      grid_ = read_height_images(dir_);
      solids_ = Geometry::from_config(scene_->geometry, scene_->material, scene_->path);
    }
    const std::vector<Real> h =
        grid_ ? read_height_frame(dir_, "h", n, *grid_) : std::vector<Real>{};
    if (h.empty())
      throw InputError(fmt::format(
          "{}, written as heightfield/h_{:04d}.png by the `height` export, which this run {}. {}",
          why, n, grid_ ? "did not write for that frame" : "left out", instead));
    const Real d = scene_->material.diameter, r = d / 2;
    std::vector<Real> ground;
    const std::vector<std::uint8_t> sand = static_sand_columns(h, *grid_, *solids_, d, &ground);
    double floor_z = std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < m.grains.size(); ++i)
      floor_z = std::min(floor_z, m.grains.position[i].z - m.grains.radius[i]);
    for (std::size_t k = 0; k < h.size(); ++k) {
      if (!sand[k]) continue;
      m.grains.position.push_back(Vec3{grid_->x_of(k), grid_->y_of(k), h[k] - r});
      m.grains.radius.push_back(r);
      m.grains.velocity.push_back(Vec3{});
      m.grains.id.push_back(0);
      m.grains.state.push_back(static_cast<std::uint8_t>(GrainState::Static));
      floor_z = std::min(floor_z, ground[k]);  // (-inf over no solid: then the default below)
      ++m.static_columns;
    }
    if (std::isfinite(floor_z)) m.floor_z = floor_z;  // (no grain and no solid: the default)
    return m;
  }

 private:
  std::string dir_;
  const std::optional<SceneConfig>& scene_;
  std::optional<HeightImages> grid_;  // read with solids_, at the first surface frame
  std::optional<Geometry> solids_;
};

/// The grains of f slower than v [m/s].
FrameData slower_than(const FrameData& f, double v) {
  FrameData slow;
  for (std::size_t i = 0; i < f.size(); ++i) {
    if (norm(f.velocity[i]) >= v) continue;
    slow.position.push_back(f.position[i]);
    slow.radius.push_back(f.radius[i]);
    slow.velocity.push_back(f.velocity[i]);
    slow.id.push_back(f.id[i]);
    slow.state.push_back(f.state[i]);
  }
  return slow;
}

/// `measure --frames`: the heap of each frame of a series, one line each, then their mean, spread
/// and range: how a heap's angle moves through a run (a pour's avalanches), beside the one angle
/// of its final state.
int measure_series(const MeasureOptions& o, const std::optional<SceneConfig>& scene) {
  const FramesSpec spec = parse_frames(o.frames, true);
  const std::string& dir = o.dir;
  RunFrames read(dir, scene);  // (checks the folder)
  if (scene && crater_site(*scene).bed)
    throw InputError(
        fmt::format("--frames {}: {}: {}; measure its crater a frame at a time with "
                    "--frame N",
                    o.frames, dir, kNoHeapInABed));
  const std::vector<int> have = list_frames(dir);
  if (have.empty()) throw InputError(fmt::format("{}: {}", dir, kNoFrames));
  const int first = spec.first.value_or(have.front()), last = spec.last.value_or(have.back());
  if (last > have.back() || first < have.front())
    throw InputError(fmt::format("--frames {}: {} holds frames {} to {}", o.frames, dir,
                                 have.front(), have.back()));
  std::vector<int> frames;
  for (int n = first; n <= last; n += spec.step) {
    if (!std::binary_search(have.begin(), have.end(), n))
      throw InputError(fmt::format("--frames {}: {} is missing", o.frames, frame_path(dir, n)));
    frames.push_back(n);
  }
  fmt::print("frames           {}/frames, {} to {}{}: {}{}\n", dir, frames.front(), frames.back(),
             spec.step > 1 ? fmt::format(" in steps of {}", spec.step) : std::string(),
             counted(frames.size(), "frame"),
             o.slower_than > 0 ? fmt::format(", the grains slower than {:g} m/s", o.slower_than)
                               : std::string());
  fmt::print("{:>6} {:>16} {:>14} {:>13} {:>9} {:>9} {:>14}\n", "frame", "repose_angle_deg",
             "standard_error", "heap_height_m", "grains", "left_out", "static_columns");
  std::vector<double> angles;
  for (int n : frames) {
    MeasuredFrame m = read(n);
    const std::size_t grains = m.grains.size() - m.static_columns;
    const FrameData f = o.slower_than > 0 ? slower_than(m.grains, o.slower_than) : m.grains;
    const HeapFit fit = measure_heap(f.position, f.radius, m.floor_z);
    const std::size_t left_out = m.grains.size() - f.size();
    if (fit.ok) {
      angles.push_back(fit.repose_angle_deg);
      fmt::print("{:>6} {:>16.2f} {:>14.2f} {:>13.4f} {:>9} {:>9} {:>14}\n", n,
                 fit.repose_angle_deg, fit.repose_angle_se_deg, fit.height, grains, left_out,
                 m.static_columns);
    } else {
      fmt::print("{:>6} {:>16} {:>14} {:>13} {:>9} {:>9} {:>14}  ({})\n", n, "n/a", "", "", grains,
                 left_out, m.static_columns, fit.reason);
    }
    std::fflush(stdout);  // (a line a frame: the progress of a long series)
  }
  if (angles.empty()) {
    fmt::print("mean             n/a (no frame of the series has a heap to measure)\n");
    return 0;
  }
  const double mean = std::accumulate(angles.begin(), angles.end(), 0.0) / angles.size();
  double ss = 0;
  for (double a : angles) ss += (a - mean) * (a - mean);
  const auto [lo, hi] = std::minmax_element(angles.begin(), angles.end());
  fmt::print("mean             {:.2f} deg over {}{} (standard deviation {}, {:.2f} to {:.2f})\n",
             mean, counted(angles.size(), "frame"),
             angles.size() < frames.size()
                 ? fmt::format("; {} without a heap", frames.size() - angles.size())
                 : std::string(),
             angles.size() > 1 ? fmt::format("{:.2f}", std::sqrt(ss / (angles.size() - 1))) : "n/a",
             *lo, *hi);
  return 0;
}

}  // namespace

int measure_command(const MeasureOptions& o) {
  // the final state, every grain; else, for a run not finished, its last checkpoint (a surface
  // run's frames hold only the grains it simulates: a sleeping column's top is not in them) or,
  // in plain DEM, its last frame; or the plain-DEM frame asked for
  const std::string& dir = o.dir;
  std::error_code ec;
  std::optional<SceneConfig> scene;
  nlohmann::json record;
  if (fs::exists(fs::path(dir) / "run.json", ec)) {
    std::string text;
    const RunOptions r = read_run_record(dir, record, text);
    scene = recorded_scene(r, text, record);
  }
  const fs::path final_state = fs::path(dir) / "final_grains.ply";
  const fs::path checkpoint = fs::path(dir) / "checkpoint.bin";
  const bool finished = fs::exists(fs::path(dir) / "summary.json", ec);
  if (!o.frames.empty()) return measure_series(o, scene);
  FrameData f;
  double floor_z = std::nan("");
  std::size_t stand_ins = 0;  // static columns standing in as grains (a surface run's frame)
  if (o.frame > 0) {
    MeasuredFrame m = RunFrames(dir, scene)(o.frame);
    f = std::move(m.grains);
    floor_z = m.floor_z;
    stand_ins = m.static_columns;
    fmt::print("frame            {}\n", frame_path(dir, o.frame));
    if (m.static_columns > 0)
      fmt::print(
          "static sand      heightfield/h_{:04d}.png: {} columns, each as one grain whose "
          "top is the static top\n",
          o.frame, m.static_columns);
  } else if (fs::exists(final_state, ec)) {
    f = read_ply(final_state.string());
    fmt::print("frame            {}\n", final_state.string());
  } else if (scene && scene->simulation.mode == Mode::Surface) {
    if (!fs::exists(checkpoint, ec)) {
      const std::string why =
          finished ? fmt::format("the run finished, but its {} and checkpoint.bin are gone",
                                 final_state.filename().string())
                   : std::string("the run is not finished and has no checkpoint yet");
      throw InputError(fmt::format(
          "{}: {}. A surface run's frames hold only the grains it simulates, not the sand asleep "
          "under them, so its heap cannot be measured from them; measure it after its first "
          "checkpoint, or run it (again): {}",
          dir, why, resume_command(dir)));
    }
    int frame = 0;
    f = grains_at_checkpoint(*scene, record, checkpoint.string(), frame);
    fmt::print("frame            {} (frame {}, every grain)\n", checkpoint.string(), frame);
  } else {
    const std::string path = last_frame(dir);
    f = read_ply(path);
    fmt::print("frame            {}\n", path);
  }
  fmt::print("grains           {}\n", f.size() - stand_ins);
  if (o.slower_than > 0) {
    const std::size_t all = f.size();
    f = slower_than(f, o.slower_than);
    fmt::print("left out         {} as fast as {:g} m/s or faster\n",
               counted(all - f.size(), "grain"), o.slower_than);
  } else if (o.frame > 0) {
    fmt::print(
        "note             frame {} of the run: grains still falling or flowing are measured with "
        "the rest (--slower-than V leaves them out)\n",
        o.frame);
  } else if (!finished) {
    fmt::print(
        "note             the run is not finished: grains still falling or flowing are "
        "measured with the rest (--slower-than V leaves them out)\n");
  }
  // a scene with a bed makes a crater, not a heap (kNoHeapInABed)
  if (scene) {
    if (const CraterSite site = crater_site(*scene); site.bed) {
      print_crater(*scene, site, f);
      return 0;
    }
  }
  const HeapFit fit = measure_heap(f.position, f.radius, floor_z);
  if (!fit.ok) {
    fmt::print("repose angle     n/a ({})\n", fit.reason);
    return 0;
  }
  fmt::print("repose_angle_deg {:.2f} (standard error {:.2f})\n", fit.repose_angle_deg,
             fit.repose_angle_se_deg);
  fmt::print("heap height      {:.4f} m\n", fit.height);
  fmt::print("base radius      {:.4f} m\n", fit.base_radius);
  fmt::print("flank points     {} (rms {:.2e} m)\n", fit.points_used, fit.fit_rms);
  return 0;
}

}  // namespace sandflow
