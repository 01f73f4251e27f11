// The readers of a scene's tables (internal to src/scene/), one a table: each takes a TableReader
// of its table (table_reader.hpp), reads every key it accepts into the config struct, refuses the
// others and checks what one key cannot check alone (a domain's corners, max_angle against
// repose_angle). settings_tables.cpp has the tables a scene has once ([material], [simulation],
// [stiffness], [surface], [output], [camera]); geometry_table.cpp and emitter_table.cpp the
// entries of [[geometry]] and [[emitter]]; scene_loader.cpp reads the document with them.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>

#include "config/scene_config.hpp"
#include "scene/scene_loader.hpp"
#include "scene/table_reader.hpp"

namespace sandflow::loader {

/// The most grains a scene may make, in one emitter or in all: far above any scene we run, below
/// 2^31 (grain ids are 32-bit) and what `--grains` accepts.
inline constexpr std::int64_t kMaxGrains = 2'000'000'000;

void read_material(TableReader r, MaterialConfig& m);
void read_simulation(TableReader r, SimulationConfig& s);
void read_stiffness(TableReader r, StiffnessConfig& k);
/// Angles are written in degrees and stored in radians. `diameter` is the default cell size.
void read_surface(TableReader r, SurfaceConfig& s, Real diameter);
/// The finest `output.vdb_voxel_size`: this many voxels across the largest grain.
constexpr double kVdbGrainVoxelsMax = 200;
void read_output(TableReader r, OutputConfig& o, const MaterialConfig& m);
/// The render camera: a fixed one (position and look_at together, up optional) or only a field
/// of view for the automatic one.
void read_camera(TableReader r, CameraConfig& c);

/// Fails at `extent` unless it is a rectangle [x0, y0, x1, y1] with x1 > x0 and y1 > y0.
void check_extent(const TableReader& r, const std::array<Real, 4>& extent);

/// The entry geometry[index]; a heightmap's `file` is found beside `scene_path` and read by
/// `read_image`.
GeometryConfig read_geometry(TableReader r, std::size_t index, const std::string& scene_path,
                             const ImageReader& read_image);

/// The entry emitter[index], checked against the grains of `material`.
EmitterConfig read_emitter(TableReader r, std::size_t index, const MaterialConfig& material);

}  // namespace sandflow::loader
