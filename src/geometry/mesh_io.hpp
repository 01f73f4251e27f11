// Reading obstacle meshes: OBJ, PLY (ascii, binary little and big endian) and OFF by readers of
// our own; STL (ASCII and binary) and glTF 2.0 (.gltf, .glb) through assimp
// (assimp_mesh_reader.cpp says why each goes where, and why FBX and COLLADA are refused). Any of
// them may be gzipped. The format is chosen by the file name (with an optional .gz); gzip data is
// recognised by its magic bytes.
//
// Mesh files come from users and other programs, so the readers are strict about content and
// never trust a count: every malformed file raises InputError naming the file, the position
// where the format allows (line for text, byte offset and element index for binary PLY, facet
// for STL) and what was expected. Our readers check the counts a header announces against the
// limits below and against the bytes the file holds before anything is allocated, so a corrupt
// or hostile file cannot exhaust memory; assimp's are bounded by the file size limit.
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
/// Largest file read through assimp (STL, glTF), with the files it names, after decompression
/// [bytes]: assimp keeps each face in an allocation of its own and took 400-640 MB a million
/// triangles, 13 (binary STL) to 18 (GLB) times the file's size, where the readers of OBJ, PLY
/// and OFF take about 50 bytes a triangle.
inline constexpr std::size_t kMaxAssimpMeshBytes = std::size_t{64} << 20;

enum class MeshFormat { Obj, Ply, Off, Stl, Gltf };

/// Loads a mesh; polygons are triangulated. Throws InputError when the file cannot be read,
/// is malformed, has no triangles or only degenerate ones.
TriangleMesh load_mesh(const std::string& path);

/// The format a file name asks for (".gz" ignored); InputError naming the file when unknown, or
/// when it is FBX or COLLADA (saying why they are not read).
MeshFormat mesh_format_from_name(const std::string& path);

/// Parses mesh data already in memory (plain, not gzipped); `name` is used in error messages, and
/// files a glTF names are looked for beside it.
TriangleMesh parse_mesh(std::string_view data, MeshFormat format, const std::string& name);

/// A mesh file's bytes already in memory: gzip data (known by its magic bytes) is inflated and
/// the format is the one `name` asks for; the same checks and messages as load_mesh. The entry
/// point for fuzzing.
TriangleMesh decode_mesh(std::string bytes, const std::string& name);

}  // namespace sandflow
