// Writing a file whole or not at all: the one atomic file writer (docs/style.md, "One way to do a
// thing"), used for every file the library writes.
//
// The bytes go to PATH.tmp, which is renamed over PATH when they are all there, so that a reader
// never sees half a file and a failed write leaves the old file as it was. A durable commit
// (Sync::Now) also flushes the file to the disk (fsync) before the rename and the folder after it,
// so that a crash or a power cut leaves either the old file or the new one, never half of one:
// summaries, checkpoints, records and exports are written so. Frames, POV-Ray scenes and the
// height-field PNGs are only renamed (Sync::Later): a run flushes the files written since its last
// checkpoint before it writes the next one (sync_file, sync_dir in apps/run.cpp), one flush per
// file per checkpoint rather than one per file as it is written.
//
// A write that fails removes its temporary file and throws OutputError naming PATH and the
// system's reason: "PATH: cannot create PATH.tmp: REASON", "PATH: cannot write: REASON",
// "PATH: cannot rename PATH.tmp: REASON".
#pragma once

#include <functional>
#include <string>
#include <string_view>

namespace sandflow {

/// The system's words for an errno value ("No space left on device"); "unknown I/O error" for 0.
std::string system_reason(int err);

/// Whether a commit flushes the file and its folder to the disk, or leaves that to the caller.
enum class Sync { Now, Later };

/// A file written as a stream to PATH.tmp, which becomes PATH at commit(). Destroyed uncommitted
/// (an exception on the way), it removes PATH.tmp.
class AtomicFile {
 public:
  /// Creates (or truncates) PATH.tmp. Throws OutputError.
  explicit AtomicFile(std::string path, Sync sync = Sync::Now);
  ~AtomicFile();
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  /// Appends `bytes` (no buffering: pass large pieces). Throws OutputError.
  void write(std::string_view bytes);
  /// Flushes the file to the disk (Sync::Now), closes it, renames PATH.tmp over PATH and flushes
  /// the folder (Sync::Now). Throws OutputError.
  void commit();

 private:
  std::string path_, tmp_;
  Sync sync_;
  int fd_ = -1;
  bool done_ = false;  ///< committed, or failed and cleaned up
};

/// Writes `bytes` to `path` whole (an AtomicFile). Throws OutputError.
void write_file_atomic(const std::string& path, std::string_view bytes, Sync sync = Sync::Now);

/// For a writer that opens its file by name (libpng's): `write(PATH.tmp)` writes and closes the
/// temporary file, which is then committed as AtomicFile::commit does. An exception from `write`
/// removes PATH.tmp and passes on. Throws OutputError.
void write_file_atomic_by_name(const std::string& path,
                               const std::function<void(const std::string& tmp)>& write,
                               Sync sync = Sync::Now);

/// Flushes a file already written, and a folder's entries, to the disk. Throws OutputError.
void sync_file(const std::string& path);
void sync_dir(const std::string& dir);

}  // namespace sandflow
