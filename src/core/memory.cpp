#include "core/memory.hpp"

#include <algorithm>
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

std::string own_cgroup(bool v2) {
  std::ifstream in("/proc/self/cgroup");
  for (std::string line; std::getline(in, line);) {
    const std::size_t a = line.find(':'), b = line.find(':', a + 1);
    if (a == std::string::npos || b == std::string::npos) continue;
    const std::string controllers = line.substr(a + 1, b - a - 1);
    if (v2 ? line.rfind("0::", 0) == 0 : controllers == "memory") return line.substr(b + 1);
  }
  return "";
}

namespace {

// The first number in `path`, or -1 ("max", absent, unreadable).
std::int64_t number_in(const char* path) {
  std::ifstream in(path);
  std::int64_t v = -1;
  if (!(in >> v) || v < 0) return -1;
  return v;
}

// What the limits of this process's control group and of its ancestors leave [bytes], or -1
// when none sets one.
std::int64_t cgroup_room() {
  std::int64_t room = -1;
  for (const bool v2 : {true, false}) {
    std::string path = own_cgroup(v2);
    if (path.empty()) continue;
    const std::string root = v2 ? "/sys/fs/cgroup" : "/sys/fs/cgroup/memory";
    const char* limit_name = v2 ? "/memory.max" : "/memory.limit_in_bytes";
    const char* usage_name = v2 ? "/memory.current" : "/memory.usage_in_bytes";
    for (;;) {
      const std::string dir = root + (path == "/" ? "" : path);
      const std::int64_t limit = number_in((dir + limit_name).c_str());
      const std::int64_t used = number_in((dir + usage_name).c_str());
      // (v1 writes "no limit" as a number near 2^63, v2 as "max")
      if (limit > 0 && used >= 0 && limit < (std::int64_t{1} << 60)) {
        const std::int64_t left = std::max<std::int64_t>(limit - used, 0);
        room = room < 0 ? left : std::min(room, left);
      }
      if (path.empty() || path == "/") break;
      const std::size_t slash = path.rfind('/');
      path = slash == 0 || slash == std::string::npos ? "/" : path.substr(0, slash);
    }
  }
  return room;
}

}  // namespace

std::int64_t available_memory_bytes() {
  // a line "MemAvailable:   24328368 kB" (Linux 3.14 and later)
  std::ifstream in("/proc/meminfo");
  std::int64_t available = 0;
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("MemAvailable:", 0) != 0) continue;
    std::istringstream fields(line.substr(13));
    std::int64_t kb = 0;
    std::string unit;
    if (fields >> kb >> unit && unit == "kB" && kb >= 0) available = kb * 1024;
    break;
  }
  const std::int64_t room = cgroup_room();
  if (room >= 0) available = available > 0 ? std::min(available, room) : room;
  return available;
}

}  // namespace sandflow
