// A small file system for the tests of a full disk: a tmpfs mounted on a folder of the test's
// own, unmounted when the test ends. Mounting needs root; elsewhere the test skips.
#pragma once

#include <sys/mount.h>
#include <unistd.h>

#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

namespace sandflow::test {

class SmallDisk {
 public:
  /// Mounts a tmpfs of `bytes` on `dir` (made if needed); see mounted() and why_not().
  SmallDisk(const std::filesystem::path& dir, std::uintmax_t bytes) : dir_(dir) {
    if (::geteuid() != 0) {
      why_not_ = "mounting a small file system needs root";
      return;
    }
    std::filesystem::create_directories(dir_);
    const std::string command = "mount -t tmpfs -o size=" + std::to_string(bytes) + " tmpfs " +
                                dir_.string() + " 2>/dev/null";
    if (std::system(command.c_str()) != 0) {
      why_not_ = "cannot mount a tmpfs here";
      return;
    }
    mounted_ = true;
  }
  ~SmallDisk() {
    if (mounted_) ::umount2(dir_.c_str(), MNT_DETACH);
  }
  SmallDisk(const SmallDisk&) = delete;
  SmallDisk& operator=(const SmallDisk&) = delete;

  bool mounted() const { return mounted_; }
  const std::string& why_not() const { return why_not_; }

  /// Fills the disk with the file `filler` until `left` bytes are free (false if fewer were);
  /// removing `filler` makes the room again.
  bool fill_to(std::uintmax_t left) const {
    const std::uintmax_t available = std::filesystem::space(dir_).available;
    if (available <= left) return false;
    std::ofstream(dir_ / "filler", std::ios::binary) << std::string(available - left, 'x');
    return true;
  }
  std::filesystem::path filler() const { return dir_ / "filler"; }

 private:
  std::filesystem::path dir_;
  bool mounted_ = false;
  std::string why_not_;
};

}  // namespace sandflow::test
