#include "core/memory_gate.hpp"

#include <algorithm>
#include <chrono>

namespace sandflow {

MemoryGate::MemoryGate(std::int64_t budget, int jobs, int unmeasured)
    : budget_(std::max<std::int64_t>(budget, 0)),
      jobs_(std::max(jobs, 1)),
      unmeasured_(std::clamp(unmeasured, 1, std::max(jobs, 1))) {}

int MemoryGate::allowed_locked() const {
  if (budget_ == 0) return jobs_;
  if (largest_ == 0) return unmeasured_;
  // one job always runs, even one that needs more than the budget: it is the job asked for
  return static_cast<int>(std::clamp<std::int64_t>(budget_ / largest_, 1, jobs_));
}

int MemoryGate::allowed() const {
  const std::lock_guard<std::mutex> lock(mutex_);
  return budget_ > 0 && largest_ == 0 ? jobs_ : allowed_locked();
}

std::int64_t MemoryGate::largest_peak() const {
  const std::lock_guard<std::mutex> lock(mutex_);
  return largest_;
}

bool MemoryGate::enter(const std::function<bool()>& stop) {
  std::unique_lock<std::mutex> lock(mutex_);
  // polled: a stop asked by a signal handler cannot notify a condition variable
  while (running_ >= allowed_locked()) {
    if (stop()) return false;
    room_.wait_for(lock, std::chrono::milliseconds(50));
  }
  if (stop()) return false;
  ++running_;
  return true;
}

void MemoryGate::leave(std::int64_t peak) {
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    --running_;
    largest_ = std::max(largest_, peak);
  }
  room_.notify_all();
}

}  // namespace sandflow
