// How many threads a job takes when neither its command line nor its scene says.
#pragma once

#include <omp.h>

#include <cstdlib>

namespace sandflow {

/// The most threads a job takes, from any of `--threads`, `simulation.threads` and OMP_NUM_THREADS
inline constexpr int kMaxThreads = 4096;

/// OMP_NUM_THREADS when it holds a positive count (the first of a list, as OpenMP reads it), else
/// one per core this process may run on. OMP_NUM_THREADS is how a user or a job scheduler gives
/// each of several jobs its share of the cores: OpenMP's threads wait by spinning, so jobs that
/// each take every core slow each other about fivefold (docs/known-issues.md). Read from the
/// environment, not from omp_get_max_threads(), which the last omp_set_num_threads() changes.
inline int default_thread_count() {
  if (const char* text = std::getenv("OMP_NUM_THREADS")) {
    char* end = nullptr;
    const long n = std::strtol(text, &end, 10);
    while (end != text && (*end == ' ' || *end == '\t')) ++end;
    if (end != text && n > 0 && n <= kMaxThreads && (*end == '\0' || *end == ','))
      return static_cast<int>(n);
  }
  return omp_get_num_procs();
}

}  // namespace sandflow
