// `sandflow compare`: a scene run in both modes, with several seeds each, and the two compared
// against the spread between the plain-DEM seeds (docs/design.md §9: sameness is statistics).
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "analysis/crater.hpp"
#include "analysis/statistics.hpp"
#include "commands.hpp"
#include "console.hpp"
#include "core/atomic_file.hpp"
#include "core/counted.hpp"
#include "core/error.hpp"
#include "core/read_file.hpp"
#include "io/folder_lock.hpp"
#include "scene/scene_loader.hpp"
#include "surface/surface_params.hpp"

namespace fs = std::filesystem;

namespace sandflow {

namespace {

constexpr const char* kPlanFile = "compare_plan.json";
constexpr const char* kEqualStiffnessDir = "dem-equal-stiffness";

double max_overlap(const RunResult& r) {
  double m = 0;
  for (const FrameStats& f : r.frames) m = std::max(m, f.max_overlap_rel);
  return m;
}

nlohmann::json number_or_null(double v) {
  return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json();
}

/// The heap angles of the runs whose fit worked.
std::vector<double> angles(const std::vector<RunResult>& runs) {
  std::vector<double> a;
  for (const RunResult& r : runs)
    if (r.heap.ok) a.push_back(r.heap.repose_angle_deg);
  return a;
}

/// Largest minus smallest of the values; NaN for fewer than two (one seed has no spread).
double spread_of(const std::vector<double>& v) {
  if (v.size() < 2) return std::nan("");
  return *std::max_element(v.begin(), v.end()) - *std::min_element(v.begin(), v.end());
}

/// What the fits that worked measured, `what` of each.
std::vector<double> crater_values(const std::vector<CraterFit>& fits, double CraterFit::*what) {
  std::vector<double> v;
  for (const CraterFit& f : fits)
    if (f.ok) v.push_back(f.*what);
  return v;
}

nlohmann::json crater_json(const CraterFit& f) {
  auto ok_or_null = [&](double v) { return f.ok ? nlohmann::json(v) : nlohmann::json(); };
  return {{"ok", f.ok},
          {"depth", ok_or_null(f.depth)},
          {"rim_height", ok_or_null(f.rim_height)},
          {"radius", ok_or_null(f.radius)},
          {"rim_radius", ok_or_null(f.rim_radius)},
          {"centre", f.ok ? nlohmann::json::array({f.centre.x, f.centre.y}) : nlohmann::json()},
          {"reason", f.reason}};
}

/// Prepares a comparison folder and locks it (the lock is returned: hold it while the comparison
/// runs): OUT is refused when not empty unless `force`, in which case the earlier comparison is
/// removed, or `resume`, which keeps it.
std::unique_ptr<FolderLock> prepare_compare_dir(const std::string& out, bool force, bool resume) {
  auto lock = std::make_unique<FolderLock>(out);  // (refuses a path that is not a folder)
  std::error_code ec;
  if (fs::exists(out, ec) && !fs::is_empty(out, ec) && !resume) {
    if (!force)
      throw InputError(fmt::format(
          "{}: the output folder is not empty; pass --force to replace its comparison, or "
          "--resume to go on with it",
          out));
    const auto renders = lock_render_folders(out, 3);  // (held while the runs go)
    for (const auto& e : fs::directory_iterator(out, ec)) {
      const std::string name = e.path().filename().string();
      if (name == "compare.json" || name == kPlanFile || name == "dem" || name == "surface" ||
          name == "report.html" || name == kEqualStiffnessDir || name.rfind("seed-", 0) == 0)
        fs::remove_all(e.path(), ec);
    }
  }
  fs::create_directories(out, ec);
  if (ec) throw OutputError(fmt::format("{}: cannot create the output folder: {}", out, ec.message()));
  return lock;
}

/// The plan of a comparison, written when it starts so that --resume goes on with the same one.
void write_plan(const std::string& out, const CompareOptions& co) {
  nlohmann::json plan{{"seeds", co.seeds}, {"equal_stiffness", co.equal_stiffness}};
  if (co.run_to_frame > 0) plan["run_to_frame"] = co.run_to_frame;
  if (!co.dem_from.empty()) plan["dem_from"] = co.dem_from;
  write_file_atomic((fs::path(out) / kPlanFile).string(), plan.dump(2) + "\n");
}

/// What `out` records of its plan; a comparison from before plans were kept ran one seed.
CompareOptions read_plan(const std::string& out) {
  CompareOptions co;
  co.seeds = 1;
  const fs::path path = fs::path(out) / kPlanFile;
  std::error_code ec;
  if (!fs::exists(path, ec)) {
    // (only a comparison of one seed is a folder with no seed-S/ in it)
    for (const auto& e : fs::directory_iterator(out, ec))
      if (e.path().filename().string().rfind("seed-", 0) == 0)
        throw InputError(fmt::format(
            "{}: missing, but {} holds {}: the plan of its seeds is lost; run the comparison "
            "again with --force",
            path.string(), out, e.path().filename().string()));
    return co;
  }
  try {
    const nlohmann::json j =
        nlohmann::json::parse(read_whole_file(path.string(), "comparison plan", kAnyFileSize));
    co.seeds = j.at("seeds").get<int>();
    co.equal_stiffness = j.at("equal_stiffness").get<bool>();
    co.run_to_frame = j.value("run_to_frame", 0);
    co.dem_from = j.value("dem_from", std::string());
  } catch (const nlohmann::json::exception& e) {
    throw InputError(fmt::format("{}: not a comparison plan sandflow can read: {}", path.string(),
                                 e.what()));
  }
  if (co.seeds < 1 || co.seeds > kMaxSeeds)
    throw InputError(fmt::format("{}: seeds = {} is outside [1, {}]", path.string(), co.seeds,
                                 kMaxSeeds));
  if (co.run_to_frame < 0)
    throw InputError(
        fmt::format("{}: run_to_frame = {} is negative", path.string(), co.run_to_frame));
  return co;
}

/// How many frames the run in `dir` has written (the rows of its stats.csv; 0 when there is none).
int frames_written(const std::string& dir) {
  const std::optional<std::string> text =
      read_file_if_present((fs::path(dir) / "stats.csv").string(), "statistics file", kAnyFileSize);
  if (!text) return 0;
  std::istringstream in(*text);
  int rows = -1;  // (the header)
  for (std::string line; std::getline(in, line);)
    if (!line.empty()) ++rows;
  return std::max(rows, 0);
}

/// What --dem-from offers for the plain-DEM run `part`: nothing (no run in `from`), the same run
/// (started as `part` would start it, ending where this comparison's runs end), or another.
enum class DemSource { None, Same, Other };

DemSource dem_source_run(const RunOptions& part, const std::string& text, int run_to_frame,
                         const std::string& from) {
  std::error_code ec;
  if (!fs::exists(fs::path(from) / "run.json", ec)) return DemSource::None;
  RunOptions probe = part;
  probe.out = from;
  try {
    const int ran_to = check_resumable(probe, text, true);
    return ran_to > 0 && ran_to != run_to_frame ? DemSource::Other : DemSource::Same;
  } catch (const InputError&) {
    return DemSource::Other;
  }
}

/// Copies the run in `from` into `to` (not yet a run), so that run_part reads it back (or goes on
/// with it) instead of making it again. Copied whole into a folder beside `to`, then renamed: a
/// copy cut short is never taken for a run (render/ stays behind: its pictures are not needed).
void copy_dem_run(const std::string& from, const std::string& to) {
  const FolderLock in_use(from, {"run", "wait for it to end or stop it before its run is taken"});
  std::error_code ec;
  const fs::path partial(to + ".copying");
  fs::remove_all(partial, ec);
  fs::remove_all(to, ec);
  fs::create_directories(partial, ec);
  for (const auto& e : fs::directory_iterator(from, ec)) {
    if (e.path().filename() == "render") continue;
    fs::copy(e.path(), partial / e.path().filename(), fs::copy_options::recursive, ec);
    if (ec) break;
  }
  if (!ec) fs::rename(partial, to, ec);
  if (ec) {
    std::error_code rm;
    fs::remove_all(partial, rm);
    throw OutputError(
        fmt::format("--dem-from: cannot copy {} into {}: {}", from, to, ec.message()));
  }
  // its record continues it where it is now
  nlohmann::json record;
  std::string recorded_text;
  read_run_record(to, record, recorded_text);
  record["resume_with"] = resume_command(to);
  write_file_atomic((fs::path(to) / "run.json").string(), record.dump(2) + "\n");
  print_to_stderr("{}: plain DEM taken from {} (its wall time as measured there)\n", to, from);
}

/// Takes the plain-DEM run `part` from the --dem-from folder `from` when it holds the same run and
/// part.out holds none yet; true when taken. `other` says why a run there that differs is not.
bool take_dem_run(const RunOptions& part, const std::string& text, const CompareOptions& co,
                  const std::string& from, const char* other) {
  std::error_code ec;
  if (co.dem_from.empty() || fs::exists(fs::path(part.out) / "run.json", ec)) return false;
  switch (dem_source_run(part, text, co.run_to_frame, from)) {
    case DemSource::Same:
      copy_dem_run(from, part.out);
      return true;
    case DemSource::None:
      print_to_stderr("{}: --dem-from has no run in {}: made here\n", part.out, from);
      return false;
    case DemSource::Other:
      print_to_stderr("{}: the run in {} {}: made here\n", part.out, from, other);
      return false;
  }
  return false;
}

/// Mean RMS distance of the surfaces of each pair (a[i], b[j]) from `pairs`, on `grid`.
double mean_distance(const HeightFieldParams& grid, const std::vector<MeasuredSurface>& a,
                     const std::vector<MeasuredSurface>& b,
                     const std::vector<std::pair<std::size_t, std::size_t>>& pairs) {
  std::vector<double> d;
  for (const auto& [i, j] : pairs)
    // (two runs with no sand on the grid have no distance, not a distance of 0)
    if (const SurfaceDistance s = surface_distance(grid, a[i], b[j]); s.samples > 0)
      d.push_back(s.rms);
  return mean(d);  // NaN (null in compare.json) when no pair had sand
}

}  // namespace

std::string compare_run_dir(const std::string& out, const std::string& mode, std::size_t index,
                            std::int64_t seed) {
  if (mode == kEqualStiffnessDir) return (fs::path(out) / kEqualStiffnessDir).string();
  return (index == 0 ? fs::path(out) / mode : fs::path(out) / fmt::format("seed-{}", seed) / mode)
      .string();
}

int compare_scene(const RunOptions& o, const CompareOptions& co, const std::string& out,
                  bool force, bool resume, const std::string* scene_text,
                  const std::string& resume_with, const std::string& label, Comparison& c) {
  if (co.seeds < 1 || co.seeds > kMaxSeeds)
    throw InputError(fmt::format("--seeds {}: expected 1 to {}", co.seeds, kMaxSeeds));
  const auto lock = prepare_compare_dir(out, force, resume);
  write_plan(out, co);
  const std::string text = scene_text ? *scene_text : read_scene_file(o.scene);
  const std::int64_t seed0 = load_for_run(o).simulation.seed;

  // each seed's run, in `mode`, with its seed set (the first has the scene's own)
  auto seed_part = [&](int k, const char* mode) {
    RunOptions part = o;
    if (k > 0) part.sets.push_back(fmt::format("simulation.seed={}", seed0 + k));
    part.mode = mode;
    part.out = compare_run_dir(out, mode, k, seed0 + k);
    return part;
  };
  // a --dem-from run of a seed started otherwise (another scene, --set, --grains, ...) is
  // refused before any run is made: the comparison asked for is not the one those runs made
  for (int k = 0; k < co.seeds && !co.dem_from.empty(); ++k) {
    const RunOptions part = seed_part(k, "dem");
    const std::string from = compare_run_dir(co.dem_from, "dem", k, seed0 + k);
    std::error_code ec;
    if (!fs::exists(fs::path(part.out) / "run.json", ec) &&
        dem_source_run(part, text, co.run_to_frame, from) == DemSource::Other)
      throw InputError(fmt::format(
          "--dem-from: {} holds a plain-DEM run started otherwise than this comparison's {} "
          "would be (another scene text, --set, --grains, --frames, --export or --up-axis, or run "
          "on to another frame): it cannot stand for it; compare without --dem-from, or with the "
          "options that run was made with",
          from, part.out));
  }

  // each seed in both modes, surface flow first
  c.seeds.clear();
  c.surface.assign(co.seeds, {});
  c.dem.assign(co.seeds, {});
  SceneConfig surface_scene;
  for (int k = 0; k < co.seeds; ++k) {
    const std::int64_t seed = seed0 + k;
    c.seeds.push_back(seed);
    const std::string tag = co.seeds > 1 ? fmt::format("{}seed {} of {}: ", label, k + 1, co.seeds)
                                         : label;
    SceneConfig scene;
    for (const char* mode : {"surface", "dem"}) {
      const RunOptions part = seed_part(k, mode);
      RunResult& res = part.mode == "surface" ? c.surface[k] : c.dem[k];
      const bool taken = part.mode == "dem" &&
                         take_dem_run(part, text, co, compare_run_dir(co.dem_from, mode, k, seed),
                                      "was started otherwise");
      if (const int stopped =
              run_part(part, resume || taken, &text, resume_with, tag, res, scene, co.run_to_frame))
        return stopped;
      if (k == 0 && part.mode == "surface") surface_scene = scene;
    }
  }
  c.scene = surface_scene;
  const SceneConfig& scene = c.scene;

  // plain DEM at the surface run's stiffness and time step: what the method gains by simulating
  // fewer grains alone, apart from the softer springs its thin loaded layer allows
  const double k_surf = c.surface[0].summary["k_n"].get<double>();
  const double dt_surf = c.surface[0].summary["dt_mean"].get<double>();
  c.dem_equal_stiffness.reset();
  if (co.equal_stiffness) {
    RunOptions part = o;
    part.mode = "dem";
    part.out = compare_run_dir(out, kEqualStiffnessDir, 0, seed0);
    for (const std::string& set :
         {std::string("stiffness.from_load=false"), fmt::format("material.k_n={:.17g}", k_surf),
          fmt::format("simulation.dt={:.17g}", dt_surf)})
      part.sets.push_back(set);
    RunResult res;
    SceneConfig s;
    const bool taken =
        take_dem_run(part, text, co, compare_run_dir(co.dem_from, kEqualStiffnessDir, 0, seed0),
                     "ran at another k_n or dt than this surface run's");
    if (const int stopped = run_part(part, resume || taken, &text, resume_with,
                                     label + "equal stiffness: ", res, s, co.run_to_frame))
      return stopped;
    c.dem_equal_stiffness = std::move(res);
  }

  // the final surfaces, all on the first surface run's grid, from every grain
  const Geometry geometry = Geometry::from_config(scene.geometry, scene.material);
  const SurfaceParams sp = surface_params(surface_scene, geometry, dt_surf);
  const TerrainColumns L = terrain_columns(sp, geometry);
  std::vector<MeasuredSurface> s_dem, s_surf;
  for (const RunResult& r : c.dem) s_dem.push_back(measure_surface(sp.grid, L, r.x, r.r));
  for (const RunResult& r : c.surface) s_surf.push_back(measure_surface(sp.grid, L, r.x, r.r));
  std::vector<std::pair<std::size_t, std::size_t>> dem_pairs, cross_pairs;
  for (std::size_t i = 0; i < s_dem.size(); ++i)
    for (std::size_t j = i + 1; j < s_dem.size(); ++j) dem_pairs.emplace_back(i, j);
  for (std::size_t i = 0; i < s_surf.size(); ++i)
    for (std::size_t j = 0; j < s_dem.size(); ++j) cross_pairs.emplace_back(i, j);
  const double rms = mean_distance(sp.grid, s_surf, s_dem, cross_pairs);
  const double rms_noise = mean_distance(sp.grid, s_dem, s_dem, dem_pairs);
  // a height of the scene, not of one run: the cone that holds all its grains at theta0
  const double reference = largest_heap(scene).height;
  const double d = scene.material.diameter;
  // the column-by-column difference of the first pair, as before (one heap's height as the scale)
  const SurfaceDiff columns = compare_surfaces(s_dem[0], s_surf[0]);

  // a scene with a bed (an impact) makes a crater, not a heap: its depth and rim are measured in
  // each run (analysis/crater.hpp), and no angle of repose
  // (from the bed's top as packed for each seed: its grains stop short of its height)
  const CraterSite site = crater_site(scene);
  std::vector<CraterFit> crater_dem, crater_surf;
  std::vector<double> z_ref;
  if (site.bed) {
    for (std::size_t k = 0; k < c.seeds.size(); ++k) {
      z_ref.push_back(
          packed_bed_level(scene, geometry, site, static_cast<std::uint64_t>(c.seeds[k])));
      crater_dem.push_back(measure_crater(site, z_ref[k], c.dem[k].x, c.dem[k].r));
      crater_surf.push_back(measure_crater(site, z_ref[k], c.surface[k].x, c.surface[k].r));
    }
  }
  const std::vector<double> a_dem = site.bed ? std::vector<double>{} : angles(c.dem);
  const std::vector<double> a_surf = site.bed ? std::vector<double>{} : angles(c.surface);
  const double a_dem_mean = mean(a_dem), a_surf_mean = mean(a_surf);
  const double spread =
      a_dem.empty() ? std::nan("")
                    : *std::max_element(a_dem.begin(), a_dem.end()) -
                          *std::min_element(a_dem.begin(), a_dem.end());
  double wall_dem = 0, wall_surf = 0, frac_mean = 0, frac_half = 0, frac_final = 0;
  double sim_mean = 0, sim_final = 0, over_surf = 0, over_dem = 0, e_woken = 0, e_trapped = 0;
  double e_inside = 0;
  const std::size_t n_frames = c.surface[0].frames.size();
  for (const RunResult& r : c.surface) {
    const FrameStats& last = r.frames.back();
    wall_surf += r.wall_seconds / co.seeds;
    frac_mean += simulated_fraction(r.frames, 0) / co.seeds;
    frac_half += simulated_fraction(r.frames, r.frames.size() / 2) / co.seeds;
    frac_final += simulated_fraction(r.frames, r.frames.size() - 1) / co.seeds;
    sim_mean += r.summary["n_simulated_mean"].get<double>() / co.seeds;
    sim_final += static_cast<double>(last.n_active + last.n_interface) / co.seeds;
    over_surf = std::max(over_surf, max_overlap(r));
    for (const FrameStats& f : r.frames) {
      e_woken += f.energy_woken / co.seeds;
      e_trapped += f.energy_trapped / co.seeds;
      e_inside += f.energy_inside / co.seeds;
    }
  }
  for (const RunResult& r : c.dem) {
    wall_dem += r.wall_seconds / co.seeds;
    over_dem = std::max(over_dem, max_overlap(r));
  }
  // each seed's own speed-up: its two runs ran one after the other, so their range shows how far
  // the machine's speed moved between seeds (as well as the seeds' own differences)
  std::vector<double> speedups;
  for (std::size_t k = 0; k < c.dem.size(); ++k)
    speedups.push_back(c.dem[k].wall_seconds / std::max(c.surface[k].wall_seconds, 1e-12));
  const RunResult& surf = c.surface[0];
  const RunResult& dem = c.dem[0];
  const double k_dem = dem.summary["k_n"].get<double>();
  nlohmann::json runs = nlohmann::json::array();
  auto add_run = [&](const RunResult& r, const std::string& mode, std::int64_t seed,
                     const std::string& dir, const CraterFit* crater) {
    runs.push_back(
        {{"mode", mode},
         {"seed", seed},
         {"folder", fs::relative(dir, out).string()},
         {"wall_seconds", r.wall_seconds},
         {"repose_angle_deg",
          r.heap.ok && !site.bed ? nlohmann::json(r.heap.repose_angle_deg) : nlohmann::json()},
         {"max_overlap_rel", max_overlap(r)},
         {"simulated_fraction_last_half", simulated_fraction(r.frames, r.frames.size() / 2)},
         {"k_n", r.summary["k_n"]},
         {"dt", r.summary["dt_mean"]},
         {"state_hash", r.summary["state_hash"]}});
    if (crater) runs.back()["crater"] = crater_json(*crater);
  };
  for (std::size_t k = 0; k < c.seeds.size(); ++k) {
    add_run(c.surface[k], "surface", c.seeds[k], compare_run_dir(out, "surface", k, c.seeds[k]),
            site.bed ? &crater_surf[k] : nullptr);
    add_run(c.dem[k], "dem", c.seeds[k], compare_run_dir(out, "dem", k, c.seeds[k]),
            site.bed ? &crater_dem[k] : nullptr);
  }
  c.json = {
      {"scene", scene.name},
      {"scene_file", scene.path},
      {"frames", n_frames},
      {"n_total", surf.frames.back().n_total},
      {"seeds", co.seeds},
      {"seed_values", c.seeds},
      {"dem_from", co.dem_from.empty() ? nlohmann::json() : nlohmann::json(co.dem_from)},
      {"speedup", wall_dem / std::max(wall_surf, 1e-12)},
      {"speedup_per_seed", speedups},
      {"speedup_min", *std::min_element(speedups.begin(), speedups.end())},
      {"speedup_max", *std::max_element(speedups.begin(), speedups.end())},
      {"simulated_fraction_mean", frac_mean},
      {"simulated_fraction_last_half", frac_half},
      {"simulated_fraction_final", frac_final},
      {"n_simulated_mean", sim_mean},
      {"n_simulated_final", sim_final},
      {"n_simulated_mean_dem", dem.summary["n_simulated_mean"]},
      {"seconds_per_frame_dem", wall_dem / n_frames},
      {"seconds_per_frame_surface", wall_surf / n_frames},
      {"wall_seconds_dem", wall_dem},
      {"wall_seconds_surface", wall_surf},
      {"dt_dem", dem.summary["dt_mean"]},
      {"dt_surface", dt_surf},
      {"k_n_dem", k_dem},
      {"k_n_surface", k_surf},
      {"same_stiffness", k_dem == k_surf},
      {"repose_angle_dem_deg", number_or_null(a_dem_mean)},
      {"repose_angle_surface_deg", number_or_null(a_surf_mean)},
      {"repose_angle_dem_spread_deg", number_or_null(spread)},
      {"repose_angle_diff_deg", number_or_null(std::abs(a_surf_mean - a_dem_mean))},
      {"repose_angle_fits", {{"dem", a_dem.size()}, {"surface", a_surf.size()}}},
      {"reference_height", reference},
      {"surface_rms", number_or_null(rms)},
      {"surface_rms_rel", number_or_null(rms / reference)},
      {"surface_rms_d", number_or_null(rms / d)},
      {"surface_rms_dem_vs_dem", number_or_null(rms_noise)},
      {"surface_rms_dem_vs_dem_rel", number_or_null(rms_noise / reference)},
      {"surface_rms_dem_vs_dem_d", number_or_null(rms_noise / d)},
      {"surface_columns_rms", columns.rms},
      {"heap_height_dem", columns.heap_height},
      {"max_overlap_surface_rel", over_surf},
      {"max_overlap_dem_rel", over_dem},
      {"impact_overlap", scene.stiffness.impact_overlap},
      {"energy_added_by_waking_j", e_woken},
      {"energy_removed_by_trapping_j", e_trapped},
      {"energy_opened_inside_active_j", e_inside},
      {"grains_inside_geometry_dem", dem.summary["grains_inside_geometry"]},
      {"grains_inside_geometry_surface", surf.summary["grains_inside_geometry"]},
      {"threads", thread_count(scene)},
      {"runs", runs},
  };
  if (site.bed) {
    // the crater's depth and rim: the means of the fits that worked in each mode, the plain-DEM
    // seeds' spread (largest minus smallest) and whether the modes differ by no more than it
    c.json["repose_angle_skipped"] = kNoHeapInABed;
    c.json["crater_bed_height"] = site.height;
    c.json["crater_z_ref"] = z_ref;  // per seed
    c.json["crater_centre"] =
        std::isnan(site.cx) ? nlohmann::json() : nlohmann::json::array({site.cx, site.cy});
    c.json["crater_centre_from"] = site.centre_from;
    c.json["crater_fits"] = {{"dem", crater_values(crater_dem, &CraterFit::depth).size()},
                             {"surface", crater_values(crater_surf, &CraterFit::depth).size()}};
    for (const auto& [name, what] :
         {std::pair{std::string("crater_depth"), &CraterFit::depth},
          std::pair{std::string("rim_height"), &CraterFit::rim_height}}) {
      const std::vector<double> dem_v = crater_values(crater_dem, what);
      const std::vector<double> surf_v = crater_values(crater_surf, what);
      const double diff = std::abs(mean(surf_v) - mean(dem_v)), dem_spread = spread_of(dem_v);
      c.json[name + "_dem"] = number_or_null(mean(dem_v));
      c.json[name + "_surface"] = number_or_null(mean(surf_v));
      c.json[name + "_dem_spread"] = number_or_null(dem_spread);
      c.json[name + "_diff"] = number_or_null(diff);
      c.json[name + "_within_spread"] = std::isfinite(diff) && std::isfinite(dem_spread)
                                            ? nlohmann::json(diff <= dem_spread)
                                            : nlohmann::json();
    }
  }
  if (const auto& eq = c.dem_equal_stiffness) {
    c.json["speedup_equal_stiffness"] = eq->wall_seconds / std::max(wall_surf, 1e-12);
    c.json["repose_angle_dem_equal_stiffness_deg"] =
        eq->heap.ok && !site.bed ? nlohmann::json(eq->heap.repose_angle_deg) : nlohmann::json();
    c.json["max_overlap_dem_equal_stiffness_rel"] = max_overlap(*eq);
    c.json["wall_seconds_dem_equal_stiffness"] = eq->wall_seconds;
    const CraterFit eq_crater =
        site.bed ? measure_crater(site, z_ref[0], eq->x, eq->r) : CraterFit{};
    add_run(*eq, "dem-equal-stiffness", seed0, compare_run_dir(out, kEqualStiffnessDir, 0, seed0),
            site.bed ? &eq_crater : nullptr);
    c.json["runs"] = runs;
  }
  write_file_atomic((fs::path(out) / "compare.json").string(), c.json.dump(2) + "\n");
  // the page of both runs (and each run's own), without pictures: `sandflow report` adds them
  write_report({out, 6, false});
  return 0;
}

namespace {
/// The folder --dem-from names, checked and made absolute (the plan records it): a comparison
/// with a plain-DEM run in it, not within the one about to be made (--force would remove its runs,
/// seed-S/ included).
std::string dem_source(const std::string& from, const std::string& out) {
  std::error_code ec;
  if (!fs::exists(fs::path(from) / "dem" / "run.json", ec))
    throw InputError(fmt::format(
        "--dem-from {}: not a comparison folder with a plain-DEM run (no dem/run.json)", from));
  const fs::path a = fs::weakly_canonical(from, ec), b = fs::weakly_canonical(out, ec);
  if (std::mismatch(b.begin(), b.end(), a.begin(), a.end()).first == b.end())
    throw InputError(fmt::format(
        "--dem-from {}: within the comparison's own output folder {}; give the new comparison "
        "another --out",
        from, out));
  return fs::absolute(from, ec).lexically_normal().string();
}
}  // namespace

std::string compare_resume_command(const std::string& dir) {
  return "sandflow compare --resume " + shell_quote(dir);
}

int compare_command(const RunOptions& o, const CompareOptions& given) {
  Comparison c;
  std::string out, text;
  CompareOptions co = given;
  if (!o.resume.empty()) {
    // the options of the comparison are those its surface run and its plan recorded
    if (!o.scene.empty() || o.grains > 0 || !o.sets.empty() || !o.out.empty() || o.force ||
        o.exports || !o.up_axis.empty() || !given.dem_from.empty())
      throw InputError(
          "compare --resume DIR goes on with the comparison in DIR as it was started: it takes no "
          "scene, --grains, --set, --export, --up-axis, --out, --force or --dem-from; only "
          "--threads, "
          "--frames N to run all its runs on to frame N, --seeds K to add seeds up to K and "
          "--equal-stiffness to add that run");
    out = o.resume;
    std::error_code ec;
    if (!fs::exists(fs::path(out) / "surface" / "run.json", ec))
      throw InputError(fmt::format(
          "{}: no comparison to resume here (no surface/run.json); start one with: sandflow "
          "compare SCENE --out {}",
          out, shell_quote(out)));
    co = read_plan(out);
    // a comparison grows (more seeds, the equal-stiffness run); it never drops runs it has
    if (given.seeds_given && given.seeds < co.seeds)
      throw InputError(fmt::format(
          "{}: --seeds {} is fewer than the {} seeds this comparison has: a resumed comparison "
          "adds seeds, it does not drop them",
          out, given.seeds, co.seeds));
    const int added_from = given.seeds_given && given.seeds > co.seeds ? co.seeds + 1 : 0;
    const bool adds_equal_stiffness = given.equal_stiffness_given && !co.equal_stiffness;
    if (given.seeds_given) co.seeds = given.seeds;
    co.equal_stiffness = co.equal_stiffness || given.equal_stiffness_given;
    nlohmann::json record;
    RunOptions r = read_run_record((fs::path(out) / "surface").string(), record, text);
    r.mode.clear();
    if (o.threads > 0) r.threads = o.threads;
    r.checkpoint_every = -1;
    if (o.frames > 0) {
      // on, not back: checked before the plan records it, against the frames each run has
      // written (at or after its checkpoint)
      const std::int64_t seed0 = load_for_run(r).simulation.seed;
      std::vector<std::string> dirs{compare_run_dir(out, kEqualStiffnessDir, 0, seed0)};
      for (int k = 0; k < co.seeds; ++k)
        for (const char* mode : {"surface", "dem"})
          dirs.push_back(compare_run_dir(out, mode, static_cast<std::size_t>(k), seed0 + k));
      for (const std::string& dir : dirs)
        if (const int reached = frames_written(dir); o.frames < reached)
          throw InputError(fmt::format(
              "{}: --frames {} is before frame {}, which {} has reached: a comparison runs on to a "
              "later frame, not back",
              out, o.frames, reached, dir));
      co.run_to_frame = o.frames;
    }
    if (added_from > 0 || adds_equal_stiffness) {
      fs::remove(fs::path(out) / "compare.json", ec);  // (its figures are of fewer runs)
      if (added_from > 0)
        print_to_stderr("{}: adding seeds {} to {} to the comparison\n", out, added_from, co.seeds);
      if (adds_equal_stiffness)
        print_to_stderr("{}: adding plain DEM at the surface run's stiffness\n", out);
    }
    if (const int stopped = compare_scene(r, co, out, false, true, &text,
                                          compare_resume_command(out), "", c))
      return stopped;
  } else {
    if (o.scene.empty()) throw InputError("compare: give a scene file, or --resume DIR");
    text = read_scene_file(o.scene);
    const SceneConfig named = load_for_run(o);  // the scene's name, for the default folder
    out = o.out.empty() ? fmt::format("out/{}-compare", named.name) : o.out;
    if (!co.dem_from.empty()) co.dem_from = dem_source(co.dem_from, out);
    if (const int stopped = compare_scene(o, co, out, o.force, false, &text,
                                          compare_resume_command(out), "", c))
      return stopped;
  }
  const SceneConfig& scene = c.scene;
  const nlohmann::json& j = c.json;
  const std::size_t n_frames = c.surface[0].frames.size();
  const FrameStats& last = c.surface[0].frames.back();
  const double k_dem = j["k_n_dem"].get<double>(), k_surf = j["k_n_surface"].get<double>();

  auto num = [&](const char* key, const char* format, const char* unit = "") {
    return j[key].is_number() ? fmt::format(fmt::runtime(format), j[key].get<double>()) + unit
                              : std::string("n/a");
  };
  auto pct = [&](const char* key) {
    return j[key].is_number() ? fmt::format("{:.1f} %", 100 * j[key].get<double>())
                              : std::string("n/a");
  };
  const int seeds = co.seeds;
  fmt::print("\n{} ({}, {}, {}, {} per mode)\n", scene.name, counted(last.n_total, "grain"),
             counted(n_frames, "frame"), counted(thread_count(scene), "thread"),
             counted(seeds, "seed"));
  fmt::print("{:<34}{:>16}{:>16}\n", "", "plain DEM", "surface flow");
  fmt::print("{:<34}{:>16}{:>16}\n", "total grains", c.dem[0].frames.back().n_total, last.n_total);
  fmt::print("{:<34}{:>16.0f}{:>16.0f}\n", "simulated grains, mean",
             j["n_simulated_mean_dem"].get<double>(), j["n_simulated_mean"].get<double>());
  fmt::print("{:<34}{:>16}{:>15.1f}%\n", "simulated fraction, mean", "100%",
             100 * j["simulated_fraction_mean"].get<double>());
  fmt::print("{:<34}{:>16}{:>15.1f}%\n", "simulated fraction, last half", "100%",
             100 * j["simulated_fraction_last_half"].get<double>());
  fmt::print("{:<34}{:>16.3f}{:>16.3f}\n", "seconds per frame", j["seconds_per_frame_dem"].get<double>(),
             j["seconds_per_frame_surface"].get<double>());
  fmt::print("{:<34}{:>16.3g}{:>16.3g}\n", "k_n [N/m]", k_dem, k_surf);
  fmt::print("{:<34}{:>16.3g}{:>16.3g}\n", "dt [s]", j["dt_dem"].get<double>(),
             j["dt_surface"].get<double>());
  const bool crater = j.contains("crater_bed_height");
  if (crater) {
    fmt::print("{:<34}{:>16}{:>16}\n", seeds > 1 ? "crater depth, mean" : "crater depth",
               num("crater_depth_dem", "{:.4f}", " m"),
               num("crater_depth_surface", "{:.4f}", " m"));
    fmt::print("{:<34}{:>16}{:>16}\n", seeds > 1 ? "rim height, mean" : "rim height",
               num("rim_height_dem", "{:.4f}", " m"), num("rim_height_surface", "{:.4f}", " m"));
  } else {
    fmt::print("{:<34}{:>16}{:>16}\n", seeds > 1 ? "repose angle, mean" : "repose angle",
               num("repose_angle_dem_deg", "{:.1f}", " deg"),
               num("repose_angle_surface_deg", "{:.1f}", " deg"));
  }
  fmt::print("{:<34}{:>16}{:>16}\n", "largest overlap (of a diameter)",
             pct("max_overlap_dem_rel"), pct("max_overlap_surface_rel"));
  fmt::print(
      "speed-up {:.2f}x ({}{})\n", j["speedup"].get<double>(),
      k_dem == k_surf ? "the same stiffness in both modes" : "each mode at its own stiffness",
      seeds > 1 ? fmt::format("; {:.2f}x to {:.2f}x by seed", j["speedup_min"].get<double>(),
                              j["speedup_max"].get<double>())
                : "");
  if (j["dem_from"].is_string())
    fmt::print("plain DEM's runs taken from {}: the speed-ups pair wall times measured then\n",
               j["dem_from"].get<std::string>());
  if (j.contains("speedup_equal_stiffness"))
    fmt::print("speed-up at equal stiffness {:.2f}x (plain DEM at k_n = {:.4g} N/m, dt = {:.3g} s: "
               "{}, largest overlap {})\n",
               j["speedup_equal_stiffness"].get<double>(), k_surf, j["dt_surface"].get<double>(),
               num("repose_angle_dem_equal_stiffness_deg", "{:.1f}", " deg"),
               pct("max_overlap_dem_equal_stiffness_rel"));
  if (crater) {
    // each run's crater, or why it has none, then the two modes against the plain-DEM seeds
    fmt::print("angle of repose  {}\n", j["repose_angle_skipped"].get<std::string>());
    std::vector<double> levels;
    for (const auto& z : j["crater_z_ref"])
      if (z.is_number()) levels.push_back(z.get<double>());
    fmt::print(
        "crater           in the bed of height {:.4f} m, from its top as packed (z = {:.4f} m, "
        "mean over the seeds); centre {}\n",
        j["crater_bed_height"].get<double>(), mean(levels),
        j["crater_centre"].is_array()
            ? fmt::format("({:.3f}, {:.3f}) m, {}", j["crater_centre"][0].get<double>(),
                          j["crater_centre"][1].get<double>(),
                          j["crater_centre_from"].get<std::string>())
            : j["crater_centre_from"].get<std::string>());
    fmt::print("  {:<8}{:<16}{:>12}{:>14}\n", "seed", "mode", "depth", "rim height");
    for (const auto& run : j["runs"]) {
      const std::string mode = run["mode"].get<std::string>();
      if (mode != "dem" && mode != "surface") continue;
      const auto& f = run["crater"];
      const std::string what =
          f["ok"].get<bool>()
              ? fmt::format("{:>12}{:>14}", fmt::format("{:.4f} m", f["depth"].get<double>()),
                            fmt::format("{:.4f} m", f["rim_height"].get<double>()))
              : "  " + f["reason"].get<std::string>();
      fmt::print("  {:<8}{:<16}{}\n", run["seed"].get<std::int64_t>(),
                 mode == "dem" ? "plain DEM" : "surface flow", what);
    }
    const auto& fits = j["crater_fits"];
    for (const auto& [name, what] :
         {std::pair{"crater_depth", "crater depth"}, std::pair{"rim_height", "rim height"}}) {
      const std::string key = name;
      const std::string spread = num((key + "_dem_spread").c_str(), "{:.4f}", " m");
      const auto& within = j[key + "_within_spread"];
      if (j[key + "_diff"].is_number())
        fmt::print("{} differs by {} between the means (plain DEM's seeds spread over {}){}\n",
                   what, num((key + "_diff").c_str(), "{:.4f}", " m"), spread,
                   within.is_boolean()
                       ? (within.get<bool>() ? ": within the spread" : ": outside the spread")
                       : "");
      else
        fmt::print(
            "{}: no difference to give, a crater was measured in {} of {} plain-DEM runs "
            "and {} of {} surface-flow runs (plain DEM's seeds spread over {})\n",
            what, fits["dem"].get<int>(), seeds, fits["surface"].get<int>(), seeds, spread);
    }
  } else {
    fmt::print("angles differ by {} (plain DEM's seeds spread over {})\n",
               num("repose_angle_diff_deg", "{:.1f}", " deg"),
               num("repose_angle_dem_spread_deg", "{:.1f}", " deg"));
  }
  fmt::print("surfaces {} apart = {} grain diameters = {} of the scene's height {:.3f} m "
             "(plain DEM's seeds: {} = {} d)\n",
             num("surface_rms", "{:.4f}", " m"), num("surface_rms_d", "{:.2f}"),
             pct("surface_rms_rel"), j["reference_height"].get<double>(),
             num("surface_rms_dem_vs_dem", "{:.4f}", " m"), num("surface_rms_dem_vs_dem_d", "{:.2f}"));
  fmt::print("output           {}/ (compare.json, dem/, surface/{})\n", out,
             seeds > 1 ? ", seed-S/" : "");
  fmt::print("report           {} (plots; `sandflow report {}` adds pictures)\n",
             (fs::path(out) / "report.html").string(), out);
  return 0;
}

}  // namespace sandflow
