#include "geometry/mesh_io_detail.hpp"

#include <cctype>
#include <charconv>
#include <cmath>
#include <limits>
#include <system_error>

namespace sandflow::mesh_io {

void fail_line(const std::string& file, std::size_t line, const std::string& what) {
  throw InputError(file + ":" + std::to_string(line) + ": " + what);
}

void fail_file(const std::string& file, const std::string& what) {
  throw InputError(file + ": " + what);
}

bool parse_real(std::string_view token, Real& value) {
  if (!token.empty() && token[0] == '+') token.remove_prefix(1);
  const char* end = token.data() + token.size();
  const auto [ptr, ec] = std::from_chars(token.data(), end, value);
  if (ec == std::errc::result_out_of_range) {
    value = std::numeric_limits<Real>::infinity();  // reported as non-finite by the caller
    return ptr == end;
  }
  return ec == std::errc() && ptr == end && !token.empty();
}

bool parse_int(std::string_view token, std::int64_t& value) {
  if (!token.empty() && token[0] == '+') token.remove_prefix(1);
  const char* end = token.data() + token.size();
  const auto [ptr, ec] = std::from_chars(token.data(), end, value);
  return ec == std::errc() && ptr == end && !token.empty();
}

bool parse_count(std::string_view token, std::uint64_t& value) {
  const char* end = token.data() + token.size();
  const auto [ptr, ec] = std::from_chars(token.data(), end, value);
  if (ec == std::errc::result_out_of_range && ptr == end) {
    value = std::numeric_limits<std::uint64_t>::max();
    return true;
  }
  return ec == std::errc() && ptr == end && !token.empty();
}

Real coordinate_at_line(std::string_view token, const std::string& file, std::size_t line) {
  Real v = 0;
  if (!parse_real(token, v))
    fail_line(file, line, "expected a number, found '" + std::string(token.substr(0, 40)) + "'");
  if (!std::isfinite(v))
    fail_line(file, line, "coordinate '" + std::string(token.substr(0, 40)) + "' is not finite");
  return v;
}

void check_count(std::uint64_t count, std::uint64_t limit, std::uint64_t bytes_left,
                 std::uint64_t min_bytes, const std::string& what, const std::string& where) {
  if (count > limit)
    throw InputError(where + std::to_string(count) + " " + what +
                     " announced, more than the limit of " + std::to_string(limit));
  if (min_bytes > 0 && count > bytes_left / min_bytes + 1)
    throw InputError(where + std::to_string(count) + " " + what +
                     " announced, but the rest of the file (" + std::to_string(bytes_left) +
                     " bytes) can hold at most " + std::to_string(bytes_left / min_bytes + 1) +
                     " (file truncated?)");
}

bool LineCursor::next(std::string_view& line) {
  if (pos_ >= text_.size()) return false;
  std::size_t nl = text_.find('\n', pos_);
  if (nl == std::string_view::npos) nl = text_.size();
  line = text_.substr(pos_, nl - pos_);
  if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
  pos_ = nl + 1 > text_.size() ? text_.size() : nl + 1;
  ++line_;
  return true;
}

namespace {
bool is_space(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f';
}
}  // namespace

bool Tokens::next(std::string_view& token) {
  while (pos_ < line_.size() && is_space(line_[pos_])) ++pos_;
  if (pos_ >= line_.size()) return false;
  const std::size_t start = pos_;
  while (pos_ < line_.size() && !is_space(line_[pos_])) ++pos_;
  token = line_.substr(start, pos_ - start);
  return true;
}

bool Tokens::empty() {
  while (pos_ < line_.size() && is_space(line_[pos_])) ++pos_;
  return pos_ >= line_.size();
}

std::string lower_case(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

std::string_view strip_comment(std::string_view line) {
  const std::size_t hash = line.find('#');
  return hash == std::string_view::npos ? line : line.substr(0, hash);
}

void add_fan(TriangleMesh& mesh, const std::uint32_t* polygon, std::size_t n) {
  for (std::size_t k = 1; k + 1 < n; ++k)
    mesh.triangles.push_back({polygon[0], polygon[k], polygon[k + 1]});
}

}  // namespace sandflow::mesh_io
