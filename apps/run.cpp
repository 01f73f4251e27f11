// `sandflow run` and `sandflow measure`, and the run driver that `compare` and `table1` share.
#include <omp.h>

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>

#include "commands.hpp"
#include "core/error.hpp"
#include "io/export_formats.hpp"
#include "io/frame_exporter.hpp"
#include "io/ply.hpp"
#include "io/run_output.hpp"
#include "progress.hpp"
#include "scene/scene_loader.hpp"

namespace fs = std::filesystem;

namespace sandflow {

std::string mode_name(Mode m) {
  return m == Mode::Dem ? "dem" : "surface";
}

SceneConfig load_for_run(const RunOptions& o) {
  std::vector<Override> overrides;
  for (const auto& s : o.sets) overrides.push_back(parse_override(s));
  if (!o.mode.empty()) overrides.push_back({"simulation.mode", fmt::format("\"{}\"", o.mode)});
  SceneConfig scene = load_scene(o.scene, overrides);
  if (o.grains > 0) scale_grain_count(scene, o.grains);
  if (o.frames > 0) scene.output.frames = o.frames;
  if (o.threads > 0) scene.simulation.threads = o.threads;
  if (o.exports) scene.output.exports = parse_export_list(*o.exports, "--export");
  if (!o.up_axis.empty()) scene.output.up_axis = o.up_axis == "y" ? UpAxis::Y : UpAxis::Z;
  return scene;
}

namespace {

nlohmann::json heap_json(const HeapFit& fit) {
  return {{"ok", fit.ok},
          {"repose_angle_deg", fit.ok ? nlohmann::json(fit.repose_angle_deg) : nlohmann::json()},
          {"height", fit.height},
          {"base_radius", fit.base_radius},
          {"apex", {fit.apex.x, fit.apex.y, fit.apex.z}},
          {"points_used", fit.points_used},
          {"fit_rms", fit.fit_rms},
          {"reason", fit.reason}};
}

nlohmann::json stiffness_json(const Stiffness& s) {
  nlohmann::json j = {{"k_n", s.k_n}, {"from_load", s.from_load}};
  if (s.from_load) {
    j["depth"] = s.depth;
    j["impact_speed"] = s.impact_speed;
    j["k_static"] = s.k_static;
    j["k_impact"] = s.k_impact;
  }
  return j;
}

}  // namespace

int thread_count(const SceneConfig& scene) {
  return scene.simulation.threads > 0 ? scene.simulation.threads : omp_get_num_procs();
}

/// Runs a scene into `out` (prepared by the caller), writing stats.csv, frames and summary.json.
/// `label` prefixes the progress line (table1's "scene k of n: ").
RunResult run_scene(const SceneConfig& scene, const std::string& out,
                    const std::string& label) {
  World world(scene);
  for (const std::string& w : world.geometry().warnings()) fmt::print(stderr, "warning: {}\n", w);
  const int frames = world.planned_frames();
  const TimeStep& ts = world.time_step();
  const int threads = thread_count(scene);
  omp_set_num_threads(threads);
  fmt::print(stderr,
             "sandflow {}: {} ({} grains, mode {}), {} frames, k_n = {:.4g} N/m, dt = {:.3g} s, {} "
             "threads -> {}\n",
             SANDFLOW_VERSION, scene.path, scene.total_grains(), mode_name(scene.simulation.mode),
             frames, world.scene().material.k_n, ts.dt, threads, out);

  RunResult res;
  StatsWriter stats(fs::path(out) / "stats.csv");
  FrameExporter exporter(world, out);  // the per-frame files of --export
  for (const std::string& w : exporter.warnings()) fmt::print(stderr, "warning: {}\n", w);
  Progress progress(fmt::format("{}{} [{}]", label, scene.name, mode_name(scene.simulation.mode)),
                    frames);
  double simulated_sum = 0;
  Real max_overlap = 0;
  TransitionCounts transitions;
  for (int f = 0; f < frames; ++f) {
    FrameStats st = world.advance_frame();
    Stopwatch io;
    exporter.write(world);
    st.wall_seconds += io.seconds();
    stats.write(st);
    simulated_sum += static_cast<double>(st.n_active + st.n_interface);
    res.wall_seconds += st.wall_seconds;
    max_overlap = std::max(max_overlap, st.max_overlap_rel);
    transitions += st.transitions;
    res.frames.push_back(st);
    progress.update(st.frame, st.n_total, st.n_active + st.n_interface);
  }

  // the heap of the final state, and what ended up where it must not be
  world.all_grains(res.x, res.r);
  // every grain of the final state, the static ones too (state 2): nothing is lost with the run
  write_ply((fs::path(out) / "final_grains.ply").string(), world.all_grains_frame(),
            scene.output.up_axis);
  res.heap = measure_heap(res.x, res.r);
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
      {"repose_angle_deg", fit.ok ? nlohmann::json(fit.repose_angle_deg) : nlohmann::json()},
      {"heap", heap_json(fit)},
      {"grains_inside_geometry", inside},
      {"state_hash", fmt::format("{:016x}", world.state_hash())},
      {"exports", exporter.summary()},
  };
  if (const SurfaceFlow* sf = world.surface()) {
    const HeightField& hf = sf->height_field();
    Real r_sum = 0, r_max = 0;
    const std::size_t sand = hf.sand_columns();
    for (std::size_t c = 0; c < hf.columns(); ++c)
      if (hf.surface()[c] > hf.terrain()[c]) {
        r_sum += hf.rolling()[c];
        r_max = std::max(r_max, hf.rolling()[c]);
      }
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
        {"exchange_rate", hf.params().gamma},
        {"rolling_min", hf.params().rolling_min},
        {"interface_thickness", sf->params().interface.thickness},
        {"trap_speed", sf->params().interface.trap_speed},
    };
    summary["transitions"] = {{"trapped", transitions.trapped},
                              {"dislodged", transitions.dislodged},
                              {"slept", transitions.slept},
                              {"woken", transitions.woken}};
  }
  nlohmann::json emitters = nlohmann::json::array();
  for (const Emitter& e : world.emitters())
    emitters.push_back({{"name", e.name()},
                        {"count", e.count()},
                        {"emitted", e.emitted()},
                        {"delayed_by_occupied_slots", e.delayed()}});
  summary["emitters"] = emitters;
  nlohmann::json prof;
  for (int s = 0; s < static_cast<int>(Stage::kCount); ++s)
    prof[std::string(stage_name(static_cast<Stage>(s)))] = world.profile().seconds[s];
  summary["stage_seconds"] = prof;
  write_file_atomic((fs::path(out) / "summary.json").string(), summary.dump(2) + "\n");
  res.summary = summary;
  return res;
}

