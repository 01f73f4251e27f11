// The command's messages on stderr, and the standard streams it starts with. A message that cannot
// be written (stderr on a full disk, or closed) is lost; the work it reports on goes on.
#pragma once

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <string>
#include <utility>

#include <fmt/format.h>

namespace sandflow {

/// fmt::print(stderr, ...) without its exception: fmt throws when the write fails, which stopped a
/// run at its first progress line (stderr on /dev/full) and aborted one from inside main's own
/// error handler (a throw while the last one was handled).
template <typename... Args>
void print_to_stderr(fmt::format_string<Args...> format, Args&&... args) {
  const std::string text = fmt::format(format, std::forward<Args>(args)...);
  if (std::fwrite(text.data(), 1, text.size(), stderr) != text.size()) std::clearerr(stderr);
}

/// Opens /dev/null on each of stdin, stdout and stderr that the command was started without
/// (`>&-`): else the next file opened takes that descriptor (a run's folder lock, its stats.csv)
/// and what is printed goes into it.
inline void open_missing_standard_streams() {
  for (int fd = 0; fd <= 2; ++fd) {
    if (fcntl(fd, F_GETFD) != -1 || errno != EBADF) continue;
    const int opened = ::open("/dev/null", fd == 0 ? O_RDONLY : O_WRONLY);
    if (opened >= 0 && opened != fd) {  // (the lowest free descriptor: fd itself)
      dup2(opened, fd);
      ::close(opened);
    }
  }
}

}  // namespace sandflow
