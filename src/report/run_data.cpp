#include "report/run_data.hpp"

#include <algorithm>
#include <charconv>
#include <cstdint>
#include <filesystem>
#include <fstream>

#include <fmt/format.h>

#include "core/error.hpp"
#include "core/file_kind.hpp"
#include "core/read_file.hpp"

namespace sandflow {

namespace fs = std::filesystem;

const std::vector<std::string> kReportColumns = {
    "frame",       "time",  "dt",      "n_total",   "n_active", "n_interface",
    "n_static",    "trapped", "dislodged", "slept", "woken",    "wall_seconds"};

namespace {

std::vector<std::string> split_fields(const std::string& line) {
  std::vector<std::string> out;
  std::size_t start = 0;
  for (;;) {
    const std::size_t comma = line.find(',', start);
    out.push_back(line.substr(start, comma - start));
    if (comma == std::string::npos) return out;
    start = comma + 1;
  }
}

/// The numbers of the frames/NNNN.ply or render/NNNN.png files of a folder.
std::vector<int> numbered_files(const fs::path& folder, const std::string& ext) {
  std::vector<int> out;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(folder, ec)) {
    const std::string stem = e.path().stem().string();
    if (e.path().extension() != ext || stem.empty() || stem.size() > 9) continue;
    if (!std::all_of(stem.begin(), stem.end(), [](char c) { return c >= '0' && c <= '9'; }))
      continue;
    out.push_back(std::stoi(stem));
  }
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace

bool StatsTable::has(const std::string& name) const {
  return std::find(columns.begin(), columns.end(), name) != columns.end();
}

std::vector<double> StatsTable::column(const std::string& name) const {
  const auto it = std::find(columns.begin(), columns.end(), name);
  if (it == columns.end()) throw InputError(fmt::format("{}: no column '{}'", path, name));
  const std::size_t c = static_cast<std::size_t>(it - columns.begin());
  std::vector<double> out;
  out.reserve(rows.size());
  for (const auto& row : rows) out.push_back(row[c]);
  return out;
}

StatsTable read_stats_csv(const std::string& path) {
  const std::optional<std::string> written =
      read_file_if_present(path, "statistics file", kAnyFileSize);
  if (!written)
    throw InputError(fmt::format("{}: cannot read (the run folder has no statistics)", path));
  const std::string& text = *written;
  StatsTable t;
  t.path = path;

  // the lines, each with whether it ended with a line break (a cut-short last row has none)
  std::vector<std::string> lines;
  std::size_t start = 0;
  while (start < text.size()) {
    const std::size_t nl = text.find('\n', start);
    std::string line = text.substr(start, nl == std::string::npos ? nl : nl - start);
    if (!line.empty() && line.back() == '\r') line.pop_back();
    lines.push_back(line);
    if (nl == std::string::npos) break;
    start = nl + 1;
  }
  const bool last_unterminated = !text.empty() && text.back() != '\n';
  if (lines.empty() || lines[0].empty())
    throw InputError(fmt::format("{}:1: empty file; expected the header line (frame,time,...)", path));

  t.columns = split_fields(lines[0]);
  for (const std::string& c : kReportColumns)
    if (!t.has(c))
      throw InputError(fmt::format("{}:1: the header has no column '{}'; expected StatsWriter's "
                                   "header (frame,time,substeps,dt,...)",
                                   path, c));

  for (std::size_t k = 1; k < lines.size(); ++k) {
    const std::size_t line_no = k + 1;
    if (lines[k].empty()) {
      if (k + 1 == lines.size()) break;  // a trailing blank line
      throw InputError(fmt::format("{}:{}: empty line; expected a row of {} fields", path, line_no,
                                   t.columns.size()));
    }
    const std::vector<std::string> fields = split_fields(lines[k]);
    // the row an interrupted run was writing (no line end: its last field may be cut too): left
    // out, and said so
    if (k + 1 == lines.size() && last_unterminated) {
      t.note = fmt::format(
          "{}:{}: the last row has no line end ({} of {} fields; the run was interrupted?) and is "
          "left out",
          path, line_no, fields.size(), t.columns.size());
      break;
    }
    if (fields.size() != t.columns.size()) {
      throw InputError(fmt::format("{}:{}: {} fields; expected {} as in the header", path, line_no,
                                   fields.size(), t.columns.size()));
    }
    std::vector<double> row(fields.size());
    for (std::size_t c = 0; c < fields.size(); ++c) {
      const std::string& f = fields[c];
      const auto [end, ec] = std::from_chars(f.data(), f.data() + f.size(), row[c]);
      if (f.empty() || ec != std::errc() || end != f.data() + f.size())
        throw InputError(fmt::format("{}:{}: column '{}' (field {}) is \"{}\"; expected a number",
                                     path, line_no, t.columns[c], c + 1, f));
    }
    t.rows.push_back(std::move(row));
  }
  return t;
}

nlohmann::json read_json_object(const std::string& path) {
  const std::string text = read_whole_file(path, "JSON file", kAnyFileSize);
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
  } catch (const nlohmann::json::parse_error& e) {
    // e.what() reads "[json.exception.parse_error.101] parse error at line 3, column 5: ..."
    throw InputError(fmt::format("{}: not valid JSON: {}", path, without_library_tag(e.what())));
  }
  if (!j.is_object())
    throw InputError(fmt::format("{}: expected a JSON object {{...}}, found a {}", path, j.type_name()));
  return j;
}

std::vector<int> list_frames(const std::string& dir) {
  return numbered_files(fs::path(dir) / "frames", ".ply");
}

std::vector<int> list_renders(const std::string& dir) {
  return numbered_files(fs::path(dir) / "render", ".png");
}

std::string render_path(const std::string& dir, int frame) {
  return (fs::path(dir) / "render" / fmt::format("{:04d}.png", frame)).string();
}

std::vector<int> evenly_spaced(const std::vector<int>& available, int n) {
  const std::size_t m = available.size();
  if (n <= 0 || m == 0) return {};
  if (m <= static_cast<std::size_t>(n)) return available;
  std::vector<int> out;
  for (int k = 1; k <= n; ++k) {
    // the one at k/n of the way, rounded to the nearest (k = n: the last)
    const std::size_t idx = (static_cast<std::size_t>(k) * m + static_cast<std::size_t>(n) / 2) /
                                static_cast<std::size_t>(n) - 1;
    out.push_back(available[std::min(idx, m - 1)]);
  }
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

std::optional<ImageSize> png_size(const std::string& path) {
  // the signature (8 bytes), then the IHDR chunk: length, "IHDR", width, height (big-endian)
  if (!special_file_kind(path).empty()) return std::nullopt;
  std::ifstream in(path, std::ios::binary);
  unsigned char b[24];
  if (!in.read(reinterpret_cast<char*>(b), sizeof b)) return std::nullopt;
  static constexpr unsigned char kSig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  if (!std::equal(kSig, kSig + 8, b) || !std::equal(b + 12, b + 16, "IHDR")) return std::nullopt;
  auto be32 = [&](int k) {
    return static_cast<int>(std::uint32_t(b[k]) << 24 | std::uint32_t(b[k + 1]) << 16 |
                            std::uint32_t(b[k + 2]) << 8 | std::uint32_t(b[k + 3]));
  };
  const ImageSize size{be32(16), be32(20)};
  if (size.width <= 0 || size.height <= 0) return std::nullopt;
  return size;
}

}  // namespace sandflow
