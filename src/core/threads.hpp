// How many threads a job takes when neither its command line nor its scene says.
#pragma once

#include <omp.h>

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <optional>
#include <string>
#include <vector>

namespace sandflow {

/// The most threads a job takes, from any of `--threads`, `simulation.threads` and OMP_NUM_THREADS
inline constexpr int kMaxThreads = 4096;

/// The count a value of OMP_NUM_THREADS holds (the first of a list, as OpenMP reads it) when it is
/// one from 1 to kMaxThreads; nothing when it holds anything else (a word, 0, 100000).
inline std::optional<int> omp_thread_count(const char* text) {
  char* end = nullptr;
  const long n = std::strtol(text, &end, 10);
  while (end != text && (*end == ' ' || *end == '\t')) ++end;
  if (end != text && n > 0 && n <= kMaxThreads && (*end == '\0' || *end == ','))
    return static_cast<int>(n);
  return std::nullopt;
}

/// The count OMP_NUM_THREADS holds (omp_thread_count); nothing when it is unset.
inline std::optional<int> omp_num_threads() {
  const char* text = std::getenv("OMP_NUM_THREADS");
  return text ? omp_thread_count(text) : std::nullopt;
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

/// The CPUs of a list as libgomp and Linux write them ("0 3-5 8-14:2", spaces or commas), in
/// order; nothing when it cannot be read.
inline std::optional<std::vector<long>> cpu_list(const std::string& text) {
  std::vector<long> cpus;
  const char* p = text.c_str();
  const auto number = [&](long& n) {
    char* end = nullptr;
    n = std::strtol(p, &end, 10);
    const bool ok = end != p && n >= 0 && n < (1 << 20);
    p = end;
    return ok;
  };
  while (*p) {
    if (*p == ' ' || *p == ',' || *p == '\t' || *p == '\n') {
      ++p;
      continue;
    }
    long first = 0, last = 0, stride = 1;
    if (!number(first)) return std::nullopt;
    last = first;
    if (*p == '-') {
      ++p;
      if (!number(last) || last < first) return std::nullopt;
      if (*p == ':') {
        ++p;
        if (!number(stride) || stride < 1) return std::nullopt;
      }
    }
    for (long cpu = first; cpu <= last; cpu += stride) cpus.push_back(cpu);
  }
  return cpus;
}

/// The CPUs online on this machine as Linux lists them ("0-1"; "" when it cannot be read).
inline std::string online_cpus() {
  std::ifstream in("/sys/devices/system/cpu/online");
  std::string text;
  std::getline(in, text);
  return text;
}

/// The CPUs the process's control group lets it run on (its cpuset: a container started with
/// fewer CPUs than the machine has), as Linux lists them; "" when no cpuset can be read. Read from
/// cgroup v2 (cpuset.cpus.effective) or v1 (the cpuset hierarchy's cpuset.effective_cpus), from
/// the process's cgroup list and the cgroup file system's root (tests point both elsewhere).
inline std::string cgroup_cpus(const std::string& cgroup_list = "/proc/self/cgroup",
                               const std::string& root = "/sys/fs/cgroup") {
  std::ifstream in(cgroup_list);
  std::string line;
  while (std::getline(in, line)) {  // "ID:CONTROLLERS:PATH", v2's line with no controllers
    const std::size_t a = line.find(':'), b = line.find(':', a + 1);
    if (a == std::string::npos || b == std::string::npos) continue;
    const std::string controllers = "," + line.substr(a + 1, b - a - 1) + ",";
    const std::string path = line.substr(b + 1);
    std::string file;
    if (controllers == ",,")
      file = root + path + "/cpuset.cpus.effective";
    else if (controllers.find(",cpuset,") != std::string::npos)
      file = root + "/cpuset" + path + "/cpuset.effective_cpus";
    else
      continue;
    std::ifstream cpus(file);
    std::string text;
    if (std::getline(cpus, text) && !text.empty()) return text;
  }
  return "";
}

/// The CPUs this process may run on: its cgroup's cpuset, else the CPUs online.
inline std::string usable_cpus() {
  const std::string cpuset = cgroup_cpus();
  return cpuset.empty() ? online_cpus() : cpuset;
}

/// The CPUs in GOMP_CPU_AFFINITY that this process may not run on (usable_cpus); empty when the
/// variable is unset or cannot be read (libgomp then ignores it and says so). libgomp binds its
/// k-th thread to the k-th CPU listed and stops the program ("Thread creation failed: Invalid
/// argument", exit status 1) when there is no such CPU (a job script written for a larger
/// machine): the caller warns first, naming the variable. (Not the process's affinity mask:
/// libgomp has already bound the main thread to the first CPU listed when main() begins.)
inline std::vector<long> absent_affinity_cpus() {
  const char* text = std::getenv("GOMP_CPU_AFFINITY");
  if (!text) return {};
  const std::optional<std::vector<long>> listed = cpu_list(text);
  const std::optional<std::vector<long>> usable = cpu_list(usable_cpus());
  if (!listed || !usable || usable->empty()) return {};
  std::vector<long> absent;
  for (const long cpu : *listed)
    if (std::find(usable->begin(), usable->end(), cpu) == usable->end() &&
        std::find(absent.begin(), absent.end(), cpu) == absent.end())
      absent.push_back(cpu);
  return absent;
}

}  // namespace sandflow
