#include "core/atomic_file.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <utility>

#include <fmt/format.h>

#include "core/error.hpp"

namespace sandflow {

namespace fs = std::filesystem;

std::string system_reason(int err) {
  return err != 0 ? std::string(std::strerror(err)) : std::string("unknown I/O error");
}

namespace {

// Closes `fd` (when open), removes the temporary file and throws "PATH: WHAT: REASON".
[[noreturn]] void fail(const std::string& path, const std::string& tmp, int fd,
                       const std::string& what, int err) {
  if (fd >= 0) ::close(fd);
  ::unlink(tmp.c_str());
  throw OutputError(fmt::format("{}: {}: {}", path, what, system_reason(err)));
}

// The end of every atomic write: `tmp`, written whole and still open as `fd` (or closed already:
// fd < 0), becomes `path`.
void commit_tmp(const std::string& path, const std::string& tmp, int fd, Sync sync) {
  if (sync == Sync::Now) {
    if (fd < 0) fd = ::open(tmp.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0 || ::fsync(fd) != 0) fail(path, tmp, fd, "cannot write", errno);
  }
  if (fd >= 0 && ::close(fd) != 0) fail(path, tmp, -1, "cannot write", errno);
  if (std::rename(tmp.c_str(), path.c_str()) != 0)
    fail(path, tmp, -1, "cannot rename " + tmp, errno);
  if (sync == Sync::Now) {
    const fs::path parent = fs::path(path).parent_path();
    sync_dir(parent.empty() ? "." : parent.string());
  }
}

}  // namespace

AtomicFile::AtomicFile(std::string path, Sync sync)
    : path_(std::move(path)), tmp_(path_ + ".tmp"), sync_(sync) {
  fd_ = ::open(tmp_.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
  if (fd_ < 0) {
    done_ = true;
    throw OutputError(fmt::format("{}: cannot create {}: {}", path_, tmp_, system_reason(errno)));
  }
}

AtomicFile::~AtomicFile() {
  if (done_) return;
  ::close(fd_);
  ::unlink(tmp_.c_str());
}

void AtomicFile::write(std::string_view bytes) {
  for (std::size_t written = 0; written < bytes.size();) {
    const ssize_t k = ::write(fd_, bytes.data() + written, bytes.size() - written);
    if (k < 0 && errno == EINTR) continue;
    if (k <= 0) {
      done_ = true;
      fail(path_, tmp_, std::exchange(fd_, -1), "cannot write", k < 0 ? errno : EIO);
    }
    written += static_cast<std::size_t>(k);
  }
}

void AtomicFile::commit() {
  done_ = true;
  commit_tmp(path_, tmp_, std::exchange(fd_, -1), sync_);
}

void write_file_atomic(const std::string& path, std::string_view bytes, Sync sync) {
  AtomicFile file(path, sync);
  file.write(bytes);
  file.commit();
}

void write_file_atomic_by_name(const std::string& path,
                               const std::function<void(const std::string& tmp)>& write,
                               Sync sync) {
  const std::string tmp = path + ".tmp";
  try {
    write(tmp);
  } catch (...) {
    ::unlink(tmp.c_str());
    throw;
  }
  commit_tmp(path, tmp, -1, sync);
}

void sync_file(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0 || ::fsync(fd) != 0) {
    const int err = errno;
    if (fd >= 0) ::close(fd);
    throw OutputError(fmt::format("{}: cannot flush to the disk: {}", path, system_reason(err)));
  }
  ::close(fd);
}

void sync_dir(const std::string& dir) {
  const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  // (some file systems cannot flush a folder: EINVAL says so, and there is nothing to do)
  if (fd < 0 || (::fsync(fd) != 0 && errno != EINVAL)) {
    const int err = errno;
    if (fd >= 0) ::close(fd);
    throw OutputError(
        fmt::format("{}: cannot flush the folder to the disk: {}", dir, system_reason(err)));
  }
  ::close(fd);
}

}  // namespace sandflow
