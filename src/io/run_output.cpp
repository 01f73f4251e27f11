#include "io/run_output.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>

#include <fmt/format.h>

#include "core/error.hpp"

namespace sandflow {

namespace fs = std::filesystem;

void prepare_output_dir(const std::string& dir, bool force) {
  std::error_code ec;
  if (fs::exists(dir, ec) && !fs::is_directory(dir, ec))
    throw InputError(fmt::format("{}: the output path exists and is not a folder", dir));
  if (fs::exists(dir, ec) && !fs::is_empty(dir, ec)) {
    if (!force)
      throw InputError(fmt::format(
          "{}: the output folder is not empty; pass --force to replace its run", dir));
    for (const char* name : {"frames", "stats.csv", "summary.json", "final_grains.ply", "render",
                             "report.html", "frames.pvd", "heightfield"})
      fs::remove_all(fs::path(dir) / name, ec);
  }
  fs::create_directories(fs::path(dir) / "frames", ec);
  if (ec) throw OutputError(fmt::format("{}: cannot create the output folder: {}", dir, ec.message()));
}

void write_file_atomic(const std::string& path, const std::string& text) {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    out << text;
    out.close();
    if (!out) {
      const std::string reason = std::strerror(errno);
      std::remove(tmp.c_str());  // no half-written file left behind
      throw OutputError(fmt::format("{}: cannot write: {}", tmp, reason));
    }
  }
  std::error_code ec;
  fs::rename(tmp, path, ec);
  if (ec) {
    const std::string reason = ec.message();
    fs::remove(tmp, ec);
    throw OutputError(fmt::format("{}: cannot write: {}", path, reason));
  }
}

std::string frame_path(const std::string& dir, int frame) {
  return (fs::path(dir) / "frames" / fmt::format("{:04d}.ply", frame)).string();
}

StatsWriter::StatsWriter(const std::string& path) : path_(path) {
  f_ = std::fopen(path.c_str(), "w");
  if (!f_) throw OutputError(fmt::format("{}: cannot write: {}", path, std::strerror(errno)));
  std::fputs(
      "frame,time,substeps,dt,n_total,n_active,n_interface,n_static,contacts,wall_contacts,"
      "max_overlap_rel,kinetic_energy,rebuilds,trapped,dislodged,slept,woken,surface_updates,"
      "wall_seconds\n",
      f_);
}

StatsWriter::~StatsWriter() {
  if (f_) std::fclose(f_);
}

void StatsWriter::write(const FrameStats& s) {
  const std::string row = fmt::format(
      "{},{:.6f},{},{:.6e},{},{},{},{},{},{},{:.6e},{:.6e},{},{},{},{},{},{},{:.4f}\n", s.frame, s.time,
      s.substeps, s.dt, s.n_total, s.n_active, s.n_interface, s.n_static, s.contacts,
      s.wall_contacts, s.max_overlap_rel, s.kinetic_energy, s.rebuilds, s.transitions.trapped,
      s.transitions.dislodged, s.transitions.slept, s.transitions.woken, s.surface_updates,
      s.wall_seconds);
  if (std::fputs(row.c_str(), f_) < 0 || std::fflush(f_) != 0)
    throw OutputError(fmt::format("{}: cannot write: {}", path_, std::strerror(errno)));
}

}  // namespace sandflow
