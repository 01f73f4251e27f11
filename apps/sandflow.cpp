// The `sandflow` command: argument parsing, printing and exit codes. The simulation itself is in
// the library (src/); this file only drives it.
//
// Exit status: 0 done, 1 unexpected failure, 2 bad input (scene, option, file),
// 3 the simulation blew up, 4 an output could not be written.
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "analysis/heap.hpp"
#include "analysis/surface_diff.hpp"
#include "core/error.hpp"
#include "io/ply.hpp"
#include "io/pov_writer.hpp"
#include "io/run_output.hpp"
#include "progress.hpp"
#include "scene/scene_loader.hpp"
#include "scene/world.hpp"
#include "surface/surface_params.hpp"
#include "table1.hpp"

namespace fs = std::filesystem;
using namespace sandflow;

namespace {

struct RunOptions {
  std::string scene;
  std::string mode;
  std::string out;
  int frames = 0;
  std::int64_t grains = 0;
  int threads = 0;
  std::vector<std::string> sets;
  bool check = false;
  bool force = false;
  bool profile = false;
};

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
  return scene;
}

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

int thread_count(const SceneConfig& scene) {
  return scene.simulation.threads > 0 ? scene.simulation.threads : omp_get_num_procs();
}

/// What a finished run leaves for the caller: its summary and its final grains.
struct RunResult {
  nlohmann::json summary;
  std::vector<FrameStats> frames;
  std::vector<Vec3> x;  ///< every grain's centre at the end
  std::vector<Real> r;
  double wall_seconds = 0;
  HeapFit heap;
};

