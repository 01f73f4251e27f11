#include "io/folder_lock.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>

#include <fmt/format.h>

#include "core/error.hpp"
#include "core/file_kind.hpp"

namespace sandflow {

namespace {

namespace fs = std::filesystem;

// The process holding an flock on the inode `ino`, from /proc/locks ("1: FLOCK  ADVISORY  WRITE
// 4242 fd:01:1234 0 EOF"), with its command line: "pid 4242: sandflow run ...", or "" when
// /proc does not tell.
std::string lock_holder(ino_t ino) {
  std::ifstream locks("/proc/locks");
  std::string line;
  const std::string inode = ":" + std::to_string(ino);
  while (std::getline(locks, line)) {
    std::istringstream in(line);
    std::string id, kind, mode, access, pid, device;
    // (a process waiting for a lock has "->" where the kind stands: skipped)
    if (!(in >> id >> kind >> mode >> access) || kind != "FLOCK") continue;
    if (!(in >> pid >> device) || device.size() < inode.size() ||
        device.compare(device.size() - inode.size(), inode.size(), inode) != 0)
      continue;
    std::ifstream cmdline("/proc/" + pid + "/cmdline", std::ios::binary);
    std::string args((std::istreambuf_iterator<char>(cmdline)), std::istreambuf_iterator<char>());
    for (char& c : args)
      if (c == '\0') c = ' ';
    while (!args.empty() && args.back() == ' ') args.pop_back();
    return args.empty() ? "pid " + pid : fmt::format("pid {}: {}", pid, args);
  }
  return "";
}

}  // namespace

FolderLock::FolderLock(const std::string& dir, const FolderUse& use) {
  std::error_code ec;
  if (fs::exists(dir, ec) && !fs::is_directory(dir, ec))
    throw InputError(fmt::format("{}: the output path exists and is not a folder", dir));
  refuse_broken_link(dir, "output folder");
  // (a file on the way is the user's mistake, not an output error: out/afile/sub)
  for (fs::path up = fs::path(dir).parent_path(); !up.empty() && up != up.root_path();
       up = up.parent_path())
    if (fs::exists(up, ec) && !fs::is_directory(up, ec))
      throw InputError(fmt::format("{}: {} is a file, not a folder", dir, up.string()));
  fs::create_directories(dir, ec);
  if (ec) throw OutputError(fmt::format("{}: cannot create the output folder: {}", dir, ec.message()));
  fd_ = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd_ < 0)
    throw OutputError(fmt::format("{}: cannot open the output folder: {}", dir, std::strerror(errno)));
  if (::flock(fd_, LOCK_EX | LOCK_NB) == 0) return;
  const int err = errno;
  struct stat st {};
  const std::string holder = ::fstat(fd_, &st) == 0 ? lock_holder(st.st_ino) : "";
  ::close(fd_);
  fd_ = -1;
  if (err != EWOULDBLOCK)
    throw OutputError(fmt::format("{}: cannot lock the output folder: {}", dir, std::strerror(err)));
  throw InputError(fmt::format("{}: the output folder is in use by another sandflow {}{}; {}", dir,
                               use.holder, holder.empty() ? "" : " (" + holder + ")", use.advice));
}

FolderLock::~FolderLock() {
  if (fd_ >= 0) ::close(fd_);  // (closing drops the lock)
}

std::vector<std::unique_ptr<FolderLock>> lock_render_folders(const std::string& dir, int depth) {
  std::vector<std::unique_ptr<FolderLock>> locks;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    const std::string name = e.path().filename().string();
    if (!e.is_directory(ec) || e.is_symlink(ec) || name == "frames" || name == "heightfield")
      continue;
    if (name == "render") {
      locks.push_back(std::make_unique<FolderLock>(
          e.path().string(),
          FolderUse{"render", "wait for it to end or stop it, then replace the run"}));
    } else if (depth > 1) {
      for (auto& lock : lock_render_folders(e.path().string(), depth - 1))
        locks.push_back(std::move(lock));
    }
  }
  return locks;
}

}  // namespace sandflow
