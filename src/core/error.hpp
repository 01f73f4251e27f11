// The two kinds of error the library raises; it never prints and never exits (docs/style.md).
#pragma once

#include <stdexcept>
#include <string>

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

}  // namespace sandflow