int run_command(const RunOptions& o) {
  const SceneConfig scene = load_for_run(o);
  if (o.check) {
    World world(scene);
    for (const std::string& w : world.geometry().warnings())
      fmt::print(stderr, "warning: {}\n", w);
    const TimeStep& ts = world.time_step();
    if (!world.dem().boundary().x.empty())
      fmt::print("{}: {} boundary particles of radius {:.3g} m on its meshes\n", scene.path,
                 world.dem().boundary().size(), world.dem().boundary().radius);
    fmt::print(
        "{}: ok — {} grains, mode {}, {} frames at {} fps, k_n = {:.4g} N/m, dt = {:.3g} s "
        "({} substeps/frame, t_c = {:.3g} s)\n",
        scene.path, scene.total_grains(), mode_name(scene.simulation.mode), world.planned_frames(),
        scene.output.fps, world.scene().material.k_n, ts.dt, ts.substeps, ts.t_c);
    std::vector<std::string> exports;
    std::vector<ExportFormat> dropped;
    for (const ExportFormat f : run_exports(scene.output, scene.simulation.mode, &dropped))
      exports.emplace_back(export_name(f));
    if (!dropped.empty())
      fmt::print(stderr, "warning: {}\n", dropped_exports_warning(scene.path, dropped));
    fmt::print("{}: exports {} each frame (up axis {})\n", scene.path,
               exports.empty() ? "nothing" : fmt::format("{}", fmt::join(exports, ", ")),
               up_axis_name(scene.output.up_axis));
    return 0;
  }
  const std::string out =
      o.out.empty() ? fmt::format("out/{}-{}", scene.name, mode_name(scene.simulation.mode))
                    : o.out;
  prepare_output_dir(out, o.force);
  const RunResult res = run_scene(scene, out);
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
    fmt::print("repose angle     {:.1f} deg (heap height {:.3f} m, base radius {:.3f} m)\n",
               fit.repose_angle_deg, fit.height, fit.base_radius);
  else
    fmt::print("repose angle     n/a ({})\n", fit.reason);
  if (s.contains("transitions")) {
    const auto& t = s["transitions"];
    fmt::print("transitions      trapped {}, dislodged {}, slept {}, woken {}\n",
               t["trapped"].get<std::int64_t>(), t["dislodged"].get<std::int64_t>(),
               t["slept"].get<std::int64_t>(), t["woken"].get<std::int64_t>());
  }
  for (const auto& e : s["emitters"]) {
    const auto emitted = e["emitted"].get<std::int64_t>(), count = e["count"].get<std::int64_t>();
    const auto delayed = e["delayed_by_occupied_slots"].get<std::int64_t>();
    if (emitted < count)
      fmt::print(stderr,
                 "warning: emitter '{}' emitted {} of its {} grains before the run ended; {} "
                 "grains waited for slots taken by grains below it: raise it or add frames\n",
                 e["name"].get<std::string>(), emitted, count, delayed);
    else if (delayed > 0)
      fmt::print("emitter          '{}': {} grains waited for a free slot\n",
                 e["name"].get<std::string>(), delayed);
  }
  fmt::print("inside geometry  {}\n", s["grains_inside_geometry"].get<std::int64_t>());
  fmt::print("max overlap      {:.2f} % of a diameter\n", 100 * s["max_overlap_rel"].get<double>());
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
    fmt::print("stage seconds   ");
    for (const auto& [k, v] : s["stage_seconds"].items())
      fmt::print(" {} {:.2f}", k, v.get<double>());
    fmt::print("\n");
  }
  return 0;
}

/// The last frame file of a run folder.
std::string last_frame(const std::string& dir) {
  std::string best;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(fs::path(dir) / "frames", ec))
    if (e.path().extension() == ".ply" && e.path().string() > best) best = e.path().string();
  if (best.empty())
    throw InputError(fmt::format(
        "{}: no frames/NNNN.ply in this folder (a run writes them unless --export leaves out ply)",
        dir));
  return best;
}

int measure_command(const std::string& dir) {
  const std::string path = last_frame(dir);
  const FrameData f = read_ply(path);
  const HeapFit fit = measure_heap(f.position, f.radius);
  fmt::print("frame            {}\n", path);
  fmt::print("grains           {}\n", f.size());
  if (!fit.ok) {
    fmt::print("repose angle     n/a ({})\n", fit.reason);
    return 0;
  }
  fmt::print("repose_angle_deg {:.2f}\n", fit.repose_angle_deg);
  fmt::print("heap height      {:.4f} m\n", fit.height);
  fmt::print("base radius      {:.4f} m\n", fit.base_radius);
  fmt::print("flank points     {} (rms {:.2e} m)\n", fit.points_used, fit.fit_rms);
  return 0;
}

}  // namespace sandflow
