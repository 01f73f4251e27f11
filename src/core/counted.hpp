#pragma once
// A count with its noun, in the singular for one: "1 grain", "2 grains".
#include <cstdint>
#include <string>
#include <string_view>

#include <fmt/format.h>

namespace sandflow {

/// "n nouns", or "1 noun" (the noun given in the singular; plurals here all add an s).
inline std::string counted(std::int64_t n, std::string_view noun) {
  return fmt::format("{} {}{}", n, noun, n == 1 ? "" : "s");
}

}  // namespace sandflow
