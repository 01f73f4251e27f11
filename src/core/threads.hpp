// How many threads a job takes when neither its command line nor its scene says.
#pragma once

#include <omp.h>

#include <algorithm>
#include <cstdlib>
#include <optional>

namespace sandflow {

/// The most threads a job takes, from any of `--threads`, `simulation.threads` and OMP_NUM_THREADS
inline constexpr int kMaxThreads = 4096;

/// The count OMP_NUM_THREADS holds (the first of a list, as OpenMP reads it) when it is one from 1
/// to kMaxThreads; nothing when it is unset or holds anything else (a word, 0, 100000).
inline std::optional<int> omp_num_threads() {
  const char* text = std::getenv("OMP_NUM_THREADS");
  if (!text) return std::nullopt;
  char* end = nullptr;
  const long n = std::strtol(text, &end, 10);
  while (end != text && (*end == ' ' || *end == '\t')) ++end;
  if (end != text && n > 0 && n <= kMaxThreads && (*end == '\0' || *end == ','))
    return static_cast<int>(n);
  return std::nullopt;
}

/// OMP_NUM_THREADS when it holds a count (omp_num_threads), else one per core this process may
/// run on; at most OMP_THREAD_LIMIT (OpenMP gives no region more). OMP_NUM_THREADS is how a user or
/// a job scheduler gives each of several jobs its share of the cores: OpenMP's threads wait by
/// spinning, so jobs that each take every core slow each other about fivefold
/// (docs/known-issues.md). Read from the environment, not from omp_get_max_threads(), which the
/// last omp_set_num_threads() changes.
inline int default_thread_count() {
  return std::min(omp_num_threads().value_or(omp_get_num_procs()), omp_get_thread_limit());
}

}  // namespace sandflow
