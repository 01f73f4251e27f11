// Wavefront OBJ: 'v' and 'f' statements; everything else a mesh obstacle does not need (texture
// coordinates, normals, groups, materials, lines) is skipped, and an unknown statement is an
// error, so binary garbage named .obj is refused instead of read as an empty mesh.
//
// Why not libtinyobjloader-dev: it reads a malformed number as 0 without a word ("v 1 abc 2"
// gives (1, 0, 2)), accepts NaN coordinates, and its messages do not reliably name the line, so
// the errors this project promises (file:line: what was expected) would be impossible. The
// subset of OBJ a mesh obstacle needs is small enough to read here.
#include <array>
#include <cstdint>
#include <vector>

#include "geometry/mesh_io.hpp"
#include "geometry/mesh_io_detail.hpp"

namespace sandflow::mesh_io {

namespace {

bool is_skipped_statement(std::string_view s) {
  static constexpr std::string_view kSkipped[] = {
      "vt",   "vn",     "vp",     "l",          "p",         "g",        "o",
      "s",    "usemtl", "mtllib", "cstype",     "deg",       "bmat",     "step",
      "curv", "curv2",  "surf",   "parm",       "trim",      "hole",     "scrv",
      "sp",   "end",    "con",    "mg",         "bevel",     "c_interp", "d_interp",
      "lod",  "maplib", "usemap", "shadow_obj", "trace_obj", "ctech",    "stech"};
  for (std::string_view k : kSkipped)
    if (s == k) return true;
  return false;
}

class ObjReader {
 public:
  ObjReader(std::string_view data, const std::string& file) : cursor_(data), file_(file) {}

  TriangleMesh read() {
    std::string_view line;
    while (cursor_.next(line)) read_statement(strip_comment(line));
    return std::move(mesh_);
  }

 private:
  void read_statement(std::string_view line) {
    Tokens tokens(line);
    std::string_view keyword;
    if (!tokens.next(keyword)) return;
    if (keyword == "v") return read_vertex(tokens);
    if (keyword == "f") return read_face(tokens);
    if (!is_skipped_statement(keyword))
      fail("unknown statement '" + std::string(keyword.substr(0, 40)) +
           "' (expected v, f, vt, vn, g, o, ...)");
  }

  // v x y z [w] or v x y z r g b: the first three numbers are the position
  void read_vertex(Tokens& tokens) {
    std::array<Real, 3> xyz{};
    for (Real& c : xyz) {
      std::string_view t;
      if (!tokens.next(t)) fail("'v' needs three coordinates x y z");
      c = coordinate_at_line(t, file_, cursor_.line_number());
    }
    if (mesh_.vertices.size() >= kMaxMeshVertices)
      fail("more than the limit of " + std::to_string(kMaxMeshVertices) + " vertices");
    mesh_.vertices.push_back({xyz[0], xyz[1], xyz[2]});
  }

  // f i j k ...: each corner is i, i/t, i//n or i/t/n; negative i counts back from the last vertex
  void read_face(Tokens& tokens) {
    polygon_.clear();
    std::string_view t;
    while (tokens.next(t)) polygon_.push_back(vertex_index(t));
    if (polygon_.size() < 3)
      fail("a face needs at least 3 vertices, found " + std::to_string(polygon_.size()));
    if (mesh_.triangles.size() + polygon_.size() - 2 > kMaxMeshTriangles)
      fail("more than the limit of " + std::to_string(kMaxMeshTriangles) + " triangles");
    add_fan(mesh_, polygon_.data(), polygon_.size());
  }

  std::uint32_t vertex_index(std::string_view corner) {
    const std::string_view index = corner.substr(0, corner.find('/'));
    std::int64_t i = 0;
    if (!parse_int(index, i) || i == 0)
      fail("expected a non-zero vertex index, found '" + std::string(corner.substr(0, 40)) + "'");
    // vertices must precede the faces that use them (as every exporter writes them)
    const auto n = static_cast<std::int64_t>(mesh_.vertices.size());
    const std::int64_t zero_based = i > 0 ? i - 1 : n + i;
    if (zero_based < 0 || zero_based >= n)
      fail("vertex index " + std::to_string(i) + " is out of range: " + std::to_string(n) +
           " vertices defined so far");
    return static_cast<std::uint32_t>(zero_based);
  }

  [[noreturn]] void fail(const std::string& what) const {
    fail_line(file_, cursor_.line_number(), what);
  }

  LineCursor cursor_;
  const std::string& file_;
  TriangleMesh mesh_;
  std::vector<std::uint32_t> polygon_;
};

}  // namespace

TriangleMesh read_obj(std::string_view data, const std::string& file) {
  return ObjReader(data, file).read();
}

}  // namespace sandflow::mesh_io
