// The progress line of long commands: frame, grains, speed, ETA. Redrawn in place on a terminal;
// on a pipe or a file, one plain line every 5 % of the frames instead.
#pragma once

#include <omp.h>
#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <optional>
#include <string>

#include <fmt/format.h>

#include "core/core_share.hpp"
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
    // (no frame timed yet, when every one so far was skipped: no speed to show)
    const double per_frame = elapsed / std::max(1, frame - first_);
    const std::string speed =
        frame > first_ ? fmt::format("{:.1f} frames/min  ETA {}", 60.0 / std::max(per_frame, 1e-9),
                                     format_duration(per_frame * (total_ - frame)))
                       : std::string("frames/min -  ETA -");
    const std::string line =
        fmt::format("{} frame {}/{}  grains {}{}  {}", label_, frame, total_, grains,
                    simulated >= 0 && simulated < grains ? fmt::format(" ({} simulated)", simulated)
                                                         : std::string(),
                    speed);
    if (tty_) {
      std::fprintf(stderr, "\r%s\033[K", line.c_str());
      if (frame == total_) std::fputc('\n', stderr);
    } else if (frame % plain_every_ == 0 || frame == total_) {
      std::fprintf(stderr, "%s\n", line.c_str());  // a log gets ~20 lines a run, not one a frame
    }
    std::fflush(stderr);
  }

  /// What the line says before the frame count, from the next update() on (render: fewer jobs at
  /// once than asked, once the memory says so).
  void relabel(std::string label) { label_ = std::move(label); }

  /// One frame done at no cost (a picture kept from an earlier render): left out of the speed,
  /// as a resumed run's first frames are. Before the update() that counts it.
  void skip() { ++first_; }

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

/// Says once, while it happens, that a job's threads wait for cores another job holds
/// (core/core_share.hpp). Only when its OpenMP threads spin (idle passive threads share the cores
/// as any program does), with 2 or more threads and no more than the cores (libgomp throttles its
/// own spinning beyond that).
class CoreShareWarning {
 public:
  /// Wall time over which the wait is measured before it may warn [s]: long enough that a compile
  /// or a backup of a few seconds beside the job says nothing.
  static constexpr double kWindow = 10.0;
  /// The share of the threads' time spent waiting that is worth a warning: two jobs that each
  /// take both cores wait half of it.
  static constexpr double kShare = 0.25;

  explicit CoreShareWarning(int threads) : threads_(threads) {
    if (threads > 1 && threads <= omp_get_num_procs() && openmp_threads_spin())
      watch_.emplace(threads, kWindow);
  }

  /// Between frames: the warning, the first time a window's share reaches kShare.
  std::optional<std::string> poll() {
    if (!watch_) return std::nullopt;
    const std::optional<double> waited = watch_->poll();
    if (!waited || *waited < kShare) return std::nullopt;
    watch_.reset();  // said once
    return fmt::format(
        "warning: this job's {} threads waited for a core {:.0f} % of the last {:.0f} s: other "
        "work shares this machine's {} cores, and OpenMP's threads, which spin while they wait, "
        "then slow every job several times; give each job its share (--threads, or "
        "OMP_NUM_THREADS) or set GOMP_SPINCOUNT=1000 (docs/usage.md, --threads)",
        threads_, 100 * *waited, kWindow, omp_get_num_procs());
  }

 private:
  int threads_;
  std::optional<CoreShareWatch> watch_;
};

}  // namespace sandflow
