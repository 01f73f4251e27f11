// An exclusive lock on a run's output folder, so that two runs (or a run and a resume, or two
// comparisons) never write into one folder at once: the second is refused, told which process
// holds the folder, before it touches anything there.
#pragma once

#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace sandflow {

/// Who holds a locked folder, for the message that refuses the next one.
struct FolderUse {
  std::string_view holder = "run";  ///< "another sandflow HOLDER"
  std::string_view advice = "wait for it to end, stop it, or choose another output folder";
};

/// Holds the lock on a folder while it lives. The lock is flock(2) on the folder itself: no file
/// is added to the folder, and the kernel drops the lock when the holder ends, however it ends
/// (kill -9 included), so a stale lock never stands in the way of a resume. It belongs to this
/// object's open file description: a second FolderLock on the same folder is refused even in the
/// same process.
class FolderLock {
 public:
  /// Creates `dir` (and its parents) if needed and locks it. Throws InputError when `dir` is
  /// something other than a folder, or naming the process that holds it (its pid and command
  /// line, where /proc tells them); OutputError when the folder cannot be created or opened.
  explicit FolderLock(const std::string& dir, const FolderUse& use = {});
  ~FolderLock();
  FolderLock(const FolderLock&) = delete;
  FolderLock& operator=(const FolderLock&) = delete;

 private:
  int fd_ = -1;
};

/// Locks every folder named render/ within `depth` levels under `dir` (a run's is one level down, a
/// comparison's seed-2/dem/render three), for as long as the locks live: taken before --force
/// removes the runs there, so that a render drawing into one is not left writing into a folder
/// removed under it. Throws InputError naming the render that holds one.
std::vector<std::unique_ptr<FolderLock>> lock_render_folders(const std::string& dir, int depth);

}  // namespace sandflow
