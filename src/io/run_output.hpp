// What a run writes in its output folder (docs/design.md §8): stats.csv (a row per frame),
// summary.json (the run's Table 1 row and heap figures) and frames/NNNN.ply. Whole files are
// written with write_file_atomic (core/atomic_file.hpp).
#pragma once

#include <cstdio>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "sim/world.hpp"

namespace sandflow {

/// Prepares DIR for a run: creates it (and DIR/frames); a non-empty DIR is refused (InputError)
/// unless `force`, in which case the old run's files are removed first.
void prepare_output_dir(const std::string& dir, bool force);

/// Removes the temporary files (NAME.tmp) a killed run left in DIR, DIR/frames and
/// DIR/heightfield.
void remove_partial_files(const std::string& dir);

/// Prepares the folder of a run resumed at frame `frame`: removes the temporary files a killed
/// run left, and the frames after `frame` (the resumed run writes them again).
void prepare_resumed_dir(const std::string& dir, int frame);

/// Path of frame `frame` (1-based) in a run folder: DIR/frames/NNNN.ply.
std::string frame_path(const std::string& dir, int frame);

/// One row of stats.csv (with its newline), and the header.
std::string stats_row(const FrameStats& s);
std::string stats_header();

/// stats.csv, one row per frame, flushed as it goes so a crash keeps the rows written so far.
class StatsWriter {
 public:
  /// Writes the header and `rows` (a resumed run's frames so far) atomically, then appends.
  explicit StatsWriter(const std::string& path, const std::vector<FrameStats>& rows = {});
  ~StatsWriter();
  StatsWriter(const StatsWriter&) = delete;
  StatsWriter& operator=(const StatsWriter&) = delete;
  void write(const FrameStats& s);

 private:
  std::string path_;
  std::FILE* f_ = nullptr;
};

}  // namespace sandflow
