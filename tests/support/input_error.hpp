// The message of the InputError a piece of code throws: what the readers' tests compare.
#pragma once

#include <string>

#include "core/error.hpp"

namespace sandflow::test {

/// The message of the InputError `f` throws ("" when it throws none).
template <class F>
std::string input_error(F f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

}  // namespace sandflow::test
