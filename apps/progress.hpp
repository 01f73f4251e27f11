// The progress line of long commands: frame, grains, speed, ETA. Redrawn in place on a terminal;
// on a pipe or a file, one plain line every 5 % of the frames instead.
#pragma once

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <string>

#include <unistd.h>

#include <fmt/format.h>

#include "core/timer.hpp"

namespace sandflow {

class Progress {
 public:
  /// `first_frame`: frames already done before this process (a resumed run), left out of the speed.
  Progress(std::string label, int total_frames, int first_frame = 0)
      : label_(std::move(label)),
        total_(total_frames),
        first_(first_frame),
        tty_(isatty(STDERR_FILENO) != 0),
        plain_every_(std::max(1, total_frames / 20)) {}

  /// `simulated`: grains in the DEM (active + interface), shown when below `grains`.
  void update(int frame, std::int64_t grains, std::int64_t simulated = -1) {
    const double elapsed = clock_.seconds();
    const double per_frame = elapsed / std::max(1, frame - first_);
    const double eta = per_frame * (total_ - frame);
    const std::string line =
        fmt::format("{} frame {}/{}  grains {}{}  {:.1f} frames/min  ETA {}", label_, frame, total_,
                    grains,
                    simulated >= 0 && simulated < grains ? fmt::format(" ({} simulated)", simulated)
                                                         : std::string(),
                    60.0 / std::max(per_frame, 1e-9), format_duration(eta));
    if (tty_) {
      std::fprintf(stderr, "\r%s\033[K", line.c_str());
      if (frame == total_) std::fputc('\n', stderr);
    } else if (frame % plain_every_ == 0 || frame == total_) {
      std::fprintf(stderr, "%s\n", line.c_str());  // a log gets ~20 lines a run, not one a frame
    }
    std::fflush(stderr);
  }

  /// A line of its own (a warning) while the progress line runs: on a terminal it takes the
  /// progress line's place, which the next update() draws again below it.
  void note(const std::string& text) {
    if (tty_) std::fputs("\r\033[K", stderr);
    std::fprintf(stderr, "%s\n", text.c_str());
    std::fflush(stderr);
  }

  static std::string format_duration(double s) {
    const auto t = static_cast<std::int64_t>(s + 0.5);
    if (t >= 3600) return fmt::format("{}h{:02d}m", t / 3600, (t % 3600) / 60);
    if (t >= 60) return fmt::format("{}m{:02d}s", t / 60, t % 60);
    return fmt::format("{}s", t);
  }

 private:
  std::string label_;
  int total_;
  int first_;
  bool tty_;
  Stopwatch clock_;
  int plain_every_;  ///< frames between plain lines (stderr not a terminal)
};

}  // namespace sandflow
