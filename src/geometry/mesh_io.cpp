// Loading a mesh file: read the bytes (refusing oversized files), inflate gzip data, pick the
// reader by the file name, and refuse meshes a scene cannot use (empty, all degenerate).
#include "geometry/mesh_io.hpp"

#include <zlib.h>

#include <algorithm>
#include <cctype>
#include <cstring>
#include <filesystem>
#include <limits>

#include "core/read_file.hpp"
#include "geometry/mesh_io_detail.hpp"

namespace sandflow {

namespace {

using mesh_io::fail_file;
using mesh_io::lower_case;

bool is_gzip(const std::string& bytes) {
  return bytes.size() >= 2 && static_cast<unsigned char>(bytes[0]) == 0x1f &&
         static_cast<unsigned char>(bytes[1]) == 0x8b;
}

// Inflates gzip data (one or more members), refusing output larger than kMaxMeshFileBytes.
std::string gunzip(const std::string& in, const std::string& path) {
  z_stream zs{};
  if (inflateInit2(&zs, 16 + MAX_WBITS) != Z_OK) fail_file(path, "zlib could not start");
  // A single member's trailer holds its size mod 2^32 (ISIZE): start there when it is within the
  // limit, so that the text is not copied while it grows (a 1 GiB text peaked at 1.5 GiB).
  std::size_t first = std::max<std::size_t>(4 * in.size(), 1024);
  if (in.size() >= 18) {
    const auto* tail = reinterpret_cast<const unsigned char*>(in.data() + in.size() - 4);
    const std::size_t isize =
        tail[0] | (tail[1] << 8) | (tail[2] << 16) | (static_cast<std::size_t>(tail[3]) << 24);
    // (+1: a full buffer then means more is coming; deflate expands at most 1032 times, so a
    // trailer that lies cannot make a small file take much)
    first = std::max(first, std::min(isize + 1, 1032 * in.size()));
  }
  std::string out(std::min(first, kMaxMeshFileBytes), '\0');
  zs.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(in.data()));
  zs.avail_in = static_cast<uInt>(in.size());
  std::size_t produced = 0;
  int rc = Z_OK;
  while (true) {
    if (produced == out.size()) {
      if (out.size() >= kMaxMeshFileBytes) {
        inflateEnd(&zs);
        fail_file(path, "decompressed data exceeds the limit of " +
                            std::to_string(kMaxMeshFileBytes) + " bytes");
      }
      out.resize(std::min(2 * out.size(), kMaxMeshFileBytes));
    }
    zs.next_out = reinterpret_cast<Bytef*>(out.data() + produced);
    zs.avail_out = static_cast<uInt>(std::min<std::size_t>(out.size() - produced, UINT32_MAX));
    const uInt before = zs.avail_out;
    rc = inflate(&zs, Z_NO_FLUSH);
    produced += before - zs.avail_out;
    if (rc == Z_STREAM_END) {
      if (zs.avail_in == 0) break;
      inflateReset(&zs);  // another gzip member follows
      continue;
    }
    if (rc == Z_OK) continue;
    if (rc == Z_BUF_ERROR && zs.avail_out == 0) continue;  // the output buffer was full
    const std::size_t at = in.size() - zs.avail_in;
    const std::string reason =
        rc == Z_BUF_ERROR ? "ends early (truncated file)" : (zs.msg ? zs.msg : "is corrupt");
    inflateEnd(&zs);
    fail_file(path, "gzip data " + reason + " at compressed byte " + std::to_string(at));
  }
  inflateEnd(&zs);
  out.resize(produced);
  return out;
}

bool ends_with(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() &&
         s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

void check_usable(const TriangleMesh& mesh, const std::string& path) {
  if (mesh.vertices.empty() || mesh.triangles.empty())
    fail_file(path, "empty mesh: " + std::to_string(mesh.vertices.size()) + " vertices, " +
                        std::to_string(mesh.triangles.size()) +
                        " triangles (expected at least one triangle)");
  for (std::size_t i = 0; i < mesh.triangles.size(); ++i)
    if (!is_degenerate(mesh, i)) return;
  fail_file(path, "every one of the " + std::to_string(mesh.triangles.size()) +
                      " triangles is degenerate (zero area or a repeated vertex)");
}

}  // namespace

MeshFormat mesh_format_from_name(const std::string& path) {
  std::string name = lower_case(std::filesystem::path(path).filename().string());
  if (ends_with(name, ".gz")) name.resize(name.size() - 3);
  if (ends_with(name, ".obj")) return MeshFormat::Obj;
  if (ends_with(name, ".ply")) return MeshFormat::Ply;
  if (ends_with(name, ".off")) return MeshFormat::Off;
  if (ends_with(name, ".stl")) return MeshFormat::Stl;
  if (ends_with(name, ".gltf") || ends_with(name, ".glb")) return MeshFormat::Gltf;
  // (docs/meshes.md, "Which reader reads which format")
  if (ends_with(name, ".fbx") || ends_with(name, ".dae"))
    fail_file(path, std::string(ends_with(name, ".fbx") ? "FBX" : "COLLADA") +
                        " files are not read: assimp 5.2, which would read them, crashes on some "
                        "malformed ones; export the mesh as glTF (.glb), STL or PLY");
  fail_file(path,
            "unknown mesh format: expected a name ending in .obj, .ply, .off, .stl, .gltf or .glb "
            "(optionally + .gz)");
}

TriangleMesh parse_mesh(std::string_view data, MeshFormat format, const std::string& name) {
  TriangleMesh mesh;
  switch (format) {
    case MeshFormat::Obj:
      mesh = mesh_io::read_obj(data, name);
      break;
    case MeshFormat::Ply:
      mesh = mesh_io::read_ply(data, name);
      break;
    case MeshFormat::Off:
      mesh = mesh_io::read_off(data, name);
      break;
    case MeshFormat::Stl:
    case MeshFormat::Gltf:
      mesh = mesh_io::read_with_assimp(data, format, name);
      break;
  }
  check_usable(mesh, name);
  return mesh;
}

TriangleMesh decode_mesh(std::string bytes, const std::string& name) {
  const MeshFormat format = mesh_format_from_name(name);
  if (is_gzip(bytes))
    bytes = gunzip(bytes, name);
  else if (ends_with(lower_case(name), ".gz"))
    fail_file(name, "expected gzip data (the name ends in .gz)");
  return parse_mesh(bytes, format, name);
}

TriangleMesh load_mesh(const std::string& path) {
  mesh_format_from_name(path);  // an unknown format is refused before the file is read
  return decode_mesh(read_whole_file(path, "mesh file", kMaxMeshFileBytes), path);
}

}  // namespace sandflow
