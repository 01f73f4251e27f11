// The memory a process has used, for the run's summary (summary.json: peak_memory_bytes).
#pragma once

#include <cstdint>

namespace sandflow {

/// The most resident memory this process has held so far (VmHWM of /proc/self/status) [bytes];
/// 0 where the system does not say.
std::int64_t peak_memory_bytes();

}  // namespace sandflow
