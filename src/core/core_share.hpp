// Whether a job has the cores it asked for. Two jobs that each take every core slow each other
// several times when OpenMP's threads spin at the step's barriers (libgomp's default): a waiting
// thread keeps the core the other job's working thread needs (docs/known-issues.md). The kernel
// counts how long each thread was ready to run but had no core; a run watches that share and says
// when it is large, while it happens, instead of only running slowly.
#pragma once

#include <optional>

#include "core/timer.hpp"

namespace sandflow {

/// Seconds the threads of this process (those alive now) have spent ready to run but waiting for
/// a core, from Linux's /proc/self/task/*/schedstat; nullopt where the kernel keeps no such count.
std::optional<double> threads_waiting_seconds();

/// Whether OpenMP's threads wait at barriers by spinning: libgomp's default, unless
/// OMP_WAIT_POLICY=passive or a GOMP_SPINCOUNT is set (both read by libgomp before main).
bool openmp_threads_spin();

/// A run's share of waiting, window by window: poll() between frames.
class CoreShareWatch {
 public:
  CoreShareWatch(int threads, double window_seconds);

  /// Once at least `window_seconds` of wall time have passed since the last window ended: the
  /// time its threads waited for a core over that window, divided by threads × the window (0: the
  /// job had its cores, 0.5: half of it waited). nullopt between windows and without the count.
  std::optional<double> poll();

 private:
  int threads_;
  double window_;
  Stopwatch clock_;
  double window_start_ = 0;
  std::optional<double> waited_at_start_;
};

}  // namespace sandflow
