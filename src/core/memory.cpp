#include "core/memory.hpp"

#include <fstream>
#include <sstream>
#include <string>

namespace sandflow {

std::int64_t peak_memory_bytes() {
  // a line "VmHWM:     123456 kB" (Linux)
  std::ifstream in("/proc/self/status");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("VmHWM:", 0) != 0) continue;
    std::istringstream fields(line.substr(6));
    std::int64_t kb = 0;
    std::string unit;
    if (fields >> kb >> unit && unit == "kB" && kb >= 0) return kb * 1024;
    return 0;
  }
  return 0;
}

}  // namespace sandflow
