// A memory control group for the tests of a memory limit: a child of this process's own group
// under cgroup v1's memory controller, with a limit, removed when the test ends. Making one needs
// root and that controller mounted writable; elsewhere the test skips.
#pragma once

#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>

#include "core/memory.hpp"

namespace sandflow::test {

class MemoryCgroup {
 public:
  /// A group `name` (unique to the test) limited to `limit_bytes`; see ready() and why_not().
  MemoryCgroup(const std::string& name, std::int64_t limit_bytes) {
    if (::geteuid() != 0) {
      why_not_ = "making a control group needs root";
      return;
    }
    const std::string own = own_cgroup(false);
    const std::filesystem::path parent = "/sys/fs/cgroup/memory" + (own == "/" ? "" : own);
    if (own.empty() || !std::filesystem::exists(parent / "memory.limit_in_bytes")) {
      why_not_ = "no cgroup v1 memory controller here";
      return;
    }
    dir_ = parent / name;
    std::error_code ec;
    std::filesystem::create_directory(dir_, ec);
    if (ec) {
      why_not_ = "cannot make " + dir_.string() + ": " + ec.message();
      return;
    }
    made_ = true;
    if (!(std::ofstream(dir_ / "memory.limit_in_bytes") << limit_bytes)) {
      why_not_ = "cannot set the limit of " + dir_.string();
      return;
    }
    limited_ = true;
  }
  ~MemoryCgroup() {
    // (its processes have ended, but the kernel may take a moment to let the group go)
    for (int i = 0; made_ && i < 50 && ::rmdir(dir_.c_str()) != 0; ++i)
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  MemoryCgroup(const MemoryCgroup&) = delete;
  MemoryCgroup& operator=(const MemoryCgroup&) = delete;

  bool ready() const { return made_ && limited_; }
  const std::string& why_not() const { return why_not_; }

  /// A wrapper for a command line that runs the command inside the group.
  std::string wrapper() const {
    return "sh -c 'echo $$ > " + (dir_ / "cgroup.procs").string() + " && exec \"$@\"' sh";
  }

  /// The processes of the group the kernel killed for memory so far (-1: it does not say).
  std::int64_t oom_kills() const {
    std::ifstream in(dir_ / "memory.oom_control");
    for (std::string line; std::getline(in, line);)
      if (line.rfind("oom_kill ", 0) == 0) return std::stoll(line.substr(9));
    return -1;
  }

 private:
  std::filesystem::path dir_;
  bool made_ = false, limited_ = false;
  std::string why_not_;
};

}  // namespace sandflow::test
