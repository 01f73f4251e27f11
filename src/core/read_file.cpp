#include "core/read_file.hpp"

#include <sys/stat.h>

#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <vector>

#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "core/file_kind.hpp"

namespace sandflow {

namespace {

struct FileCloser {
  void operator()(std::FILE* f) const { std::fclose(f); }
};

[[noreturn]] void too_large(const std::string& path, const std::string& what,
                            std::size_t max_bytes) {
  throw InputError(path + ": the " + what + " is larger than the limit of " +
                   std::to_string(max_bytes) + " bytes");
}

}  // namespace

std::string read_whole_file(const std::string& path, std::string_view what, std::size_t max_bytes) {
  const std::string name(what);
  refuse_special_file(path, name);
  errno = 0;
  const std::unique_ptr<std::FILE, FileCloser> fp(std::fopen(path.c_str(), "rb"));
  if (!fp) throw InputError(path + ": cannot open the " + name + ": " + system_reason(errno));
  std::string bytes;
  // a file already over the limit is refused unread; one that grows while it is read, at the limit
  struct stat st {};
  if (::fstat(::fileno(fp.get()), &st) == 0 && st.st_size > 0) {
    if (static_cast<std::uintmax_t>(st.st_size) > max_bytes) too_large(path, name, max_bytes);
    bytes.reserve(static_cast<std::size_t>(st.st_size));
  }
  // off the stack: a command's whole stack may be 64 KiB (`ulimit -s 64`)
  std::vector<char> piece(std::size_t{1} << 16);
  std::size_t got = 0;
  errno = 0;
  while ((got = std::fread(piece.data(), 1, piece.size(), fp.get())) > 0) {
    if (got > max_bytes - bytes.size()) too_large(path, name, max_bytes);
    bytes.append(piece.data(), got);
  }
  if (std::ferror(fp.get()))
    throw InputError(path + ": cannot read the " + name + ": " +
                     system_reason(errno ? errno : EIO));
  return bytes;
}

std::optional<std::string> read_file_if_present(const std::string& path, std::string_view what,
                                                std::size_t max_bytes) {
  // (not found only: a folder that cannot be searched is read_whole_file's to say)
  std::error_code ec;
  if (std::filesystem::status(path, ec).type() == std::filesystem::file_type::not_found)
    return std::nullopt;
  return read_whole_file(path, what, max_bytes);
}

}  // namespace sandflow
