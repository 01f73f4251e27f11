// The grain formats of `--export` besides PLY (ply.hpp) and POV-Ray (pov_writer.hpp): one frame
// of visible grains as legacy VTK, VTK XML PolyData, Houdini classic .geo (plain or gzipped) and
// CSV, and the ParaView series (.pvd) that lists a run's frames with their times. No Debian
// package writes these for us; each is a page of the format's documentation, written here by
// hand (gzip by zlib).
//
// Every file is written whole to `path + ".tmp"` and renamed over `path` (write_file_atomic), so a
// reader never sees half a frame; a failure throws OutputError naming the path.
//
// Houdini's frames are numbered on Houdini's time line, not as the other exports: Houdini puts
// frame 1 at t = 0 ($T = ($F - 1) / $FPS), so sand.0001.geo holds the state the run starts from
// and sand.NNNN.geo the state at t = (NNNN - 1) / fps, the state of the other exports' frame
// NNNN - 1. A File SOP on sand.$F4.geo then shows at each frame the grains of that moment.
//
// The grains are spheres and the simulation tracks their spin (angular velocity), not how far
// they have turned (src/dem/grains.hpp): there is no orientation to export. `orient` is the
// identity for every grain, in the exported frame, so a shape copied onto the points stands as it
// was modelled. A random turn per grain drawn from its id was tried: the gzipped frames grew from
// 37 to 57 bytes a grain for a number the simulation does not know; docs/houdini.md gives each
// grain one in Houdini instead, from its id, the same in every frame.
//
// The up axis. The scene is right-handed with z up. With UpAxis::Y every position and velocity is
// written rotated by -90 degrees about x, (x, y, z) -> (x, z, -y): the scene's z becomes y and the
// frame stays right-handed (what Houdini, Maya, Blender's glTF and Unity-side tools expect).
//
// Why both .vtk and .vtp: the issue asks for legacy VTK, which every VTK-based tool reads, but
// ParaView's .pvd series can list only VTK XML files (its reader builds an XML reader from each
// file's extension). So `vtk` writes each frame twice, NNNN.vtk and NNNN.vtp, with the same
// arrays, and frames.pvd lists the .vtp files.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "config/scene_config.hpp"
#include "core/vec3.hpp"
#include "dem/frame.hpp"

namespace sandflow {

// ---- Choosing exports ----

/// "ply", "vtk", "geo", "geo_gz", "pov", "csv", "height", "height_obj", "vdb": the names of scene
/// files and --export.
std::string_view export_name(ExportFormat f);
/// The format of a name, or nullopt.
std::optional<ExportFormat> export_format(std::string_view name);
/// Every name, comma-separated, for messages.
std::string export_names();
/// `--export LIST`: comma-separated names (repeats allowed), or "none" alone for no per-frame
/// files. Throws InputError starting with `where` and listing the known names.
std::vector<ExportFormat> parse_export_list(const std::string& list, const std::string& where);
/// The exports of a run: the scene's choice, else the default: ply, and height in surface mode.
/// A DEM run has no height field: height and height_obj are left out and listed in `dropped`.
std::vector<ExportFormat> run_exports(const OutputConfig& o, Mode mode,
                                      std::vector<ExportFormat>* dropped = nullptr);
/// The warning for exports dropped by run_exports, naming the scene file.
std::string dropped_exports_warning(const std::string& scene_path,
                                    const std::vector<ExportFormat>& dropped);
bool has_export(const std::vector<ExportFormat>& list, ExportFormat f);

std::string_view up_axis_name(UpAxis up);
/// A scene vector in the exported frame: (x, y, z) as it is, or (x, z, -y) for y up.
constexpr Vec3 to_up_axis(const Vec3& v, UpAxis up) {
  return up == UpAxis::Y ? Vec3{v.x, v.z, -v.y} : v;
}
/// The inverse of to_up_axis.
constexpr Vec3 from_up_axis(const Vec3& v, UpAxis up) {
  return up == UpAxis::Y ? Vec3{v.x, -v.z, v.y} : v;
}

// ---- Writers ----
// Each writes the grains of `f` (velocity, id and state may be empty: 0, the index, 0), as float32
// (positions to a tenth of a micrometre on a metre-sized scene, as in the PLY frames).

/// Legacy VTK 3.0, binary (big-endian, as the format requires), POLYDATA: the points, one vertex
/// cell each (so that ParaView draws them), and the point arrays radius (float), velocity (float
/// x 3), state (unsigned_char) and id (unsigned_int). `title` is the header's second line.
void write_vtk_legacy(const std::string& path, const FrameData& f, UpAxis up,
                      const std::string& title);

/// VTK XML PolyData (.vtp) with the same points, vertex cells and arrays, raw little-endian
/// appended data with UInt64 block headers.
void write_vtp(const std::string& path, const FrameData& f, UpAxis up);

/// One dataset of a ParaView series: its file, relative to the .pvd's folder, and its time [s].
struct SeriesEntry {
  double time = 0;
  std::string file;
};
/// A ParaView collection (.pvd) listing `entries` in order.
void write_pvd(const std::string& path, const std::vector<SeriesEntry>& entries);

/// The name of the Houdini file holding the state after `frame` frames (0: the start), on
/// Houdini's time line (see above): "sand.0001.geo" for frame 0, with ".gz" when `gzip`.
std::string houdini_frame_name(int frame, bool gzip);

/// Houdini classic ASCII geometry (PGEOMETRY V5): one point per grain with P (its position) and
/// the point attributes Cd (its colour, linear RGB: sand_colour.hpp), v (vector), pscale (the
/// radius, float), orient (the identity: see above), id and state (int), held by one
/// particle-system primitive (Part), as Houdini writes particles. No primitive when f is empty.
/// A path ending in ".gz" is written as gzip data, which Houdini reads as it is.
void write_houdini_geo(const std::string& path, const FrameData& f, UpAxis up);

/// CSV with the header `id,x,y,z,radius,vx,vy,vz,state`, one row per grain.
void write_grains_csv(const std::string& path, const FrameData& f, UpAxis up);

}  // namespace sandflow
