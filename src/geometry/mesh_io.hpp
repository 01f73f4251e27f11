// Reading obstacle meshes: OBJ, PLY (ascii, binary little and big endian) and OFF by readers of
// our own; STL (ASCII and binary), glTF 2.0 (.gltf, .glb), FBX and COLLADA (.dae) through assimp
// (assimp_mesh_reader.cpp says why each goes where). Any of them may be gzipped. The format is
// chosen by the file name (with an optional .gz); gzip data is recognised by its magic bytes.
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
#include <vector>

#include "geometry/mesh.hpp"

namespace sandflow {

/// Largest mesh accepted (about 0.5 GB of vertices and triangles).
inline constexpr std::size_t kMaxMeshVertices = 20'000'000;
inline constexpr std::size_t kMaxMeshTriangles = 20'000'000;
/// Largest file accepted, after decompression [bytes].
inline constexpr std::size_t kMaxMeshFileBytes = std::size_t{1} << 30;
/// Largest file read through assimp (STL, glTF, FBX, COLLADA), after decompression [bytes]:
/// assimp keeps each face in an allocation of its own and took 400-640 MB a million triangles,
/// 13 (binary STL) to 23 (COLLADA) times the file's size, where the readers of OBJ, PLY and OFF
/// take about 50 bytes a triangle.
inline constexpr std::size_t kMaxAssimpMeshBytes = std::size_t{64} << 20;

enum class MeshFormat { Obj, Ply, Off, Stl, Gltf, Fbx, Dae };

/// Loads a mesh; polygons are triangulated. Throws InputError when the file cannot be read,
/// is malformed, has no triangles or only degenerate ones. What assimp logged as an error without
/// refusing the file (glTF, FBX, COLLADA) is appended to `warnings`, one line each, when given.
TriangleMesh load_mesh(const std::string& path, std::vector<std::string>* warnings = nullptr);

/// The format a file name asks for (".gz" ignored); InputError naming the file when unknown.
MeshFormat mesh_format_from_name(const std::string& path);

/// Parses mesh data already in memory (plain, not gzipped); `name` is used in error messages, and
/// files a glTF names are looked for beside it.
TriangleMesh parse_mesh(std::string_view data, MeshFormat format, const std::string& name,
                        std::vector<std::string>* warnings = nullptr);

/// A mesh file's bytes already in memory: gzip data (known by its magic bytes) is inflated and
/// the format is the one `name` asks for; the same checks and messages as load_mesh. The entry
/// point for fuzzing.
TriangleMesh decode_mesh(std::string bytes, const std::string& name,
                         std::vector<std::string>* warnings = nullptr);

}  // namespace sandflow
