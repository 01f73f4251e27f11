// The two kinds of error the library raises; it never prints and never exits (docs/style.md).
#pragma once

#include <stdexcept>
#include <string>
#include <string_view>

namespace sandflow {

/// Bad input from a user: a scene file, an option, a mesh. The app prints what() and exits 2.
/// The message already names the place ("scenes/floor.toml:14:3: material.restitution = ...").
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The simulation left its valid range (non-finite values, runaway overlaps). Exit status 3.
class SimulationError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// An output could not be written (unwritable folder, full disk). Exit status 4.
class OutputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A library's message without its leading tag: nlohmann::json's "[json.exception.type_error.302]
/// type must be string" is "type must be string", the user's words without the library's.
inline std::string without_library_tag(std::string_view what) {
  const std::size_t end = what.find("] ");
  return std::string(!what.empty() && what.front() == '[' && end != std::string_view::npos
                         ? what.substr(end + 2)
                         : what);
}

}  // namespace sandflow
