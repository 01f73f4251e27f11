// What the report reads back from a run folder (stats.csv, summary.json, frames/, render/) and a
// compare folder (compare.json). Bad files give an InputError naming the file and, for the CSV,
// the line; a missing summary or a last CSV row cut short by an interrupted run is not an error
// but a note the report prints, so a report can still be had of what the run left.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace sandflow {

/// The rows of a stats.csv, by column name.
struct StatsTable {
  std::string path;
  std::vector<std::string> columns;
  std::vector<std::vector<double>> rows;  ///< one per frame, in the order of `columns`
  std::string note;  ///< what was left out (a last row cut short), or empty

  std::size_t frames() const { return rows.size(); }
  bool has(const std::string& column) const;
  /// The column's values, one per row (InputError when the column is missing).
  std::vector<double> column(const std::string& name) const;
};

/// The columns the report plots; a stats.csv without one of them is refused.
extern const std::vector<std::string> kReportColumns;

/// Reads a stats.csv (as StatsWriter writes it: a header, then one row per frame). A header
/// without the report's columns, a row with a wrong number of fields or a field that is not a
/// number is an InputError "PATH:LINE: ..."; a last row without its line end and fields is
/// left out and named in `note`.
StatsTable read_stats_csv(const std::string& path);

/// Reads a JSON object (summary.json, compare.json). InputError naming the file when it cannot be
/// read, is not JSON (with the line and column) or is not an object.
nlohmann::json read_json_object(const std::string& path);

/// The frame numbers N of DIR/frames/NNNN.ply, ascending.
std::vector<int> list_frames(const std::string& dir);
/// The frame numbers N of DIR/render/NNNN.png, ascending.
std::vector<int> list_renders(const std::string& dir);
/// DIR/render/NNNN.png
std::string render_path(const std::string& dir, int frame);

/// Up to `n` of `available` (ascending), evenly spaced and ending with the last: the k-th of n is
/// the one at k/n of the way through (so frame 1, which shows little, is left out when there are
/// more frames than pictures).
std::vector<int> evenly_spaced(const std::vector<int>& available, int n);

/// Width and height of a PNG file, from its header; nullopt when it is not a readable PNG.
struct ImageSize {
  int width = 0, height = 0;
};
std::optional<ImageSize> png_size(const std::string& path);

}  // namespace sandflow
