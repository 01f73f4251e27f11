// Finding and running other programs (process.hpp): PATH lookup, and fork, exec and wait.

#include "core/process.hpp"

#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <string_view>
#include <thread>

#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include "core/atomic_file.hpp"
#include "core/error.hpp"

namespace sandflow {

namespace {
std::atomic<const volatile std::sig_atomic_t*> g_stop_flag{nullptr};
}  // namespace

void stop_children_on(const volatile std::sig_atomic_t* flag) {
  g_stop_flag = flag;
}

std::string find_program(const std::string& name) {
  const char* path_env = std::getenv("PATH");
  std::string_view dirs = path_env ? path_env : "/usr/local/bin:/usr/bin:/bin";
  while (!dirs.empty()) {
    const std::size_t colon = dirs.find(':');
    std::string dir(dirs.substr(0, colon));
    dirs = colon == std::string_view::npos ? std::string_view{} : dirs.substr(colon + 1);
    if (dir.empty()) dir = ".";
    const std::string candidate = dir + "/" + name;
    if (::access(candidate.c_str(), X_OK) == 0 && !std::filesystem::is_directory(candidate))
      return candidate;
  }
  return "";
}

std::string run_logged(std::vector<std::string> args, const std::string& work_dir,
                       const std::string& log_path, const std::string& what,
                       std::int64_t* peak_bytes) {
  // Everything the child needs is prepared before fork: it may only call async-signal-safe
  // functions (the parent has other threads).
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  errno = 0;
  const int log_fd = ::open(log_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (log_fd < 0) throw OutputError(log_path + ": cannot create: " + system_reason(errno));
  const pid_t parent = ::getpid();
  const pid_t pid = ::fork();
  if (pid < 0) {
    const int err = errno;
    ::close(log_fd);
    return "cannot start " + what + ": " + system_reason(err);
  }
  if (pid == 0) {
    // the child ends with sandflow: killed (kill -9, a second Ctrl-C), sandflow leaves no POV-Ray
    // running on, writing pictures into a folder no one watches (checked after the call: sandflow
    // may have died before it)
    ::prctl(PR_SET_PDEATHSIG, SIGKILL);
    if (::getppid() != parent) ::_exit(1);
    // (an ignored signal stays ignored across exec: the child gets the defaults sandflow changed)
    ::signal(SIGPIPE, SIG_DFL);
    ::signal(SIGXFSZ, SIG_DFL);
    const int null_fd = ::open("/dev/null", O_RDONLY);
    if (null_fd >= 0) ::dup2(null_fd, 0);
    ::dup2(log_fd, 1);
    ::dup2(log_fd, 2);
    if (::chdir(work_dir.c_str()) != 0) ::_exit(126);
    ::execv(argv[0], argv.data());
    ::_exit(127);
  }
  ::close(log_fd);
  int status = 0;
  bool stopped = false;
  struct rusage usage {};
  if (const volatile std::sig_atomic_t* stop = g_stop_flag.load()) {
    // polled: a signal handler's flag cannot wake a blocking wait (SA_RESTART restarts it)
    for (;;) {
      const pid_t got = ::wait4(pid, &status, WNOHANG, &usage);
      if (got == pid || (got < 0 && errno != EINTR)) break;
      if (*stop != 0 && !stopped) {
        ::kill(pid, SIGTERM);
        stopped = true;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
  } else {
    while (::wait4(pid, &status, 0, &usage) < 0 && errno == EINTR) {
    }
  }
  if (peak_bytes) *peak_bytes = static_cast<std::int64_t>(usage.ru_maxrss) * 1024;  // (kB)
  if (stopped) return what + " was stopped";
  if (WIFSIGNALED(status))
    return what + " was killed by signal " + std::to_string(WTERMSIG(status));
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0)
    return what + " failed with exit status " + std::to_string(WEXITSTATUS(status));
  return "";
}

}  // namespace sandflow
