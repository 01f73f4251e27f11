// What a run writes in its output folder (DESIGN.md §8): stats.csv (a row per frame),
// summary.json (the run's Table 1 row and heap figures) and frames/NNNN.ply.
#pragma once

#include <cstdio>
#include <string>

#include <nlohmann/json.hpp>

#include "scene/world.hpp"

namespace sandflow {

/// Prepares DIR for a run: creates it (and DIR/frames); a non-empty DIR is refused (InputError)
/// unless `force`, in which case the old run's files are removed first.
void prepare_output_dir(const std::string& dir, bool force);

/// Writes `text` to `path` atomically (temporary file, then rename). Throws OutputError.
void write_file_atomic(const std::string& path, const std::string& text);

/// Path of frame `frame` (1-based) in a run folder: DIR/frames/NNNN.ply.
std::string frame_path(const std::string& dir, int frame);

/// stats.csv, one row per frame, flushed as it goes so a crash keeps the rows written so far.
class StatsWriter {
 public:
  explicit StatsWriter(const std::string& path);
  ~StatsWriter();
  StatsWriter(const StatsWriter&) = delete;
  StatsWriter& operator=(const StatsWriter&) = delete;
  void write(const FrameStats& s);

 private:
  std::string path_;
  std::FILE* f_ = nullptr;
};

}  // namespace sandflow
