// SANDFLOW_ASSERT (src/core/assert.hpp): in a build with assertions a failure names the place,
// the condition and the message and aborts; in Release the condition is not even evaluated.
#include <gtest/gtest.h>

#include <string>

#include "core/assert.hpp"

namespace sandflow {
namespace {

TEST(Assertions, AFailureAbortsNamingThePlaceTheConditionAndTheMessage) {
  if constexpr (!kAssertions) GTEST_SKIP() << "a Release build: assertions are off";
  GTEST_FLAG_SET(death_test_style, "threadsafe");  // (OpenMP's threads may be running)
  const int three = 3;
  EXPECT_DEATH(SANDFLOW_ASSERT(1 + 1 == three, "arithmetic, " + std::to_string(three)),
               "test_assert\\.cpp:[0-9]+: assertion failed: 1 \\+ 1 == three: arithmetic, 3");
  SANDFLOW_ASSERT(1 + 1 == 2, "not evaluated");  // a condition that holds: nothing happens
}

TEST(Assertions, AReleaseBuildEvaluatesNothing) {
  if constexpr (kAssertions) GTEST_SKIP() << "a build with assertions";
  int evaluated = 0;
  SANDFLOW_ASSERT(++evaluated < 0, "never");
  EXPECT_EQ(evaluated, 0);
}

}  // namespace
}  // namespace sandflow
