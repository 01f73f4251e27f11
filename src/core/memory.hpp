// The memory a process has used, for the run's summary (summary.json: peak_memory_bytes), and
// what the machine has free for more.
#pragma once

#include <cstdint>
#include <string>

namespace sandflow {

/// The most resident memory this process has held so far (VmHWM of /proc/self/status) [bytes];
/// 0 where the system does not say.
std::int64_t peak_memory_bytes();

/// This process's control group for the v1 memory controller ("4:memory:/a/b" gives "/a/b") or
/// the v2 hierarchy ("0::/a/b"), or "" when it is in neither.
std::string own_cgroup(bool v2);

/// The memory that new work can take without swapping [bytes]: the kernel's MemAvailable, or less
/// when this process's control group (cgroup v2 memory.max, v1 memory.limit_in_bytes) leaves less;
/// 0 where the system does not say.
std::int64_t available_memory_bytes();

}  // namespace sandflow