/// Runs a scene into `out` (prepared by the caller), writing stats.csv, frames and summary.json.
/// `label` prefixes the progress line (table1's "scene k of n: ").
RunResult run_scene(const SceneConfig& scene, const std::string& out,
                    const std::string& label = "") {
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
  Progress progress(fmt::format("{}{} [{}]", label, scene.name, mode_name(scene.simulation.mode)),
                    frames);
  double simulated_sum = 0;
  Real max_overlap = 0;
  TransitionCounts transitions;
  for (int f = 0; f < frames; ++f) {
    FrameStats st = world.advance_frame();
    Stopwatch io;
    if (scene.output.write_frames) write_ply(frame_path(out, st.frame), world.visible_frame());
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
  write_ply((fs::path(out) / "final_grains.ply").string(), world.all_grains_frame());
  res.heap = measure_heap(res.x, res.r);
  const HeapFit& fit = res.heap;
  const auto inside = world.geometry().count_inside(res.x);
  const FrameStats& last = res.frames.back();
  nlohmann::json summary = {
      {"sandflow_version", SANDFLOW_VERSION},
      {"scene", scene.name},
      {"scene_file", scene.path},
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
  if (o.profile) {
    fmt::print("stage seconds   ");
    for (const auto& [k, v] : s["stage_seconds"].items())
      fmt::print(" {} {:.2f}", k, v.get<double>());
    fmt::print("\n");
  }
  return 0;
}

/// Mean of the simulated fraction (active + interface over all grains) over frames [first, end).
double simulated_fraction(const std::vector<FrameStats>& frames, std::size_t first) {
  double sum = 0;
  std::size_t n = 0;
  for (std::size_t k = first; k < frames.size(); ++k, ++n)
    sum += frames[k].n_total > 0 ? static_cast<double>(frames[k].n_active + frames[k].n_interface) /
                                       static_cast<double>(frames[k].n_total)
                                 : 1.0;
  return n ? sum / static_cast<double>(n) : 0.0;
}

nlohmann::json angle_json(const HeapFit& f) {
  return f.ok ? nlohmann::json(f.repose_angle_deg) : nlohmann::json();
}

/// Prepares a comparison folder: OUT is refused when not empty unless `force`, in which case the
/// earlier comparison (compare.json, dem/, surface/) is removed; OUT/dem and OUT/surface are made.
void prepare_compare_dir(const std::string& out, bool force) {
  std::error_code ec;
  if (fs::exists(out, ec) && !fs::is_directory(out, ec))
    throw InputError(fmt::format("{}: the output path exists and is not a folder", out));
  if (fs::exists(out, ec) && !fs::is_empty(out, ec)) {
    if (!force)
      throw InputError(fmt::format(
          "{}: the output folder is not empty; pass --force to replace its comparison", out));
    for (const char* name : {"compare.json", "dem", "surface"})
      fs::remove_all(fs::path(out) / name, ec);
  }
  prepare_output_dir((fs::path(out) / "surface").string(), false);
  prepare_output_dir((fs::path(out) / "dem").string(), false);
}

/// Both runs of a scene and the figures compared (what compare.json holds).
struct Comparison {
  RunResult surface, dem;
  SurfaceDiff diff;
  nlohmann::json json;
};

/// The shared part of `compare` and `table1`: runs `scene` in surface mode into OUT/surface, then
/// in plain DEM into OUT/dem, compares the two final surfaces and writes OUT/compare.json.
/// OUT is prepared here (see prepare_compare_dir); `label` prefixes the progress lines.
Comparison compare_scene(const SceneConfig& scene, const std::string& out, bool force,
                         const std::string& label = "") {
  prepare_compare_dir(out, force);
  SceneConfig surface_scene = scene, dem_scene = scene;
  surface_scene.simulation.mode = Mode::Surface;
  dem_scene.simulation.mode = Mode::Dem;
  Comparison c;
  c.surface = run_scene(surface_scene, (fs::path(out) / "surface").string(), label);
  c.dem = run_scene(dem_scene, (fs::path(out) / "dem").string(), label);
  const RunResult& surf = c.surface;
  const RunResult& dem = c.dem;

  // both final surfaces on the surface run's grid, from every grain
  const Geometry geometry = Geometry::from_config(scene.geometry, scene.material);
  const SurfaceParams sp =
      surface_params(surface_scene, geometry, surf.summary["dt_mean"].get<double>());
  const TerrainColumns L = terrain_columns(sp, geometry);
  c.diff = compare_surfaces(measure_surface(sp.grid, L, dem.x, dem.r),
                            measure_surface(sp.grid, L, surf.x, surf.r));
  const SurfaceDiff& diff = c.diff;

  const std::size_t n_frames = surf.frames.size();
  const FrameStats& last = surf.frames.back();
  const double frac_final = static_cast<double>(last.n_active + last.n_interface) /
                            static_cast<double>(std::max<std::int64_t>(last.n_total, 1));
  const double k_dem = dem.summary["k_n"].get<double>(), k_surf = surf.summary["k_n"].get<double>();
  const double angle_diff = surf.heap.ok && dem.heap.ok
                                ? std::abs(surf.heap.repose_angle_deg - dem.heap.repose_angle_deg)
                                : std::nan("");
  c.json = {
      {"scene", scene.name},
      {"scene_file", scene.path},
      {"frames", n_frames},
      {"n_total", last.n_total},
      {"speedup", dem.wall_seconds / std::max(surf.wall_seconds, 1e-12)},
      {"simulated_fraction_mean", simulated_fraction(surf.frames, 0)},
      {"simulated_fraction_last_half", simulated_fraction(surf.frames, n_frames / 2)},
      {"simulated_fraction_final", frac_final},
      {"n_simulated_mean", surf.summary["n_simulated_mean"]},
      {"n_simulated_final", last.n_active + last.n_interface},
      {"n_simulated_mean_dem", dem.summary["n_simulated_mean"]},
      {"seconds_per_frame_dem", dem.wall_seconds / n_frames},
      {"seconds_per_frame_surface", surf.wall_seconds / n_frames},
      {"wall_seconds_dem", dem.wall_seconds},
      {"wall_seconds_surface", surf.wall_seconds},
      {"dt_dem", dem.summary["dt_mean"]},
      {"dt_surface", surf.summary["dt_mean"]},
      {"k_n_dem", k_dem},
      {"k_n_surface", k_surf},
      {"same_stiffness", k_dem == k_surf},
      {"repose_angle_dem_deg", angle_json(dem.heap)},
      {"repose_angle_surface_deg", angle_json(surf.heap)},
      {"repose_angle_difference_deg",
       std::isnan(angle_diff) ? nlohmann::json() : nlohmann::json(angle_diff)},
      {"surface_rms", diff.rms},
      {"surface_rms_rel", diff.rms_rel},
      {"heap_height_dem", diff.heap_height},
      {"surface_columns_compared", diff.columns},
      {"grains_inside_geometry_dem", dem.summary["grains_inside_geometry"]},
      {"grains_inside_geometry_surface", surf.summary["grains_inside_geometry"]},
      {"threads", thread_count(scene)},
  };
  write_file_atomic((fs::path(out) / "compare.json").string(), c.json.dump(2) + "\n");
  return c;
}

int compare_command(const RunOptions& o) {
  const SceneConfig scene = load_for_run(o);
  const std::string out = o.out.empty() ? fmt::format("out/{}-compare", scene.name) : o.out;
  const Comparison c = compare_scene(scene, out, o.force);
  const RunResult& surf = c.surface;
  const RunResult& dem = c.dem;
  const nlohmann::json& j = c.json;
  const std::size_t n_frames = surf.frames.size();
  const FrameStats& last = surf.frames.back();
  const double k_dem = j["k_n_dem"].get<double>(), k_surf = j["k_n_surface"].get<double>();

  auto angle = [](const HeapFit& f) {
    return f.ok ? fmt::format("{:.1f} deg", f.repose_angle_deg) : std::string("n/a");
  };
  fmt::print("\n{} ({} grains, {} frames, {} threads)\n", scene.name, last.n_total, n_frames,
             thread_count(scene));
  fmt::print("{:<34}{:>16}{:>16}\n", "", "plain DEM", "surface flow");
  fmt::print("{:<34}{:>16}{:>16}\n", "total grains", dem.frames.back().n_total, last.n_total);
  fmt::print("{:<34}{:>16.0f}{:>16.0f}\n", "simulated grains, mean",
             dem.summary["n_simulated_mean"].get<double>(),
             surf.summary["n_simulated_mean"].get<double>());
  fmt::print("{:<34}{:>16}{:>15.1f}%\n", "simulated fraction, mean", "100%",
             100 * j["simulated_fraction_mean"].get<double>());
  fmt::print("{:<34}{:>16}{:>15.1f}%\n", "simulated fraction, last half", "100%",
             100 * j["simulated_fraction_last_half"].get<double>());
  fmt::print("{:<34}{:>16}{:>16}\n", "simulated grains, final", dem.frames.back().n_total,
             last.n_active + last.n_interface);
  fmt::print("{:<34}{:>16.3f}{:>16.3f}\n", "seconds per frame", dem.wall_seconds / n_frames,
             surf.wall_seconds / n_frames);
  fmt::print("{:<34}{:>16.3g}{:>16.3g}\n", "k_n [N/m]", k_dem, k_surf);
  fmt::print("{:<34}{:>16.3g}{:>16.3g}\n", "dt [s]", dem.summary["dt_mean"].get<double>(),
             surf.summary["dt_mean"].get<double>());
  fmt::print("{:<34}{:>16}{:>16}\n", "repose angle", angle(dem.heap), angle(surf.heap));
  fmt::print(
      "speed-up {:.2f}x; surfaces differ by {:.4f} m RMS = {:.1f}% of the heap height "
      "({:.3f} m); {} stiffness in both modes\n",
      j["speedup"].get<double>(), c.diff.rms, 100 * c.diff.rms_rel, c.diff.heap_height,
      k_dem == k_surf ? "the same" : "a different");
  fmt::print("output           {}/ (compare.json, dem/, surface/)\n", out);
  return 0;
}

struct Table1Options {
  double scale = 1;
  int frames = 0;
  int threads = 0;
  std::string out = "out/table1";
  std::string scene_dir;
  std::vector<std::string> scenes;
  bool force = false;
};

/// Where table1 finds scenes/<name>.toml: --scene-dir when given, else ./scenes when the current
/// folder has one (as `run` and `compare` take paths from the current folder), else the scenes/
/// of the source tree this binary was built from.
std::string table1_scene_dir(const std::string& given) {
  std::error_code ec;
  if (!given.empty()) {
    if (!fs::is_directory(given, ec))
      throw InputError(fmt::format("--scene-dir {}: no such folder", given));
    return given;
  }
  if (fs::is_directory("scenes", ec)) return "scenes";
  return (fs::path(SANDFLOW_SOURCE_DIR) / "scenes").string();
}

/// The scenes asked for, checked against the paper's five: unknown or repeated names are refused.
std::vector<const PaperScene*> table1_scenes(const Table1Options& o) {
  std::vector<const PaperScene*> list;
  if (o.scenes.empty())
    for (const PaperScene& p : kPaperTable1) list.push_back(&p);
  for (const std::string& name : o.scenes) {
    const PaperScene* p = find_paper_scene(name);
    if (!p)
      throw InputError(fmt::format("--scenes: unknown scene '{}'; the paper's scenes are {}", name,
                                   known_scene_names()));
    if (std::find(list.begin(), list.end(), p) != list.end())
      throw InputError(fmt::format("--scenes: '{}' is listed twice", name));
    list.push_back(p);
  }
  return list;
}

/// The command line as typed, quoted where a shell would need it.
std::string command_line(int argc, char** argv) {
  std::string s;
  for (int k = 0; k < argc; ++k) {
    std::string a = argv[k];
    if (a.empty() || a.find_first_of(" \t'\"$\\*?;&|<>()") != std::string::npos) {
      std::string q = "'";
      for (char ch : a) q += ch == '\'' ? std::string("'\\''") : std::string(1, ch);
      a = q + "'";
    }
    s += (k ? " " : "") + a;
  }
  return s;
}

std::string local_date_time() {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  localtime_r(&now, &tm);
  char buf[64];
  return std::strftime(buf, sizeof buf, "%Y-%m-%d %H:%M %Z", &tm) ? buf : "unknown date";
}

/// The row of a scene that ran, from its comparison.
Table1Row table1_row(const std::string& name, std::int64_t total, const Comparison& c) {
  Table1Row r;
  r.scene = name;
  r.status = RowStatus::Done;
  r.total = total;
  r.emitted = c.surface.frames.back().n_total;
  r.surface_simulated_mean = c.surface.summary["n_simulated_mean"].get<double>();
  r.surface_s_per_frame = c.json["seconds_per_frame_surface"].get<double>();
  r.dem_simulated_mean = c.dem.summary["n_simulated_mean"].get<double>();
  r.dem_s_per_frame = c.json["seconds_per_frame_dem"].get<double>();
  r.speedup = c.json["speedup"].get<double>();
  r.surface_rms_rel = c.diff.rms_rel;
  r.inside_dem = c.dem.summary["grains_inside_geometry"].get<std::int64_t>();
  r.inside_surface = c.surface.summary["grains_inside_geometry"].get<std::int64_t>();
  return r;
}

int table1_command(const Table1Options& o, const std::string& command) {
  // everything that can be refused is checked before anything is written
  if (!(o.scale > 0) || !(o.scale <= 100))
    throw InputError(fmt::format(
        "--scale {}: expected a number in (0, 100], the fraction of the paper's grain counts",
        o.scale));
  const std::vector<const PaperScene*> scenes = table1_scenes(o);
  for (const PaperScene* p : scenes)
    if (scaled_count(*p, o.scale) < 1)
      throw InputError(fmt::format("--scale {}: gives no grains for {} (round({} x {}) = 0)",
                                   o.scale, p->name, o.scale, p->total));
  const std::string scene_dir = table1_scene_dir(o.scene_dir);
  std::error_code ec;
  if (fs::exists(o.out, ec) && !fs::is_directory(o.out, ec))
    throw InputError(fmt::format("{}: the output path exists and is not a folder", o.out));
  if (fs::exists(o.out, ec) && !fs::is_empty(o.out, ec)) {
    if (!o.force)
      throw InputError(fmt::format(
          "{}: the output folder is not empty; pass --force to replace its table", o.out));
    for (const char* name : {"table1.csv", "table1.md"}) fs::remove(fs::path(o.out) / name, ec);
  }
  fs::create_directories(o.out, ec);
  if (ec)
    throw OutputError(fmt::format("{}: cannot create the output folder: {}", o.out, ec.message()));

  std::vector<Table1Row> rows(scenes.size());
  for (std::size_t k = 0; k < scenes.size(); ++k) rows[k].scene = std::string(scenes[k]->name);
  Table1Context ctx{command,
                    local_date_time(),
                    omp_get_num_procs(),
                    o.threads > 0 ? o.threads : omp_get_num_procs(),
                    o.scale,
                    o.frames};
  // rewritten after every scene, so an interrupted run keeps the scenes that finished
  auto write_table = [&] {
    write_file_atomic((fs::path(o.out) / "table1.csv").string(), table1_csv(rows));
    write_file_atomic((fs::path(o.out) / "table1.md").string(), table1_markdown(rows, ctx));
  };
  write_table();

  int status = 0;  // of the first scene that failed
  std::size_t ran = 0;
  for (std::size_t k = 0; k < scenes.size(); ++k) {
    const PaperScene& p = *scenes[k];
    Table1Row& row = rows[k];
    const std::string label = fmt::format("scene {} of {}: ", k + 1, scenes.size());
    const fs::path file = fs::path(scene_dir) / (std::string(p.name) + ".toml");
    if (!fs::exists(file, ec)) {
      row.status = RowStatus::Missing;
      row.message = fmt::format("no scene file {}", file.string());
      fmt::print(stderr, "table1: {}{} skipped: {}\n", label, p.name, row.message);
      write_table();
      continue;
    }
    const std::int64_t total = scaled_count(p, o.scale);
    auto fail = [&](const std::exception& e, int code) {
      row.status = RowStatus::Failed;
      row.message = e.what();
      if (status == 0) status = code;
      fmt::print(stderr, "\ntable1: {}{} failed: {}\n", label, p.name, row.message);
    };
    try {
      RunOptions ro;
      ro.scene = file.string();
      ro.grains = total;
      ro.frames = o.frames;
      ro.threads = o.threads;
      const SceneConfig full = load_scene(ro.scene);
      if (full.total_grains() != p.total)
        fmt::print(stderr,
                   "warning: {} has {} grains, the paper's {} {}; table1 scales the paper's "
                   "count\n",
                   ro.scene, full.total_grains(), p.title, p.total);
      const SceneConfig scene = load_for_run(ro);
      if (scene.total_grains() != total)
        throw InputError(
            fmt::format("{}: cannot scale its emitters to {} grains", ro.scene, total));
      ctx.threads = thread_count(scene);
      fmt::print(stderr, "table1: {}{}, {} grains ({} x {}), surface flow then plain DEM -> {}\n",
                 label, p.name, total, o.scale, p.total, (fs::path(o.out) / p.name).string());
      const Comparison c =
          compare_scene(scene, (fs::path(o.out) / p.name).string(), o.force, label);
      row = table1_row(std::string(p.name), total, c);
      ++ran;
    } catch (const InputError& e) {
      fail(e, 2);
    } catch (const SimulationError& e) {
      fail(e, 3);
    } catch (const OutputError& e) {
      fail(e, 4);
    } catch (const std::exception& e) {
      fail(e, 1);
    }
    write_table();
  }

  fmt::print("\n{}", table1_text(rows));
  fmt::print(
      "output  {}/ (table1.csv, table1.md, SCENE/compare.json, SCENE/dem/, SCENE/surface/)\n",
      o.out);
  if (status != 0) return status;
  if (ran == 0) {
    fmt::print(stderr, "error: no scene ran: none of the scene files was found in {}\n", scene_dir);
    return 2;
  }
  return 0;
}

/// The last frame file of a run folder.
std::string last_frame(const std::string& dir) {
  std::string best;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(fs::path(dir) / "frames", ec))
    if (e.path().extension() == ".ply" && e.path().string() > best) best = e.path().string();
  if (best.empty()) throw InputError(fmt::format("{}: no frames/NNNN.ply in this folder", dir));
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

int render_command(const std::string& dir, int width, int height, int frame) {
  const std::string ply = frame > 0 ? frame_path(dir, frame) : last_frame(dir);
  const FrameData f = read_ply(ply);
  // the geometry comes from the scene file the run recorded
  std::vector<GeometryConfig> geometry;
  Geometry placed;  // its meshes, placed
  std::vector<const TriangleMesh*> meshes;
  std::ifstream in(fs::path(dir) / "summary.json");
  if (in) {
    const auto summary = nlohmann::json::parse(in, nullptr, false);
    if (!summary.is_discarded() && summary.contains("scene_file")) {
      const SceneConfig scene = load_scene(summary["scene_file"].get<std::string>());
      geometry = scene.geometry;
      placed = Geometry::from_config(geometry, scene.material, scene.path);
      std::size_t next = 0;
      for (const GeometryConfig& g : geometry)
        meshes.push_back(g.type == GeometryType::Mesh ? &placed.meshes()[next++].mesh : nullptr);
    }
  }
  if (find_povray().empty())
    throw InputError("povray is not installed: sudo apt-get install povray");
  fs::create_directories(fs::path(dir) / "render");
  const std::string stem = (fs::path(dir) / "render" / fs::path(ply).stem()).string();
  PovOptions opt;
  opt.width = width;
  opt.height = height;
  write_pov_scene(stem + ".pov", f, geometry, opt, meshes);
  render_pov(stem + ".pov", stem + ".png", width, height, omp_get_num_procs());
  fmt::print("{}\n", stem + ".png");
  return 0;
}

/// The options of the commands that run a scene: the file, where to write, and how to scale it.
void add_scene_options(CLI::App* cmd, RunOptions& o, const std::string& out_help,
                       const std::string& set_help) {
  cmd->add_option("scene", o.scene, "scene file (TOML)")->required();
  cmd->add_option("--out", o.out, out_help);
  cmd->add_option("--frames", o.frames, "number of frames (default: from the scene)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--grains", o.grains, "scale the emitters to N grains in total")
      ->check(CLI::Range(std::int64_t{1}, std::int64_t{2000000000}));
  cmd->add_option("--threads", o.threads, "OpenMP threads (default: all cores)")
      ->check(CLI::Range(1, 1024));
  cmd->add_option("--set", o.sets, set_help);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "sandflow: sand animated as a surface flow (Zhu & Yang 2010), with plain DEM beside it"};
  app.require_subcommand(1);
  app.set_version_flag("--version", SANDFLOW_VERSION);

  RunOptions ro;
  auto* run = app.add_subcommand("run", "simulate a scene and write its frames and statistics");
  add_scene_options(run, ro, "output folder (default out/SCENE-MODE)",
                    "override a scene key: --set material.friction=0.5");
  run->add_option("--mode", ro.mode, "surface (height field + DEM) or dem (plain DEM)")
      ->check(CLI::IsMember({"surface", "dem"}));
  run->add_flag("--check", ro.check, "validate the scene and print its plan, then stop");
  run->add_flag("--force", ro.force, "replace the run in a non-empty output folder");
  run->add_flag("--profile", ro.profile, "print the seconds spent in each stage");

  std::string dir;
  auto* measure = app.add_subcommand("measure", "print the angle of repose of a run's last frame");
  measure->add_option("dir", dir, "run folder")->required();

  RunOptions co;
  auto* compare = app.add_subcommand(
      "compare", "run a scene in both modes and compare speed, grains simulated and the heaps");
  add_scene_options(compare, co, "output folder (default out/SCENE-compare)",
                    "override a scene key in both runs");
  compare->add_flag("--force", co.force, "replace a comparison in a non-empty output folder");

  Table1Options to;
  auto* table1 = app.add_subcommand(
      "table1",
      "the paper's Table 1: run its scenes in both modes (as compare does) and tabulate them");
  table1->add_option("--scale", to.scale,
                     "grains per scene: round(F x the paper's count), F in (0, 100] (default 1)");
  table1->add_option("--frames", to.frames, "number of frames per run (default: each scene's)")
      ->check(CLI::PositiveNumber);
  table1->add_option("--out", to.out, "output folder (default out/table1)");
  table1
      ->add_option("--scenes", to.scenes,
                   "comma-separated subset of floor,terrain,bowl,dragon,armadillo (default: all "
                   "five)")
      ->delimiter(',');
  table1->add_option("--scene-dir", to.scene_dir,
                     "folder of the scene files NAME.toml (default: ./scenes if there is one, "
                     "else the source tree's scenes/)");
  table1->add_option("--threads", to.threads, "OpenMP threads (default: all cores)")
      ->check(CLI::Range(1, 1024));
  table1->add_flag("--force", to.force,
                   "write into a non-empty output folder, replacing its table and the folders of "
                   "the scenes run");
  table1->footer(
      "Writes DIR/table1.csv (one row per scene that ran), DIR/table1.md (every scene, the\n"
      "command, date, cores and threads, and the paper's figures) and DIR/SCENE/ (compare.json,\n"
      "dem/, surface/), rewriting both tables after each scene. A scene whose file SCENE.toml is\n"
      "missing is skipped: listed as missing, and the others still run. A scene that fails is\n"
      "listed as failed with its error, and the others still run.\n"
      "Exit status: 0 when every scene whose file was found ran; otherwise that of the first\n"
      "scene that failed (2 bad input, 3 blow-up, 4 output, 1 other); 2 when no scene file was\n"
      "found at all (the tables list every scene as missing) or an option is bad (then nothing\n"
      "is written).");

  int width = 1280, height = 720, frame = 0;
  auto* render = app.add_subcommand("render", "render a run's frame with POV-Ray to PNG");
  render->add_option("dir", dir, "run folder")->required();
  render->add_option("--width", width, "image width")->check(CLI::Range(16, 16384));
  render->add_option("--height", height, "image height")->check(CLI::Range(16, 16384));
  render->add_option("--frame", frame, "frame number (default: the last)")
      ->check(CLI::PositiveNumber);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? 0 : 2;
  }
  try {
    if (*run) return run_command(ro);
    if (*compare) return compare_command(co);
    if (*table1) return table1_command(to, command_line(argc, argv));
    if (*measure) return measure_command(dir);
    if (*render) return render_command(dir, width, height, frame);
  } catch (const InputError& e) {
    fmt::print(stderr, "error: {}\n", e.what());
    return 2;
  } catch (const SimulationError& e) {
    fmt::print(stderr, "\nsimulation stopped: {}\n", e.what());
    return 3;
  } catch (const OutputError& e) {
    fmt::print(stderr, "\noutput error: {}\n", e.what());
    return 4;
  } catch (const std::exception& e) {
    fmt::print(stderr, "\nerror: {}\n", e.what());
    return 1;
  }
  return 0;
}
