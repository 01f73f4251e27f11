// What every fuzz target shares: the input as text, and the one outcome a reader may have besides
// success. A reader fed bad bytes must throw InputError whose message starts with the name it was
// given; anything else escaping (another exception, even SimulationError or OutputError, which
// would give the wrong exit status), a message that does not name the file, a crash, a sanitizer
// report, a hang or an allocation past libFuzzer's limit is a finding.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <string_view>

#include "core/error.hpp"

namespace sandflow_fuzz {

inline std::string_view as_text(const std::uint8_t* data, std::size_t size) {
  return {reinterpret_cast<const char*>(data), size};
}

/// Runs `read`; an InputError is the expected outcome for bad input, and its message must start
/// with one of the names the input goes by ("fuzz.toml", "--set KEY").
template <class Read>
void expect_clean(Read&& read, std::string_view name, std::string_view other_name = {}) {
  try {
    read();
  } catch (const sandflow::InputError& e) {
    const std::string_view msg = e.what();
    const bool named = msg.substr(0, name.size()) == name ||
                       (!other_name.empty() && msg.substr(0, other_name.size()) == other_name);
    if (!named) {
      std::fprintf(stderr, "finding: an InputError that does not name the input: %s\n", e.what());
      std::abort();
    }
  }
}

}  // namespace sandflow_fuzz
