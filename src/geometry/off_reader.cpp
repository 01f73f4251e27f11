// Object File Format (Geomview OFF): a header keyword ([ST][C][N]OFF), the counts
// "vertices faces edges" (on the keyword's line or the next), one vertex per line (x y z, then
// colours or normals, ignored) and one face per line ("n i1 ... in", then an optional colour).
// '#' starts a comment; blank lines are skipped. Binary OFF and 4-D or n-D variants are refused.
#include <cstdint>
#include <vector>

#include "geometry/mesh_io.hpp"
#include "geometry/mesh_io_detail.hpp"

namespace sandflow::mesh_io {

namespace {

class OffReader {
 public:
  OffReader(std::string_view data, const std::string& file) : cursor_(data), file_(file) {}

  TriangleMesh read() {
    read_header();
    mesh_.vertices.reserve(vertex_count_);
    mesh_.triangles.reserve(face_count_);
    for (std::uint64_t i = 0; i < vertex_count_; ++i) read_vertex(next_line("vertex", i));
    for (std::uint64_t i = 0; i < face_count_; ++i) read_face(next_line("face", i));
    return std::move(mesh_);
  }

 private:
  // The next line with something on it; a truncated file is reported with what was expected.
  Tokens next_line(const char* what, std::uint64_t index) {
    std::string_view line;
    while (cursor_.next(line)) {
      Tokens tokens(strip_comment(line));
      if (!tokens.empty()) return tokens;
    }
    fail_line(file_, cursor_.line_number() + 1,
              "unexpected end of file: expected " + std::string(what) + " " +
                  std::to_string(index) + " (file truncated?)");
  }

  void read_header() {
    Tokens tokens = next_line("the 'OFF' header", 0);
    std::string_view keyword;
    tokens.next(keyword);
    check_keyword(keyword);
    std::string_view t;
    if (Tokens peek = tokens; peek.next(t) && t == "BINARY")
      fail("binary OFF is not supported (expected ascii OFF)");
    if (tokens.empty()) tokens = next_line("the counts 'vertices faces edges'", 0);
    std::uint64_t counts[2] = {0, 0};
    for (std::uint64_t& c : counts)
      if (!tokens.next(t) || !parse_count(t, c))
        fail("expected the counts 'vertices faces edges' as non-negative integers");
    vertex_count_ = counts[0];
    face_count_ = counts[1];
    // a vertex line is at least "0 0 0\n", a face line "3 0 1 2\n"
    const std::string where = file_ + ":" + std::to_string(cursor_.line_number()) + ": ";
    check_count(vertex_count_, kMaxMeshVertices, cursor_.bytes_left(), 6, "vertices", where);
    check_count(face_count_, kMaxMeshTriangles, cursor_.bytes_left(), 8, "faces", where);
  }

  void check_keyword(std::string_view keyword) {
    if (keyword.size() < 3 || keyword.substr(keyword.size() - 3) != "OFF")
      fail("expected the header keyword 'OFF' (or COFF, NOFF, STOFF, ...), found '" +
           std::string(keyword.substr(0, 40)) + "'");
    const std::string_view prefix = keyword.substr(0, keyword.size() - 3);
    if (prefix.find('4') != std::string_view::npos || prefix.find('n') != std::string_view::npos)
      fail("4-D and n-D OFF files are not supported (expected 3-D 'OFF')");
    if (prefix.find_first_not_of("STCN") != std::string_view::npos)
      fail("unknown OFF header keyword '" + std::string(keyword.substr(0, 40)) + "'");
  }

  void read_vertex(Tokens tokens) {
    Real xyz[3];
    for (Real& c : xyz) {
      std::string_view t;
      if (!tokens.next(t)) fail("a vertex line needs three coordinates x y z");
      c = coordinate_at_line(t, file_, cursor_.line_number());
    }
    mesh_.vertices.push_back({xyz[0], xyz[1], xyz[2]});
  }

  void read_face(Tokens tokens) {
    std::string_view t;
    std::uint64_t n = 0;
    if (!tokens.next(t) || !parse_count(t, n)) fail("expected a face: 'n i1 ... in'");
    if (n < 3) fail("a face needs at least 3 vertices, found " + std::to_string(n));
    polygon_.clear();
    for (std::uint64_t k = 0; k < n; ++k) {
      if (!tokens.next(t))
        fail("the face announces " + std::to_string(n) + " vertices but lists " +
             std::to_string(k));
      polygon_.push_back(vertex_index(t));
    }
    if (mesh_.triangles.size() + polygon_.size() - 2 > kMaxMeshTriangles)
      fail("more than the limit of " + std::to_string(kMaxMeshTriangles) + " triangles");
    add_fan(mesh_, polygon_.data(), polygon_.size());
  }

  std::uint32_t vertex_index(std::string_view token) {
    std::int64_t i = 0;
    if (!parse_int(token, i))
      fail("expected a vertex index, found '" + std::string(token.substr(0, 40)) + "'");
    if (i < 0 || static_cast<std::uint64_t>(i) >= vertex_count_)
      fail("vertex index " + std::to_string(i) + " is out of range [0, " +
           std::to_string(vertex_count_) + ")");
    return static_cast<std::uint32_t>(i);
  }

  [[noreturn]] void fail(const std::string& what) const {
    fail_line(file_, cursor_.line_number(), what);
  }

  LineCursor cursor_;
  const std::string& file_;
  std::uint64_t vertex_count_ = 0, face_count_ = 0;
  TriangleMesh mesh_;
  std::vector<std::uint32_t> polygon_;
};

}  // namespace

TriangleMesh read_off(std::string_view data, const std::string& file) {
  return OffReader(data, file).read();
}

}  // namespace sandflow::mesh_io
