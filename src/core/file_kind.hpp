// What kind of thing a path names, so that a reader refuses a FIFO or a device by its type
// before it opens it: opening a FIFO blocks until a writer comes, and a device such as /dev/zero
// never ends.
#pragma once

#include <sys/stat.h>
#include <unistd.h>

#include <string>
#include <string_view>

#include "core/error.hpp"

namespace sandflow {

/// "" for a regular file (or a path that is not there: the reader's own open then says so), else
/// what it is: "a folder", "a FIFO", "a character device", ...
inline std::string special_file_kind(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0 || S_ISREG(st.st_mode)) return "";
  if (S_ISDIR(st.st_mode)) return "a folder";
  if (S_ISFIFO(st.st_mode)) return "a FIFO";
  if (S_ISCHR(st.st_mode)) return "a character device";
  if (S_ISBLK(st.st_mode)) return "a block device";
  if (S_ISSOCK(st.st_mode)) return "a socket";
  return "not a regular file";
}

/// Throws InputError "PATH: the WHAT is a FIFO, not a file" unless `path` is a regular file (or
/// is not there).
inline void refuse_special_file(const std::string& path, const std::string& what) {
  const std::string kind = special_file_kind(path);
  if (!kind.empty()) throw InputError(path + ": the " + what + " is " + kind + ", not a file");
}

/// A name that makes exactly one folder inside another: not empty, not . or .., no / or \.
inline bool is_plain_folder_name(std::string_view name) {
  return !name.empty() && name != "." && name != ".." &&
         name.find_first_of("/\\") == std::string_view::npos;
}

/// Throws InputError "PATH: the WHAT is a link to nothing (TARGET)" when `path` is a symbolic link
/// that leads nowhere (a missing target, a loop): a reader that takes a missing file for "not made
/// yet" must not take a link to storage that is not mounted for it.
inline void refuse_broken_link(const std::string& path, const std::string& what) {
  struct stat st {};
  if (::lstat(path.c_str(), &st) != 0 || !S_ISLNK(st.st_mode) || ::stat(path.c_str(), &st) == 0)
    return;
  std::string target(4096, '\0');
  const ssize_t n = ::readlink(path.c_str(), target.data(), target.size());
  target.resize(n > 0 ? static_cast<std::size_t>(n) : 0);
  throw InputError(path + ": the " + what + " is a link to nothing (" + target +
                   "): mount or restore what it leads to, or remove the link");
}

}  // namespace sandflow
