// Assertions: checks of the program's own invariants, the second kind of error of docs/style.md.
// A failed assertion is a bug of sandflow, never bad input (that is an InputError) nor a blow-up
// of the physics (a SimulationError, which the guards report with the step).
//
// They are compiled in when SANDFLOW_ASSERTIONS is defined: CMake defines it for the Debug and
// RelWithDebInfo builds and for the sanitizer build (SANDFLOW_SANITIZE), not for Release. In
// Release SANDFLOW_ASSERT evaluates nothing and emits no code (its condition is only type-checked),
// so a Release build computes bit for bit what it computed without them; a check too costly to
// write as one condition goes in `if constexpr (kAssertions)`.
//
// A failure prints "file:line: assertion failed: condition: message" to stderr and aborts: the
// one place the library prints, because a broken invariant leaves no state worth handing back.
// The message is evaluated only on failure, so it may be built with fmt::format.
#pragma once

#ifdef SANDFLOW_ASSERTIONS
#include <cstdio>
#include <cstdlib>
#include <string_view>
#endif

namespace sandflow {

#ifdef SANDFLOW_ASSERTIONS
inline constexpr bool kAssertions = true;

namespace detail {
[[noreturn, gnu::cold, gnu::noinline]] inline void assertion_failed(const char* file, int line,
                                                                    const char* condition,
                                                                    std::string_view message) {
  std::fprintf(stderr, "%s:%d: assertion failed: %s: %.*s\n", file, line, condition,
               static_cast<int>(message.size()), message.data());
  std::fflush(stderr);
  std::abort();
}
}  // namespace detail

#define SANDFLOW_ASSERT(cond, message)                                            \
  do {                                                                            \
    if (!(cond)) [[unlikely]]                                                     \
      ::sandflow::detail::assertion_failed(__FILE__, __LINE__, #cond, (message)); \
  } while (false)
#else
inline constexpr bool kAssertions = false;

// (sizeof: the condition is not evaluated, but a variable it alone reads still counts as used)
#define SANDFLOW_ASSERT(cond, message) static_cast<void>(sizeof(!(cond)))
#endif

}  // namespace sandflow
