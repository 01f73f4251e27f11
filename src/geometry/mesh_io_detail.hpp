// Shared pieces of the mesh readers (mesh_io.hpp): error messages that name the position,
// strict number parsing, a line cursor. Internal to src/geometry.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "core/error.hpp"
#include "geometry/mesh.hpp"
#include "geometry/mesh_io.hpp"

namespace sandflow::mesh_io {

/// "file:line: what"
[[noreturn]] void fail_line(const std::string& file, std::size_t line, const std::string& what);
/// "file: what"
[[noreturn]] void fail_file(const std::string& file, const std::string& what);

/// Parses the whole token as a finite-or-not real (leading '+' allowed); false if not a number.
bool parse_real(std::string_view token, Real& value);
/// Parses the whole token as a signed integer; false if not an integer or out of range.
bool parse_int(std::string_view token, std::int64_t& value);
/// Parses the whole token as an unsigned count; false if not one. Overflow gives UINT64_MAX.
bool parse_count(std::string_view token, std::uint64_t& value);

/// A coordinate token at a line: a finite number, else InputError saying which.
Real coordinate_at_line(std::string_view token, const std::string& file, std::size_t line);

/// Refuses a count above `limit` or above what `bytes_left` bytes can hold (`min_bytes` each),
/// before the caller allocates anything. `where` is the message prefix naming the position.
void check_count(std::uint64_t count, std::uint64_t limit, std::uint64_t bytes_left,
                 std::uint64_t min_bytes, const std::string& what, const std::string& where);

/// Lines of a text with their 1-based numbers; '\r' before '\n' is dropped.
class LineCursor {
 public:
  explicit LineCursor(std::string_view text) : text_(text) {}
  bool next(std::string_view& line);
  std::size_t line_number() const { return line_; }
  std::size_t bytes_left() const { return text_.size() - pos_; }
  std::size_t offset() const { return pos_; }

 private:
  std::string_view text_;
  std::size_t pos_ = 0, line_ = 0;
};

/// Whitespace-separated tokens of one line.
class Tokens {
 public:
  explicit Tokens(std::string_view line) : line_(line) {}
  bool next(std::string_view& token);
  bool empty();  ///< no token left

 private:
  std::string_view line_;
  std::size_t pos_ = 0;
};

/// The text in lower case (ASCII), for file names.
std::string lower_case(std::string s);

/// The line without a '#' comment.
std::string_view strip_comment(std::string_view line);

/// Appends the fan triangulation of a polygon (v0, v1, v2), (v0, v2, v3), ...
void add_fan(TriangleMesh& mesh, const std::uint32_t* polygon, std::size_t n);

TriangleMesh read_obj(std::string_view data, const std::string& file);
TriangleMesh read_ply(std::string_view data, const std::string& file);
TriangleMesh read_off(std::string_view data, const std::string& file);
/// STL and glTF (assimp_mesh_reader.cpp).
TriangleMesh read_with_assimp(std::string_view data, MeshFormat format, const std::string& file);

}  // namespace sandflow::mesh_io
