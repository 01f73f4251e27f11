// The guard in front of toml++ (internal to src/scene/): what Debian's toml++ 3.3 cannot be given
// safely is found in the text before toml++ sees it (toml_guard.cpp says what and why). Every text
// the loader parses, the scene file and each --set value, passes here first.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <string_view>

namespace sandflow::loader {

/// Where a text stops being safe for toml++, and why (a message for the user).
struct TomlHazard {
  std::size_t line = 1, column = 1;
  std::string what;
};

/// The first place in `text` that toml++ cannot be given safely, or nothing.
std::optional<TomlHazard> toml_hazard(std::string_view text);

}  // namespace sandflow::loader
