// What the scene tests ask of an invalid scene text: the message of its InputError, and that the
// message names every piece (a place, a key, what was expected). The text is loaded as "t.toml".
#pragma once

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "core/error.hpp"
#include "scene/scene_loader.hpp"

namespace sandflow::test {

/// The message of the InputError the scene raises, or "" when it loads.
inline std::string error_of(const std::string& text, const std::vector<Override>& overrides = {}) {
  try {
    load_scene_from_string(text, "t.toml", overrides);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

/// The scene must raise an InputError whose message contains every piece.
inline void expect_error(const std::string& text, const std::vector<std::string>& pieces,
                         const std::vector<Override>& overrides = {}) {
  const std::string msg = error_of(text, overrides);
  ASSERT_FALSE(msg.empty()) << "expected an InputError for:\n" << text;
  for (const auto& piece : pieces)
    EXPECT_NE(msg.find(piece), std::string::npos) << "message: " << msg << "\nmissing: " << piece;
}

}  // namespace sandflow::test
