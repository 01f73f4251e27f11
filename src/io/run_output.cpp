#include "io/run_output.hpp"

#include <cerrno>
#include <cstdio>
#include <filesystem>

#include <fmt/format.h>

#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "io/folder_lock.hpp"

namespace sandflow {

namespace fs = std::filesystem;

namespace {

/// Whether the folder `dir` holds anything but what a start stopped before its run.json leaves
/// (an empty frames/: a run interrupted while it calibrated, say; a half-written run.json.tmp:
/// one killed as it wrote it), which no --force need replace.
bool holds_something(const std::string& dir) {
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec))
    if (e.path().filename() != "run.json.tmp" &&
        (e.path().filename() != "frames" || !fs::is_directory(e.path(), ec) ||
         !fs::is_empty(e.path(), ec)))
      return true;
  return static_cast<bool>(ec);
}

/// Removes each of `paths`. Throws OutputError naming the first that cannot go.
void remove_each(const std::vector<fs::path>& paths) {
  std::error_code ec;
  for (const fs::path& p : paths) {
    fs::remove(p, ec);
    if (ec) throw OutputError(fmt::format("{}: cannot remove: {}", p.string(), ec.message()));
  }
}

}  // namespace

void prepare_output_dir(const std::string& dir, bool force) {
  std::error_code ec;
  if (fs::exists(dir, ec) && !fs::is_directory(dir, ec))
    throw InputError(fmt::format("{}: the output path exists and is not a folder", dir));
  if (fs::exists(dir, ec) && holds_something(dir)) {
    if (!force)
      throw InputError(fmt::format(
          "{}: the output folder is not empty; pass --force to replace its run (or --resume {} "
          "to continue it)",
          dir, dir));
    const auto renders = lock_render_folders(dir, 1);  // (held while the run's files go)
    for (const char* name : {"frames", "stats.csv", "summary.json", "final_grains.ply", "render",
                             "report.html", "frames.pvd", "heightfield", "checkpoint.bin",
                             "run.json"})
      fs::remove_all(fs::path(dir) / name, ec);
  }
  const bool existed = fs::is_directory(dir, ec);
  if (existed) remove_partial_files(dir);
  fs::create_directories(fs::path(dir) / "frames", ec);
  if (ec)
    throw OutputError(existed ? fmt::format("{}: cannot write into the output folder (creating "
                                            "{}/frames: {})",
                                            dir, dir, ec.message())
                              : fmt::format("{}: cannot create the output folder: {}", dir,
                                            ec.message()));
}

void remove_partial_files(const std::string& dir) {
  std::error_code ec;
  for (const fs::path& folder :
       {fs::path(dir), fs::path(dir) / "frames", fs::path(dir) / "heightfield"}) {
    std::vector<fs::path> stale;
    for (const auto& e : fs::directory_iterator(folder, ec))
      if (e.path().extension() == ".tmp") stale.push_back(e.path());
    remove_each(stale);
  }
}

void prepare_resumed_dir(const std::string& dir, int frame) {
  std::error_code ec;
  fs::create_directories(fs::path(dir) / "frames", ec);
  if (ec) throw OutputError(fmt::format("{}: cannot create {}/frames: {}", dir, dir, ec.message()));
  remove_partial_files(dir);
  // NNNN.ply after the checkpoint's frame
  std::vector<fs::path> stale;
  for (const auto& e : fs::directory_iterator(fs::path(dir) / "frames", ec)) {
    const fs::path& p = e.path();
    const std::string stem = p.stem().string();
    if (p.extension() == ".ply" && !stem.empty() &&
        stem.find_first_not_of("0123456789") == std::string::npos && stem.size() < 10 &&
        std::stoi(stem) > frame)
      stale.push_back(p);
  }
  remove_each(stale);
}

std::string frame_path(const std::string& dir, int frame) {
  return (fs::path(dir) / "frames" / fmt::format("{:04d}.ply", frame)).string();
}

std::string stats_header() {
  return "frame,time,substeps,dt,n_total,n_active,n_interface,n_static,contacts,wall_contacts,"
         "max_overlap_rel,kinetic_energy,rebuilds,trapped,dislodged,slept,woken,surface_updates,"
         "left_domain,woken_by_reach,energy_trapped,energy_woken,energy_preloaded,energy_inside,wall_seconds\n";
}

std::string stats_row(const FrameStats& s) {
  return fmt::format(
      "{},{:.6f},{},{:.6e},{},{},{},{},{},{},{:.6e},{:.6e},{},{},{},{},{},{},{},{},{:.6e},{:.6e},"
      "{:.6e},{:.6e},{:.4f}\n",
      s.frame, s.time, s.substeps, s.dt, s.n_total, s.n_active, s.n_interface, s.n_static,
      s.contacts, s.wall_contacts, s.max_overlap_rel, s.kinetic_energy, s.rebuilds,
      s.transitions.trapped, s.transitions.dislodged, s.transitions.slept, s.transitions.woken,
      s.surface_updates, s.left_domain, s.transitions.woken_by_reach, s.energy_trapped,
      s.energy_woken, s.energy_preloaded, s.energy_inside, s.wall_seconds);
}

StatsWriter::StatsWriter(const std::string& path, const std::vector<FrameStats>& rows)
    : path_(path) {
  std::string text = stats_header();
  for (const FrameStats& s : rows) text += stats_row(s);
  write_file_atomic(path, text);
  f_ = std::fopen(path.c_str(), "a");
  if (!f_) throw OutputError(fmt::format("{}: cannot write: {}", path, system_reason(errno)));
}

StatsWriter::~StatsWriter() {
  if (f_) std::fclose(f_);
}

void StatsWriter::write(const FrameStats& s) {
  const std::string row = stats_row(s);
  if (std::fputs(row.c_str(), f_) < 0 || std::fflush(f_) != 0)
    throw OutputError(fmt::format("{}: cannot write: {}", path_, system_reason(errno)));
}

}  // namespace sandflow
