// Whether a picture or a movie another program wrote is whole, read from its structure.
//
// A program's exit status does not say it: ffmpeg 5.1 (Debian 12) on a full disk logs "Error
// writing trailer of ...: No space left on device" and exits with status 0, leaving an MP4 cut
// after its first few kilobytes, with no index (docs/performance.md, sixtieth entry). So a picture
// or movie is put under its name only when its own structure says it is complete.
#pragma once

#include <cstdint>
#include <string>

namespace sandflow {

/// "" when `path` is a whole PNG: the signature first, the IEND chunk last. Else what is wrong
/// ("it ends without its IEND chunk: cut short", ...).
std::string png_problem(const std::string& path);

/// "" when `path` is a whole MP4 holding `frames` video frames: its top-level boxes tile the file
/// exactly, it has its index ('moov') and its data ('mdat'), and the index's video track lists
/// `frames` samples. Else what is wrong ("its box 'mdat' at byte 40 says 70,611 bytes, and the
/// file ends 12,248 bytes after it starts: cut short", ...).
std::string mp4_problem(const std::string& path, std::int64_t frames);

}  // namespace sandflow
