// What every fuzz target shares: the input as text, and the one outcome a reader may have besides
// success. A reader fed bad bytes must throw InputError whose message starts with the name it was
// given; anything else escaping (another exception, even SimulationError or OutputError, which
// would give the wrong exit status), a message that does not name the file, a crash, a sanitizer
// report, a hang or an allocation past libFuzzer's limit is a finding.
#pragma once

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <string_view>

#include "core/error.hpp"

namespace sandflow_fuzz {

inline std::string_view as_text(const std::uint8_t* data, std::size_t size) {
  return {reinterpret_cast<const char*>(data), size};
}

/// Runs `read`; an InputError is the expected outcome for bad input, and its message must start
/// with one of the names the input goes by ("fuzz.toml", "--set KEY", a mesh file's path).
template <class Read>
void expect_clean(Read&& read, std::string_view name, std::string_view other_name = {},
                  std::string_view third_name = {}) {
  try {
    read();
  } catch (const sandflow::InputError& e) {
    const std::string_view msg = e.what();
    const auto starts = [&](std::string_view n) {
      return !n.empty() && msg.substr(0, n.size()) == n;
    };
    const bool named = starts(name) || starts(other_name) || starts(third_name);
    if (!named) {
      std::fprintf(stderr, "finding: an InputError that does not name the input: %s\n", e.what());
      std::abort();
    }
  }
}

/// A folder of this process's own for files a target writes (in /dev/shm when there is one, so
/// that writing a file each input costs no disk), removed when the process exits normally
/// (libFuzzer's timed runs end otherwise: scripts/fuzz.sh removes it).
inline const std::filesystem::path& own_folder() {
  namespace fs = std::filesystem;
  static const fs::path dir = [] {
    std::error_code ec;
    const fs::path base =
        fs::is_directory("/dev/shm", ec) ? fs::path("/dev/shm") : fs::temp_directory_path();
    fs::path d = base / ("sandflow_fuzz_" + std::to_string(::getpid()));
    fs::create_directories(d);
    std::atexit([] {
      std::error_code ignored;
      fs::remove_all(own_folder(), ignored);
    });
    return d;
  }();
  return dir;
}

}  // namespace sandflow_fuzz
