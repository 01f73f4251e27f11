// Reading a file whole: the one reader of whole files (docs/style.md, "One way to do a thing"),
// the counterpart of core/atomic_file.hpp's writer, used for scenes, frames, heightmap pictures,
// statistics and caches.
//
// It refuses what is not a regular file by its type before opening it (a FIFO blocks until a
// writer comes, /dev/zero never ends), reads in pieces up to a limit (a file can grow while it is
// read) and names the file, what it was read as and the system's reason in every error.
#pragma once

#include <cstddef>
#include <limits>
#include <optional>
#include <string>
#include <string_view>

namespace sandflow {

/// A limit for files whose size nothing bounds but the disk (statistics, logs, frames).
inline constexpr std::size_t kAnyFileSize = std::numeric_limits<std::size_t>::max();

/// The bytes of the regular file `path`, read as the `what` ("scene file", "frame", ...), at most
/// `max_bytes`. Throws InputError, each message starting "PATH: ": "the WHAT is a FIFO, not a
/// file", "cannot open the WHAT: REASON", "the WHAT is larger than the limit of N bytes", "cannot
/// read the WHAT: REASON".
std::string read_whole_file(const std::string& path, std::string_view what, std::size_t max_bytes);

/// read_whole_file, or nothing when `path` is not there (a file a command writes later, such as a
/// run's summary). A link to nothing counts as not there: refuse_broken_link says otherwise.
std::optional<std::string> read_file_if_present(const std::string& path, std::string_view what,
                                                std::size_t max_bytes);

}  // namespace sandflow
