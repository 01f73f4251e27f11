// `sandflow table1`: the paper's scenes, each compared as `sandflow compare` does, tabulated.
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "commands.hpp"
#include "console.hpp"
#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "core/threads.hpp"
#include "io/folder_lock.hpp"
#include "scene/scene_loader.hpp"
#include "table1.hpp"

namespace fs = std::filesystem;

namespace sandflow {

namespace {

/// Where table1 finds scenes/<name>.toml: --scene-dir when given, else ./scenes when the current
/// folder has one (as `run` and `compare` take paths from the current folder), else the scenes/
/// of the source tree this binary was built from.
std::string table1_scene_dir(const std::string& given) {
  std::error_code ec;
  if (!given.empty()) {
    if (const std::string problem = folder_problem(given); !problem.empty())
      throw InputError(fmt::format("--scene-dir {}: {}", given, problem));
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

std::string local_date_time() {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  localtime_r(&now, &tm);
  char buf[64];
  return std::strftime(buf, sizeof buf, "%Y-%m-%d %H:%M %Z", &tm) ? buf : "unknown date";
}

/// The runs of scene `p` as this table1 command makes them (mode unset; compare_scene sets it).
RunOptions table1_run(const Table1Options& o, const PaperScene& p, const fs::path& file) {
  RunOptions ro;
  ro.scene = file.string();
  ro.grains = scaled_count(p, o.scale);
  ro.frames = o.frames;
  ro.threads = o.threads;
  return ro;
}

/// --resume: every run the folder already holds must be the one this command would start, so
/// that other options are refused before anything is written.
void check_table1_resumable(const Table1Options& o, const std::vector<const PaperScene*>& scenes,
                            const std::string& scene_dir) {
  std::error_code ec;
  for (const PaperScene* p : scenes) {
    const fs::path file = fs::path(scene_dir) / (std::string(p->name) + ".toml");
    if (!fs::exists(file, ec)) continue;
    RunOptions ro = table1_run(o, *p, file);
    const std::string text = read_scene_file(ro.scene);
    const std::int64_t seed0 = load_for_run(ro).simulation.seed;
    for (int k = 0; k < o.seeds; ++k) {
      RunOptions part = ro;
      if (k > 0) part.sets.push_back(fmt::format("simulation.seed={}", seed0 + k));
      for (const char* mode : {"surface", "dem"}) {
        part.mode = mode;
        part.out = compare_run_dir((fs::path(o.out) / p->name).string(), mode, k, seed0 + k);
        check_resumable(part, text);
      }
    }
  }
}

/// The command that goes on with this table: the one typed, without --force, with --resume.
std::string table1_resume_command(const std::string& command, bool resumed) {
  std::string c = " " + command + " ";
  for (std::size_t at; (at = c.find(" --force ")) != std::string::npos;) c.erase(at, 8);
  c = c.substr(1, c.size() - 2);
  return resumed ? c : c + " --resume";
}

/// The row of a scene that ran, from its comparison.
Table1Row table1_row(const std::string& name, std::int64_t total, const Comparison& c) {
  Table1Row r;
  r.scene = name;
  r.status = RowStatus::Done;
  r.total = total;
  r.emitted = c.surface[0].frames.back().n_total;
  r.surface_simulated_mean = c.json["n_simulated_mean"].get<double>();
  r.surface_s_per_frame = c.json["seconds_per_frame_surface"].get<double>();
  r.dem_simulated_mean = c.dem[0].summary["n_simulated_mean"].get<double>();
  r.dem_s_per_frame = c.json["seconds_per_frame_dem"].get<double>();
  r.speedup = c.json["speedup"].get<double>();
  r.surface_rms_rel = c.json["surface_rms_rel"].is_number()
                          ? c.json["surface_rms_rel"].get<double>()
                          : std::nan("");  // no sand in either
  r.max_overlap_surface = c.json["max_overlap_surface_rel"].get<double>();
  r.impact_overlap = c.json["impact_overlap"].get<double>();
  r.energy_woken = c.json["energy_added_by_waking_j"].get<double>();
  for (const RunResult& run : c.dem)
    r.inside_dem += run.summary["grains_inside_geometry"].get<std::int64_t>();
  for (const RunResult& run : c.surface)
    r.inside_surface += run.summary["grains_inside_geometry"].get<std::int64_t>();
  return r;
}

}  // namespace

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
  if (o.force && o.resume)
    throw InputError("table1: --force replaces what the output folder holds, --resume goes on with "
                     "it: give one of them");
  const FolderLock lock(o.out);  // held until the table is done; refuses a path that is no folder
  std::error_code ec;
  if (fs::exists(o.out, ec) && !fs::is_empty(o.out, ec) && !o.resume) {
    if (!o.force)
      throw InputError(fmt::format(
          "{}: the output folder is not empty; pass --force to replace its table, or --resume "
          "(with the same options) to go on with it",
          o.out));
    for (const char* name : {"table1.csv", "table1.md"}) fs::remove(fs::path(o.out) / name, ec);
  }
  if (o.resume) check_table1_resumable(o, scenes, scene_dir);
  fs::create_directories(o.out, ec);
  if (ec)
    throw OutputError(fmt::format("{}: cannot create the output folder: {}", o.out, ec.message()));

  std::vector<Table1Row> rows(scenes.size());
  for (std::size_t k = 0; k < scenes.size(); ++k) rows[k].scene = std::string(scenes[k]->name);
  Table1Context ctx{command,
                    local_date_time(),
                    omp_get_num_procs(),
                    o.threads > 0 ? o.threads : default_thread_count(),
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
      print_to_stderr("table1: {}{} skipped: {}\n", label, p.name, row.message);
      write_table();
      continue;
    }
    const std::int64_t total = scaled_count(p, o.scale);
    auto fail = [&](const std::exception& e, int code) {
      row.status = RowStatus::Failed;
      row.message = e.what();
      if (status == 0) status = code;
      print_to_stderr("\ntable1: {}{} failed: {}\n", label, p.name, row.message);
    };
    try {
      const RunOptions ro = table1_run(o, p, file);
      const SceneConfig full = load_scene(ro.scene);
      if (full.total_grains() != p.total)
        print_to_stderr(
            "warning: {} has {} grains, the paper's {} {}; table1 scales the paper's "
            "count\n",
            ro.scene, full.total_grains(), p.title, p.total);
      const SceneConfig scene = load_for_run(ro);
      if (scene.total_grains() != total)
        throw InputError(
            fmt::format("{}: cannot scale its emitters to {} grains", ro.scene, total));
      ctx.threads = thread_count(scene);
      print_to_stderr("table1: {}{}, {} grains ({} x {}), surface flow then plain DEM -> {}\n",
                      label, p.name, total, o.scale, p.total, (fs::path(o.out) / p.name).string());
      Comparison c;
      const std::string resume_with = table1_resume_command(command, o.resume);
      CompareOptions co;
      co.seeds = o.seeds;
      if (const int stopped = compare_scene(ro, co, (fs::path(o.out) / p.name).string(), o.force,
                                            o.resume, nullptr, resume_with, label, c)) {
        row.status = RowStatus::Failed;
        row.message = "interrupted; resume with: " + resume_with;
        write_table();
        return stopped;
      }
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
    print_to_stderr("error: no scene ran: none of the scene files was found in {}\n", scene_dir);
    return 2;
  }
  return 0;
}

}  // namespace sandflow
