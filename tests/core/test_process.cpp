// The one process runner (core/process.hpp): programs are found on PATH, run in their folder with
// their output in the log and nothing on stdin, and every way a run can end is told apart.
#include "core/process.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include <unistd.h>

#include "core/error.hpp"
#include "support/scratch.hpp"

namespace sandflow {
namespace {

namespace fs = std::filesystem;

class ProcessTest : public test::ScratchTest {
 protected:
  void SetUp() override {
    sh_ = find_program("sh");
    ASSERT_FALSE(sh_.empty()) << "sh is not on PATH";
  }

  // Runs `sh -c script` in dir_, its output to dir_/log.
  std::string run_sh(const std::string& script) const {
    return run_logged({sh_, "-c", script}, dir_.string(), log(), "sh");
  }
  std::string log() const { return (dir_ / "log").string(); }
  std::string log_text() const { return test::read_bytes(log()); }

  std::string sh_;
};

TEST_F(ProcessTest, FindsProgramsOnPathAndNothingElse) {
  EXPECT_EQ(fs::path(sh_).filename(), "sh") << sh_;
  EXPECT_EQ(find_program("sandflow-no-such-program"), "");
}

TEST_F(ProcessTest, SuccessWritesStdoutAndStderrToTheLog) {
  EXPECT_EQ(run_sh("echo out; echo err >&2"), "");
  EXPECT_EQ(log_text(), "out\nerr\n");
}

TEST_F(ProcessTest, RunsInTheWorkFolderWithNothingOnStdin) {
  // cat returns at once: stdin is /dev/null, not the test's terminal
  EXPECT_EQ(run_sh("cat; pwd -P"), "");
  EXPECT_EQ(log_text(), fs::canonical(dir_).string() + "\n");
}

TEST_F(ProcessTest, TellsExitStatusSignalAndMissingProgramApart) {
  EXPECT_EQ(run_sh("exit 3"), "sh failed with exit status 3");
  EXPECT_EQ(run_sh("kill -9 $$"), "sh was killed by signal 9");
  EXPECT_EQ(run_logged({(dir_ / "missing").string()}, dir_.string(), log(), "missing"),
            "missing failed with exit status 127");
  EXPECT_EQ(run_logged({sh_, "-c", "true"}, (dir_ / "no-folder").string(), log(), "sh"),
            "sh failed with exit status 126");
}

TEST_F(ProcessTest, AnUncreatableLogIsAnOutputError) {
  EXPECT_THROW(run_logged({sh_, "-c", "true"}, dir_.string(), (dir_ / "no" / "log").string(), "sh"),
               OutputError);
}

}  // namespace
}  // namespace sandflow
