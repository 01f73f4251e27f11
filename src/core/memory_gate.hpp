// How many memory-hungry jobs (the POV-Rays of `sandflow render`) run at once: as many as their
// largest measured peak fits in the memory free when the jobs began, and never more than asked.
// Before any job has ended nothing is measured, and at most `unmeasured` run: asking for far more
// jobs than cores on a scene of millions of grains would otherwise start them all before the first
// says what one costs.
#pragma once

#include <condition_variable>
#include <cstdint>
#include <functional>
#include <mutex>

namespace sandflow {

class MemoryGate {
 public:
  /// budget: bytes the jobs may hold together (0: unknown, no limit but `jobs`); jobs: at most
  /// this many at once; unmeasured: at most this many before a job's peak is known.
  MemoryGate(std::int64_t budget, int jobs, int unmeasured);

  /// Waits for room for one more job; false, without waiting on, once `stop()` is true.
  bool enter(const std::function<bool()>& stop);
  /// A job has ended, having held `peak` bytes at most (0: not known).
  void leave(std::int64_t peak);

  /// The jobs the measured peak lets run at once (the jobs asked for until one is measured).
  int allowed() const;
  /// The largest peak measured so far [bytes].
  std::int64_t largest_peak() const;

 private:
  int allowed_locked() const;

  const std::int64_t budget_;
  const int jobs_;
  const int unmeasured_;
  mutable std::mutex mutex_;
  std::condition_variable room_;
  int running_ = 0;
  std::int64_t largest_ = 0;
};

}  // namespace sandflow
