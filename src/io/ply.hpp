// Frames as PLY point clouds: one vertex per visible grain.
//
// Written as binary_little_endian PLY 1.0 with the vertex properties
//   float x, y, z, radius, vx, vy, vz; uint id; uchar state
// (33 bytes a grain), which ParaView and Houdini read as they are (Blender's own PLY importer keeps
// only the positions: tools/blender/sandflow_blender.py reads the rest). The file is written
// to `path + ".tmp"` and renamed over `path`, so a reader never sees half a frame. A header line
// `comment up_axis z` (or `y`) says which way is up: with y, positions and velocities are written
// rotated, (x, y, z) -> (x, z, -y) (export_formats.hpp), and read_ply rotates them back, so that
// `sandflow measure` and `render` see the scene's frame whichever way a run wrote its frames.
//
// The reader is lenient about layout and strict about content: it accepts binary_little_endian
// or ascii files, any property order, any numeric property types and extra properties or
// elements, but requires x, y, z and radius, and checks every count against the bytes the file
// actually holds before allocating, so a corrupt or hostile file raises InputError instead of
// crashing. Missing optional properties default to: velocity 0, id = vertex index, state 0.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

#include "config/scene_config.hpp"
#include "dem/frame.hpp"

namespace sandflow {

/// Writes `f` to `path` atomically. Throws OutputError naming the path and the system's reason.
/// The velocity, id and state arrays may be empty (written as 0, the index, 0); otherwise every
/// array must have f.size() entries (std::invalid_argument if not: a bug in the caller).
void write_ply(const std::string& path, const FrameData& f, UpAxis up = UpAxis::Z);

/// The most grains a frame may hold: as many as a scene may have (ids are 32-bit).
inline constexpr std::uint64_t kMaxFrameGrains = 2'000'000'000;

/// Reads a PLY point cloud written by write_ply (or any PLY described above) from a regular
/// file, in the scene's frame (z up: a y-up file is turned back). Throws InputError naming the file, the place ("header line N", then "line N" in ascii
/// data or "byte N" in binary data) and what is wrong.
FrameData read_ply(const std::string& path);

/// Parses PLY data already in memory, `name` standing for the file in messages; the same checks
/// and messages as read_ply. The entry point for fuzzing.
FrameData parse_frame_ply(std::string_view bytes, const std::string& name);

}  // namespace sandflow
