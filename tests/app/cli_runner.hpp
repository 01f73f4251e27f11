// Running the sandflow binary from a test: a scratch folder per test and the command's exit status
// with its output, and a tiny scene. Shared by the tests of the command's subcommands.
#pragma once

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <system_error>

#include <fmt/format.h>

namespace sandflow_test {

namespace fs = std::filesystem;

/// The running test's "Suite.Name" and process id, for names that must not clash between
/// parallel tests, nor between test runs of two build folders at once.
inline std::string test_id() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  return std::string(info->test_suite_name()) + "." + info->name() + "." +
         std::to_string(::getpid());
}

/// A scratch folder for one test, removed when the test ends.
struct Sandbox {
  fs::path dir;
  Sandbox() {
    dir = fs::temp_directory_path() /
          ("sandflow_cli_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) +
           "_" + test_id());
    fs::remove_all(dir);
    fs::create_directories(dir);
  }
  ~Sandbox() { fs::remove_all(dir); }
  fs::path write(const std::string& name, const std::string& text) const {
    std::ofstream(dir / name) << text;
    return dir / name;
  }
};

/// Runs the command (behind `wrapper`, e.g. "timeout 30"); returns its exit status, with
/// stdout+stderr in `output`.
inline int run_sandflow(const std::string& args, std::string* output = nullptr,
                        const std::string& wrapper = "") {
  // one log per test: ctest runs tests in parallel processes
  const std::string log =
      (fs::temp_directory_path() / ("sandflow_cli_" + test_id() + ".log")).string();
  const int rc =
      std::system((wrapper + " " + SANDFLOW_BINARY + " " + args + " > " + log + " 2>&1").c_str());
  if (output) {
    std::stringstream ss;
    ss << std::ifstream(log).rdbuf();
    *output = ss.str();
  }
  std::error_code ec;
  fs::remove(log, ec);  // leave nothing behind in the system's temporary folder
  return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

/// Starts the binary with `args` (output to `log`), with files limited to `max_file_bytes`;
/// `env` ("env -u X Y=1") sets its environment. Its pid is the binary's: signals reach it.
inline pid_t spawn(const std::string& args, const fs::path& log,
                   rlim_t max_file_bytes = RLIM_INFINITY, const std::string& env = "") {
  const std::string command = "exec " + env + " " + SANDFLOW_BINARY + " " + args;
  const std::string log_path = log.string();
  const pid_t pid = fork();
  if (pid == 0) {  // (only async-signal-safe calls until exec)
    const int fd = ::open(log_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    dup2(fd, 1);
    dup2(fd, 2);
    if (max_file_bytes != RLIM_INFINITY) {
      const rlimit rl{max_file_bytes, max_file_bytes};
      setrlimit(RLIMIT_FSIZE, &rl);
    }
    execl("/bin/sh", "sh", "-c", command.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  return pid;
}

/// Waits for `pid`; its exit status, or 128 + the signal that ended it.
inline int wait_for(pid_t pid) {
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

/// The whole text of a file ("" when it cannot be read).
inline std::string read_text(const fs::path& path) {
  std::stringstream ss;
  ss << std::ifstream(path).rdbuf();
  return ss.str();
}

/// A scene's tables up to a floor at z = 0 (1 cm grains, k_n given, 30 frames a second), for the
/// tiny scenes below to add their emitter to.
inline std::string tiny_floor_scene(const std::string& name, double fps = 30) {
  return fmt::format(R"(
[scene]
name = "{}"
[material]
diameter = 0.01
k_n = 1.0e4
[output]
fps = {}
[[geometry]]
type = "plane"
)",
                     name, fps);
}

/// The command tests' tiny scene: a block of `count` 1 cm grains, `height` tall and centred at
/// `z`, settling on a floor; a fraction of a second a run.
inline std::string tiny_block_scene(int count, double fps = 30, double z = 0.05,
                                    double height = 0.06) {
  return tiny_floor_scene("tiny", fps) + fmt::format(R"([[emitter]]
type = "block"
count = {}
center = [0.0, 0.0, {}]
size = [0.1, 0.1, {}]
)",
                                                     count, z, height);
}

/// `count` grains of 1 cm poured at `rate` from a disk of 4 cm radius `z` above a floor; `emitter`
/// adds keys to the pour, `tables` tables after it.
inline std::string tiny_pour_scene(int count, double z, double rate,
                                   const std::string& emitter = "",
                                   const std::string& tables = "") {
  return tiny_floor_scene("tiny pour") + fmt::format(R"([[emitter]]
type = "pour"
count = {}
center = [0.0, 0.0, {}]
radius = 0.04
rate = {}
{}
{})",
                                                     count, z, rate, emitter, tables);
}

/// A tetrahedron as an ASCII STL, 0.1 m across, its apex at height `apex` [m]; `face_twice`
/// gives one of its faces twice (the same surface, another mesh).
inline std::string tetrahedron_stl(double apex, bool face_twice = false) {
  const std::string v[4] = {"0 0 0", "0.1 0 0", "0 0.1 0", fmt::format("0.03 0.03 {}", apex)};
  const int faces[5][3] = {{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {2, 0, 3}, {0, 1, 3}};
  std::string s = "solid tet\n";
  for (int k = 0; k < (face_twice ? 5 : 4); ++k)
    s += fmt::format(
        "facet normal 0 0 0\nouter loop\nvertex {}\nvertex {}\nvertex {}\nendloop\n"
        "endfacet\n",
        v[faces[k][0]], v[faces[k][1]], v[faces[k][2]]);
  return s + "endsolid tet\n";
}

}  // namespace sandflow_test
