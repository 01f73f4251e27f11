// The per-frame files of a run, as chosen by output.export / --export (docs/scenes.md "Exports").
// run_scene makes one FrameExporter when the run starts and calls write() after every frame.
//
// Grains: the visible ones (ACTIVE and INTERFACE; in surface mode the STATIC grains are the
// height field's) go to DIR/frames/NNNN.ply, .vtk and .vtp (listed with their times in
// DIR/frames.pvd, rewritten after every frame so that an interrupted run leaves a readable
// series), .csv and .pov, NNNN being the frame (at t = NNNN / fps), and to
// DIR/frames/sand.NNNN.geo and .geo.gz, numbered on Houdini's time line: NNNN - 1 frames, at
// t = (NNNN - 1) / fps, from sand.0001 (the state at the start, write_start) to one past the
// last frame (export_formats.hpp). The POV-Ray frames are small: camera, lights, textures and the
// geometry (a mesh can be megabytes) are written once to DIR/frames/pov_scene.inc, which every
// NNNN.pov includes. Its camera is fixed for the whole run, framing the geometry and where the
// grains can go (each emitter widened by the largest heap the scene can make), so that the frames
// make an animation; it is the view of `sandflow render`.
//
// Height fields (surface mode only): DIR/heightfield/H_NNNN.png and h_NNNN.png (16-bit), with
// DIR/heightfield/heightfield.json, written when the run starts, holding the z range of every
// frame's greys (height_export.hpp); H_NNNN.obj and h_NNNN.obj meshes for `height_obj`. The z
// range runs from the lowest solid top under the grid to the highest solid top or emitter plus the
// height of the largest heap the scene can make: no height of the run can leave it, so none is
// clamped (a clamped height would be counted in summary()).
//
// A DEM run has no height field: `height` and `height_obj` are dropped with a warning (so that
// `compare` can export them from its surface run), never an error.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "io/export_formats.hpp"
#include "io/height_export.hpp"
#include "io/pov_writer.hpp"
#include "sim/world.hpp"

namespace sandflow {

class FrameExporter {
 public:
  /// Prepares the exports of `world`'s scene in the run folder `dir` (DIR/frames exists): the
  /// heightfield folder and heightfield.json, the POV-Ray include. Throws OutputError.
  FrameExporter(const World& world, const std::string& dir);

  /// Writes the files of the state a run starts from (world.frame() is 0, at t = 0): the Houdini
  /// frame sand.0001 (the other exports have no frame 0). Call it once, before the first frame.
  void write_start(const World& world);
  /// Writes every chosen file of the frame just finished (world.frame(), at world.time()).
  void write(const World& world);

  /// A resumed run: frames.pvd goes on listing the frames written before the checkpoint.
  void continue_after(const std::vector<FrameStats>& done);
  /// The files the last write() made (a checkpoint flushes them to the disk first).
  const std::vector<std::string>& written() const { return written_; }

  /// What the user should know (height asked for in DEM mode).
  const std::vector<std::string>& warnings() const { return warnings_; }
  /// The formats written, after dropping those the mode cannot write.
  const std::vector<ExportFormat>& formats() const { return formats_; }
  /// For summary.json: formats, up axis, the height range and cells clamped.
  nlohmann::json summary() const;

 private:
  bool has(ExportFormat f) const { return has_export(formats_, f); }
  /// The chosen Houdini files of world.frame(), holding `f`.
  void write_houdini(const World& world, const FrameData& f);

  std::string dir_;
  std::vector<ExportFormat> formats_;
  UpAxis up_ = UpAxis::Z;
  std::vector<std::string> warnings_;
  std::vector<SeriesEntry> series_;  ///< frames.pvd
  std::vector<std::string> written_;
  HeightRange range_;
  std::int64_t clamped_ = 0;  ///< height values outside range_, over the run
};

/// The view of a whole run (see above): PovOptions with auto_camera false.
PovOptions fixed_pov_camera(const World& world);

/// The z range of a run's height images (see above). Surface mode only.
HeightRange run_height_range(const World& world);

}  // namespace sandflow
