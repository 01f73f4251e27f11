// Golden numbers: the final state hash of a tiny scene (tests/regression/golden.toml, 500 grains,
// one second) in each mode, run by the sandflow command from start to end.
#include <gtest/gtest.h>

#include <fstream>
#include <string>

#include <nlohmann/json.hpp>

#include "../app/cli_runner.hpp"

namespace {

using sandflow_test::run_sandflow;
using sandflow_test::Sandbox;

// What these guard: any unintended change of the physics or of the order of floating-point
// operations — the contact law, the integrator, the order of the pair lists and of the sums, the
// emitters' random draws, the height field and the transitions between the layers. The state
// hash (World::state_hash) covers every grain's id, position, velocity and spin to the last bit,
// so a refactoring that reorders two additions moves it too: such a change must either keep the
// hash or be a change of the physics on purpose. The hash does not depend on the thread count
// (docs/design.md §3, and the determinism tests with 5,000 grains); the runs ask for 2 threads
// all the same (at 500 grains each loop stays on one: kParallelMinGrains). The assertions only read
// the state, so Release and the builds with them agree; the constants hold for the default flags
// (not SANDFLOW_NATIVE, whose -march=native may fuse multiplications and additions) with GCC 12 and
// glibc (another libm may round exp, log or atan differently).
//
// When the physics changes on purpose, print the new hashes from the source folder with
//   build/tests/sandflow_tests --gtest_filter='Golden.*'
// (a failure names the hash it got), or those of one mode with the command itself (one line):
//   build/sandflow run tests/regression/golden.toml --mode surface --threads 2 --export none
//       --out /tmp/golden --force 2>/dev/null | grep 'state hash'
// put them below, and say in the commit why the state changed. Only the mode whose physics
// changed should move: a change of the surface method leaves kDemHash alone.
constexpr const char* kDemHash = "ba77f1f81ecc4983";
constexpr const char* kSurfaceHash = "6ce483f403af355b";

/// Runs the golden scene in `mode` with 2 threads; returns its summary.json.
nlohmann::json run_golden(const std::string& mode) {
  Sandbox box;
  const auto out = box.dir / "out";
  const std::string scene = std::string(SANDFLOW_SOURCE_DIR) + "/tests/regression/golden.toml";
  std::string log;
  const int rc = run_sandflow(
      "run " + scene + " --mode " + mode + " --threads 2 --export none --out " + out.string(),
      &log);
  EXPECT_EQ(rc, 0) << log;
  if (rc != 0) return {};
  return nlohmann::json::parse(std::ifstream(out / "summary.json"));
}

TEST(Golden, DemModeStateHash) {
  const nlohmann::json s = run_golden("dem");
  ASSERT_TRUE(s.contains("state_hash"));
  EXPECT_EQ(s["n_total"], 500);
  EXPECT_EQ(s["threads"], 2);
  EXPECT_EQ(s["state_hash"], kDemHash)
      << "the plain-DEM state changed; if on purpose, kDemHash = \""
      << s["state_hash"].get<std::string>() << "\" (see the comment above it)";
}

TEST(Golden, SurfaceModeStateHash) {
  const nlohmann::json s = run_golden("surface");
  ASSERT_TRUE(s.contains("state_hash"));
  EXPECT_EQ(s["n_total"], 500);
  EXPECT_EQ(s["threads"], 2);
  // the scene guards the surface method only while the method acts in it: grains froze
  EXPECT_GT(s["n_interface_final"].get<int>() + s["n_static_final"].get<int>(), 0);
  EXPECT_EQ(s["state_hash"], kSurfaceHash)
      << "the surface-mode state changed; if on purpose, kSurfaceHash = \""
      << s["state_hash"].get<std::string>() << "\" (see the comment above it)";
}

}  // namespace
