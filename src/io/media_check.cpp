// Written by hand: a PNG's signature and last chunk, and an MP4's box headers down to its sample
// count, are a few fixed-size fields (ISO/IEC 14496-12, §4.2 and §8.7.3); libavformat would be a
// new build dependency to read them, ffprobe another program to run and parse. The files are
// read by seeking to those fields, not whole (core/read_file.hpp): a movie can be gigabytes.
#include "io/media_check.hpp"

#include <sys/stat.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <memory>
#include <optional>
#include <string_view>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include "core/file_kind.hpp"

namespace sandflow {
namespace {

using File = std::unique_ptr<std::FILE, int (*)(std::FILE*)>;

struct Opened {
  File file{nullptr, &std::fclose};
  std::uint64_t size = 0;
};

std::optional<Opened> open_regular(const std::string& path, std::string& problem) {
  // (opening a FIFO would wait for a writer: refused by its type first)
  if (const std::string kind = special_file_kind(path); !kind.empty()) {
    problem = "it is " + kind + ", not a file";
    return std::nullopt;
  }
  Opened o;
  o.file.reset(std::fopen(path.c_str(), "rb"));
  struct stat st {};
  if (!o.file || ::fstat(::fileno(o.file.get()), &st) != 0) {
    problem = fmt::format("cannot read it: {}", std::strerror(errno));
    return std::nullopt;
  }
  o.size = static_cast<std::uint64_t>(st.st_size);
  return o;
}

bool read_at(std::FILE* f, std::uint64_t offset, void* into, std::size_t bytes) {
  return ::fseeko(f, static_cast<off_t>(offset), SEEK_SET) == 0 &&
         std::fread(into, 1, bytes, f) == bytes;
}

std::uint32_t be32(const unsigned char* p) {
  return std::uint32_t{p[0]} << 24 | std::uint32_t{p[1]} << 16 | std::uint32_t{p[2]} << 8 | p[3];
}

std::uint64_t be64(const unsigned char* p) {
  return std::uint64_t{be32(p)} << 32 | be32(p + 4);
}

// One box's header read from `p` (at least 16 bytes, or `left` if fewer): its type, the size of
// its header and its whole size (a size of 0 runs to the end: `left`). Nothing when the header
// does not fit in `left` or claims less than itself.
struct BoxHeader {
  std::string type;
  std::uint64_t header = 8;
  std::uint64_t size = 0;
};

std::optional<BoxHeader> box_header(const unsigned char* p, std::uint64_t left) {
  if (left < 8) return std::nullopt;
  BoxHeader b;
  b.type.assign(reinterpret_cast<const char*>(p + 4), 4);
  b.size = be32(p);
  if (b.size == 1) {
    if (left < 16) return std::nullopt;
    b.header = 16;
    b.size = be64(p + 8);
  } else if (b.size == 0) {
    b.size = left;
  }
  if (b.size < b.header) return std::nullopt;
  return b;
}

// The boxes directly inside `body` (a box's content), in order, up to the first that overruns
// it: each one's type and content.
std::vector<std::pair<std::string, std::string_view>> boxes(std::string_view body) {
  std::vector<std::pair<std::string, std::string_view>> out;
  std::uint64_t at = 0;
  while (at < body.size()) {
    const std::uint64_t left = body.size() - at;
    const std::optional<BoxHeader> b =
        box_header(reinterpret_cast<const unsigned char*>(body.data() + at), left);
    if (!b || b->size > left) break;
    out.emplace_back(b->type, body.substr(at + b->header, b->size - b->header));
    at += b->size;
  }
  return out;
}

// The content of the first box of `type` directly inside `body`, or nothing.
std::optional<std::string_view> child(std::string_view body, std::string_view type) {
  for (const auto& [t, content] : boxes(body))
    if (t == type) return content;
  return std::nullopt;
}

// The samples of the video tracks of a 'moov' box's content (each 'trak' whose handler is
// 'vide': its sample table's 'stsz' or 'stz2' count), or nothing when there is no video track.
std::optional<std::uint64_t> video_samples(std::string_view moov) {
  std::optional<std::uint64_t> samples;
  for (const auto& [type, content] : boxes(moov)) {
    if (type != "trak") continue;
    const auto mdia = child(content, "mdia");
    const auto hdlr = mdia ? child(*mdia, "hdlr") : std::nullopt;
    // hdlr: version and flags (4), pre_defined (4), handler_type (4)
    if (!hdlr || hdlr->size() < 12 || hdlr->substr(8, 4) != "vide") continue;
    const auto minf = child(*mdia, "minf");
    const auto stbl = minf ? child(*minf, "stbl") : std::nullopt;
    if (!stbl) continue;
    // stsz: version and flags, sample_size, sample_count; stz2: version and flags, field size,
    // sample_count
    auto sizes = child(*stbl, "stsz");
    if (!sizes) sizes = child(*stbl, "stz2");
    if (!sizes || sizes->size() < 12) continue;
    samples = samples.value_or(0) + be32(reinterpret_cast<const unsigned char*>(sizes->data()) + 8);
  }
  return samples;
}

}  // namespace

std::string png_problem(const std::string& path) {
  std::string problem;
  std::optional<Opened> o = open_regular(path, problem);
  if (!o) return problem;
  static constexpr unsigned char kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  // the last chunk: length 0, "IEND", its CRC
  static constexpr unsigned char kEnd[12] = {0,   0,   0,    0,    'I',  'E',
                                             'N', 'D', 0xae, 0x42, 0x60, 0x82};
  unsigned char head[8], tail[12];
  if (o->size < sizeof head + sizeof tail || !read_at(o->file.get(), 0, head, sizeof head) ||
      std::memcmp(head, kSignature, sizeof head) != 0)
    return fmt::format("it is not a PNG ({} bytes, without a PNG's signature)", o->size);
  if (!read_at(o->file.get(), o->size - sizeof tail, tail, sizeof tail) ||
      std::memcmp(tail, kEnd, sizeof tail) != 0)
    return fmt::format("it ends without its IEND chunk after {} bytes: cut short", o->size);
  return "";
}

std::string mp4_problem(const std::string& path, std::int64_t frames) {
  std::string problem;
  std::optional<Opened> o = open_regular(path, problem);
  if (!o) return problem;
  std::FILE* f = o->file.get();
  std::string moov;
  bool has_moov = false, has_mdat = false;
  std::uint64_t at = 0;
  while (at < o->size) {
    const std::uint64_t left = o->size - at;
    unsigned char head[16] = {};
    const std::size_t want = left < sizeof head ? static_cast<std::size_t>(left) : sizeof head;
    if (!read_at(f, at, head, want)) return fmt::format("cannot read it: {}", std::strerror(errno));
    const std::optional<BoxHeader> b = box_header(head, left);
    if (!b)
      return fmt::format(
          "it ends {} bytes into a box's header at byte {}: cut short, or not an MP4", left, at);
    if (at == 0 && b->type != "ftyp") return "it does not start with an 'ftyp' box: not an MP4";
    if (b->size > left)
      return fmt::format(
          "its box '{}' at byte {} says {} bytes, and the file ends {} bytes after it starts: cut "
          "short",
          b->type, at, b->size, left);
    if (b->type == "mdat") has_mdat = true;
    if (b->type == "moov" && !has_moov) {
      has_moov = true;
      moov.resize(b->size - b->header);
      if (!read_at(f, at + b->header, moov.data(), moov.size()))
        return fmt::format("cannot read it: {}", std::strerror(errno));
    }
    at += b->size;
  }
  if (o->size == 0) return "it is empty";
  if (!has_moov) return "it has no index (no 'moov' box): it was not finished";
  if (!has_mdat) return "it has no data (no 'mdat' box)";
  const std::optional<std::uint64_t> samples = video_samples(moov);
  if (!samples) return "its index lists no video track";
  if (*samples != static_cast<std::uint64_t>(frames))
    return fmt::format("it holds {} frames, not {}", *samples, frames);
  return "";
}

}  // namespace sandflow
