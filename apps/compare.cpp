// `sandflow compare`: a scene run in both modes and the two compared.
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "commands.hpp"
#include "core/error.hpp"
#include "io/run_output.hpp"
#include "surface/surface_params.hpp"

namespace fs = std::filesystem;

namespace sandflow {

namespace {

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
/// earlier comparison (compare.json, dem/, surface/) is removed, or `resume`, which keeps it;
/// OUT/dem and OUT/surface are made.
void prepare_compare_dir(const std::string& out, bool force, bool resume) {
  std::error_code ec;
  if (fs::exists(out, ec) && !fs::is_directory(out, ec))
    throw InputError(fmt::format("{}: the output path exists and is not a folder", out));
  if (fs::exists(out, ec) && !fs::is_empty(out, ec) && !resume) {
    if (!force)
      throw InputError(fmt::format(
          "{}: the output folder is not empty; pass --force to replace its comparison, or "
          "--resume to go on with it",
          out));
    for (const char* name : {"compare.json", "dem", "surface", "report.html"})
      fs::remove_all(fs::path(out) / name, ec);
  }
  for (const char* mode : {"surface", "dem"}) {
    const fs::path dir = fs::path(out) / mode;
    if (!fs::exists(dir / "run.json", ec)) prepare_output_dir(dir.string(), true);
  }
}

}  // namespace

int compare_scene(const RunOptions& o, const std::string& out, bool force, bool resume,
                  const std::string* scene_text, const std::string& resume_with,
                  const std::string& label, Comparison& c) {
  prepare_compare_dir(out, force, resume);
  const std::string text = scene_text ? *scene_text : read_scene_text(o.scene);
  RunOptions part = o;
  SceneConfig surface_scene, dem_scene;
  part.mode = "surface";
  part.out = (fs::path(out) / "surface").string();
  if (const int stopped =
          run_part(part, resume, &text, resume_with, label, c.surface, surface_scene))
    return stopped;
  part.mode = "dem";
  part.out = (fs::path(out) / "dem").string();
  if (const int stopped = run_part(part, resume, &text, resume_with, label, c.dem, dem_scene))
    return stopped;
  c.scene = surface_scene;
  const SceneConfig& scene = c.scene;
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
  // the page of both runs (and each run's own), without pictures: `sandflow report` adds them
  write_report({out, 6, false});
  return 0;
}

std::string compare_resume_command(const std::string& dir) {
  return "sandflow compare --resume " + shell_quote(dir);
}

int compare_command(const RunOptions& o) {
  Comparison c;
  std::string out, text;
  if (!o.resume.empty()) {
    // the options of the comparison are those its surface run recorded
    if (!o.scene.empty() || o.grains > 0 || o.frames > 0 || !o.sets.empty() || !o.out.empty() ||
        o.force || o.exports || !o.up_axis.empty())
      throw InputError(
          "compare --resume DIR goes on with the comparison in DIR exactly as it was started: it "
          "takes no scene, --grains, --frames, --set, --export, --up-axis, --out or --force; "
          "only --threads");
    out = o.resume;
    std::error_code ec;
    if (!fs::exists(fs::path(out) / "surface" / "run.json", ec))
      throw InputError(fmt::format(
          "{}: no comparison to resume here (no surface/run.json); start one with: sandflow "
          "compare SCENE --out {}",
          out, shell_quote(out)));
    nlohmann::json record;
    RunOptions r = read_run_record((fs::path(out) / "surface").string(), record, text);
    r.mode.clear();
    if (o.threads > 0) r.threads = o.threads;
    r.checkpoint_every = -1;
    if (const int stopped = compare_scene(r, out, false, true, &text, compare_resume_command(out),
                                          "", c))
      return stopped;
  } else {
    if (o.scene.empty()) throw InputError("compare: give a scene file, or --resume DIR");
    text = read_scene_text(o.scene);
    const SceneConfig named = load_for_run(o);  // the scene's name, for the default folder
    out = o.out.empty() ? fmt::format("out/{}-compare", named.name) : o.out;
    if (const int stopped =
            compare_scene(o, out, o.force, false, &text, compare_resume_command(out), "", c))
      return stopped;
  }
  const SceneConfig& scene = c.scene;
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
  fmt::print("report           {} (plots; `sandflow report {}` adds pictures)\n",
             (fs::path(out) / "report.html").string(), out);
  return 0;
}

}  // namespace sandflow
