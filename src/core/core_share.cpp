#include "core/core_share.hpp"

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

namespace fs = std::filesystem;

namespace sandflow {

std::optional<double> threads_waiting_seconds() {
  std::error_code ec;
  fs::directory_iterator it("/proc/self/task", ec);
  if (ec) return std::nullopt;
  double waited = 0;
  bool any = false;
  for (const fs::directory_entry& task : it) {
    // "time on a core, time waiting for one (both ns), timeslices" (the kernel's sched-stats.rst)
    std::ifstream in(task.path() / "schedstat");
    unsigned long long on_core = 0, waiting = 0;
    if (!(in >> on_core >> waiting)) continue;  // a thread that ended meanwhile
    waited += static_cast<double>(waiting) * 1e-9;
    any = true;
  }
  if (!any) return std::nullopt;
  return waited;
}

bool openmp_threads_spin() {
  if (std::getenv("GOMP_SPINCOUNT") != nullptr) return false;
  const char* policy = std::getenv("OMP_WAIT_POLICY");
  if (policy == nullptr) return true;
  std::string p(policy);
  std::transform(p.begin(), p.end(), p.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return p.find("passive") == std::string::npos;
}

CoreShareWatch::CoreShareWatch(int threads, double window_seconds)
    : threads_(std::max(1, threads)),
      window_(window_seconds),
      waited_at_start_(threads_waiting_seconds()) {}

std::optional<double> CoreShareWatch::poll() {
  const double now = clock_.seconds();
  const double wall = now - window_start_;
  if (wall < window_) return std::nullopt;
  const std::optional<double> waited = threads_waiting_seconds();
  const std::optional<double> before = waited_at_start_;
  window_start_ = now;
  waited_at_start_ = waited;
  // (a thread that ended takes its count with it: that window says nothing)
  if (!waited || !before || *waited < *before) return std::nullopt;
  return (*waited - *before) / (threads_ * wall);
}

}  // namespace sandflow
