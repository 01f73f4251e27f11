// Reading obstacle meshes: OBJ, PLY (ascii, binary little and big endian) and OFF, each possibly
// gzipped. The format is chosen by the file name (.obj, .ply, .off, with an optional .gz); gzip
// data is recognised by its magic bytes.
//
// Mesh files come from users and other programs, so the readers are strict about content and
// never trust a count: every malformed file raises InputError naming the file, the position
// (line for text, byte offset and element index for binary PLY) and what was expected. Counts a
// header announces are checked against the limits below and against the bytes the file holds
// before anything is allocated, so a corrupt or hostile file cannot exhaust memory.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

#include "geometry/mesh.hpp"

namespace sandflow {

/// Largest mesh accepted (about 0.5 GB of vertices and triangles).
inline constexpr std::size_t kMaxMeshVertices = 20'000'000;
inline constexpr std::size_t kMaxMeshTriangles = 20'000'000;
/// Largest file accepted, after decompression [bytes].
inline constexpr std::size_t kMaxMeshFileBytes = std::size_t{1} << 30;

enum class MeshFormat { Obj, Ply, Off };

/// Loads a mesh; polygons are fan-triangulated. Throws InputError when the file cannot be read,
/// is malformed, has no triangles or only degenerate ones.
TriangleMesh load_mesh(const std::string& path);

/// The format a file name asks for (".gz" ignored); InputError naming the file when unknown.
MeshFormat mesh_format_from_name(const std::string& path);

/// Parses mesh data already in memory (plain, not gzipped); `name` is used in error messages.
TriangleMesh parse_mesh(std::string_view data, MeshFormat format, const std::string& name);

/// A mesh file's bytes already in memory: gzip data (known by its magic bytes) is inflated and
/// the format is the one `name` asks for; the same checks and messages as load_mesh. The entry
/// point for fuzzing.
TriangleMesh decode_mesh(std::string bytes, const std::string& name);

}  // namespace sandflow
