#include "io/ply.hpp"

#include <algorithm>
#include <bit>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string_view>
#include <vector>

#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "core/read_file.hpp"
#include "geometry/ply_format.hpp"
#include "io/export_formats.hpp"

namespace sandflow {
namespace {

// ---------------------------------------------------------------------------------------------
// Writing

constexpr std::size_t kRecordBytes = 7 * 4 + 4 + 1;  // 7 floats, a uint, a uchar
constexpr std::size_t kChunkGrains = 1 << 16;        // bounded buffer for any frame size

template <class T>
void put_le(unsigned char*& p, T v) {
  unsigned char b[sizeof(T)];
  std::memcpy(b, &v, sizeof(T));
  if constexpr (std::endian::native == std::endian::big) std::reverse(b, b + sizeof(T));
  std::memcpy(p, b, sizeof(T));
  p += sizeof(T);
}

void check_sizes(const FrameData& f) {
  const std::size_t n = f.size();
  auto ok = [n](std::size_t m, bool optional) { return m == n || (optional && m == 0); };
  if (!ok(f.radius.size(), false) || !ok(f.velocity.size(), true) || !ok(f.id.size(), true) ||
      !ok(f.state.size(), true)) {
    throw std::invalid_argument("write_ply: FrameData arrays have different lengths");
  }
}

// ---------------------------------------------------------------------------------------------
// Reading

using ply::Element;
using ply::Encoding;
using ply::Property;
using ply::Type;

// The frame reader's words for a problem in the header, after "NAME: header line N: ".
constexpr ply::Words kFrameWords = {
    "not a PLY file (expected the first line 'ply')",
    "end of file, but the header has no 'end_header' line (file truncated?)",
    "no 'format' line before 'end_header'",
    "expected 'format <kind> 1.0'",
    "binary_big_endian PLY is not supported (use binary_little_endian)",
    "unknown format '{}'",
    "expected 'element <name> <count>'",
    "element count '{}' is not a non-negative integer",
    "property before any element",
    "expected 'property <type> <name>' or 'property list <type> <type> <name>'",
    "list count type '{}' is not an integer type",
    "unknown property type '{}'",
    "duplicate property '{}'",
    "unexpected '{}'",
};
static_assert(ply::all_worded(kFrameWords));

// What the frame reader accepts of the PLY grammar (geometry/ply_format.hpp): words between spaces
// and tabs, header lines that end with a newline, binary data in little-endian order only, each
// property named once, names cut to 40 characters.
constexpr ply::Dialect kFrameDialect{.blanks = " \t",
                                     .magic_only = true,
                                     .final_newline = true,
                                     .big_endian = false,
                                     .saturate_counts = false,
                                     .unique_properties = true,
                                     .name_chars = 40,
                                     .line_label = ": header line ",
                                     .words = &kFrameWords};

// "comment up_axis y": written by write_ply with UpAxis::Y
UpAxis up_axis(const ply::Header& h) {
  for (std::string_view line : h.comments) {
    const auto w = ply::split_words(line, kFrameDialect.blanks);
    if (w.size() == 3 && w[1] == "up_axis" && w[2] == "y") return UpAxis::Y;
  }
  return UpAxis::Z;
}

// Where each grain field comes from inside a vertex record: a property index, or -1.
enum Field { kX, kY, kZ, kRadius, kVx, kVy, kVz, kId, kState, kFieldCount };
constexpr std::string_view kFieldNames[kFieldCount] = {"x",  "y",  "z",  "radius", "vx",
                                                       "vy", "vz", "id", "state"};

// Messages name the place: "header line N" in the header, then "line N" (ascii) or "byte N"
// (binary) in the data, and the element record.
class Reader {
 public:
  Reader(std::string_view data, const std::string& name) : data_(data), name_(name) {}

  FrameData read() {
    const ply::Header h = ply::parse_header(data_, kFrameDialect, name_);
    const UpAxis up = up_axis(h);
    const unsigned char* p = bytes() + h.body_offset;
    const unsigned char* end = bytes() + data_.size();
    for (const Element& e : h.elements) {
      if (e.name == "vertex") {
        FrameData f = read_vertices(h.encoding, e, p, end);
        // back to the scene's frame, z up
        for (Vec3& x : f.position) x = from_up_axis(x, up);
        for (Vec3& v : f.velocity) v = from_up_axis(v, up);
        return f;
      }
      skip_element(h.encoding, e, p, end);
    }
    fail("header line " + std::to_string(h.end_line) + ": no 'vertex' element");
  }

 private:
  [[noreturn]] void fail(const std::string& what) const { throw InputError(name_ + ": " + what); }

  const unsigned char* bytes() const {
    return reinterpret_cast<const unsigned char*>(data_.data());
  }

  // The place of a byte of the data: its line in an ascii file, its offset in a binary one.
  std::string place(Encoding encoding, const unsigned char* p) const {
    const auto offset = static_cast<std::size_t>(p - bytes());
    if (encoding != Encoding::Ascii) return "byte " + std::to_string(offset);
    return "line " + std::to_string(1 + std::count(data_.begin(), data_.begin() + offset, '\n'));
  }

  void check_count(Encoding encoding, const Element& e, const unsigned char* p,
                   const unsigned char* end) const {
    const std::string where = "header line " + std::to_string(e.line) + ": element '" + e.name +
                              "' declares " + std::to_string(e.count) + " records";
    if (e.name == "vertex" && e.count > kMaxFrameGrains)
      fail(where + ", more than the limit of " + std::to_string(kMaxFrameGrains) + " grains");
    const std::size_t min_bytes = ply::min_record_bytes(encoding, e);
    if (min_bytes == 0) return;
    // The last ascii token needs no trailing separator.
    const std::size_t avail = static_cast<std::size_t>(end - p) + (encoding == Encoding::Ascii);
    if (e.count > avail / min_bytes) {
      fail(where + " but only " + std::to_string(end - p) +
           " bytes of data follow the header (truncated file or corrupt count)");
    }
  }

  // "line 12: element 'vertex' record 3: " (ascii) or "byte 480: element 'vertex' record 3: "
  std::string record_place(Encoding encoding, const unsigned char* p, const Element& e,
                           std::uint64_t record) const {
    return place(encoding, p) + ": element '" + e.name + "' record " + std::to_string(record) +
           ": ";
  }

  // Reads the next ascii number; fails naming the record when the data ends or is not a number.
  double next_ascii(const unsigned char*& p, const unsigned char* end, const Element& e,
                    std::uint64_t record) const {
    while (p < end && std::isspace(*p)) ++p;
    const unsigned char* start = p;
    while (p < end && !std::isspace(*p)) ++p;
    if (start == p)
      fail(record_place(Encoding::Ascii, p, e, record) + "unexpected end of data (truncated file)");
    const char* b = reinterpret_cast<const char*>(start);
    const char* t = reinterpret_cast<const char*>(p);
    double v = 0;
    const auto r = std::from_chars(b, t, v);
    if (r.ec != std::errc() || r.ptr != t) {
      fail(record_place(Encoding::Ascii, start, e, record) + "'" +
           std::string(b, std::min<std::size_t>(t - b, 40)) + "' is not a number");
    }
    return v;
  }

  double next_binary(const unsigned char*& p, const unsigned char* end, Type t, const Element& e,
                     std::uint64_t record) const {
    const std::size_t n = ply::type_size(t);
    if (static_cast<std::size_t>(end - p) < n) {
      fail(record_place(Encoding::BinaryLittleEndian, p, e, record) +
           "unexpected end of data (truncated file)");
    }
    const double v = ply::decode(p, t, false);
    p += n;
    return v;
  }

  std::uint64_t list_count(double v, Encoding encoding, const unsigned char* at, const Element& e,
                           std::uint64_t record) const {
    if (!(v >= 0) || v != std::floor(v) || v > 4.0e9) {
      fail(record_place(encoding, at, e, record) + "bad list length");
    }
    return static_cast<std::uint64_t>(v);
  }

  // Reads one record, storing the values of the wanted scalar properties into `out`
  // (indexed like e.props; lists are skipped).
  void read_record(Encoding encoding, const Element& e, std::uint64_t record,
                   const unsigned char*& p, const unsigned char* end, double* out) const {
    for (std::size_t k = 0; k < e.props.size(); ++k) {
      const Property& prop = e.props[k];
      const unsigned char* at = p;
      if (encoding == Encoding::Ascii) {
        if (prop.is_list) {
          const std::uint64_t n =
              list_count(next_ascii(p, end, e, record), encoding, at, e, record);
          for (std::uint64_t i = 0; i < n; ++i) next_ascii(p, end, e, record);
        } else {
          out[k] = next_ascii(p, end, e, record);
        }
      } else {
        if (prop.is_list) {
          const std::uint64_t n =
              list_count(next_binary(p, end, prop.count_type, e, record), encoding, at, e, record);
          const std::size_t item = ply::type_size(prop.type);
          if (n > static_cast<std::size_t>(end - p) / item) {
            fail(record_place(encoding, at, e, record) +
                 "list runs past the end of the file (truncated file)");
          }
          p += n * item;
        } else {
          out[k] = next_binary(p, end, prop.type, e, record);
        }
      }
    }
  }

  void skip_element(Encoding encoding, const Element& e, const unsigned char*& p,
                    const unsigned char* end) const {
    if (e.props.empty()) return;
    check_count(encoding, e, p, end);
    std::vector<double> scratch(e.props.size());
    for (std::uint64_t r = 0; r < e.count; ++r) read_record(encoding, e, r, p, end, scratch.data());
  }

  FrameData read_vertices(Encoding encoding, const Element& e, const unsigned char*& p,
                          const unsigned char* end) const {
    // Map the grain fields to property indices.
    const std::string where = "header line " + std::to_string(e.line) + ": ";
    int field[kFieldCount];
    for (int f = 0; f < kFieldCount; ++f) {
      field[f] = -1;
      for (std::size_t k = 0; k < e.props.size(); ++k) {
        if (e.props[k].name == kFieldNames[f]) {
          if (e.props[k].is_list) {
            fail(where + "vertex property '" + e.props[k].name + "' is a list, expected a number");
          }
          field[f] = static_cast<int>(k);
        }
      }
    }
    for (int f : {kX, kY, kZ}) {
      if (field[f] < 0)
        fail(where + "vertex element has no '" + std::string(kFieldNames[f]) + "' property");
    }
    if (field[kRadius] < 0)
      fail(where + "vertex element has no 'radius' property (grain radii are needed)");
    check_count(encoding, e, p, end);

    FrameData f;
    const std::size_t n = static_cast<std::size_t>(e.count);
    f.position.resize(n);
    f.radius.resize(n);
    f.velocity.resize(n);
    f.id.resize(n);
    f.state.resize(n);
    std::vector<double> v(e.props.size(), 0.0);
    auto get = [&](int fi, double fallback) { return field[fi] >= 0 ? v[field[fi]] : fallback; };
    for (std::size_t i = 0; i < n; ++i) {
      const unsigned char* record = p;
      read_record(encoding, e, i, p, end, v.data());
      auto bad = [&](const std::string& what) {
        fail(place(encoding, record) + ": vertex " + std::to_string(i) + ": " + what);
      };
      f.position[i] = {get(kX, 0), get(kY, 0), get(kZ, 0)};
      f.radius[i] = get(kRadius, 0);
      f.velocity[i] = {get(kVx, 0), get(kVy, 0), get(kVz, 0)};
      if (!is_finite(f.position[i]) || !is_finite(f.velocity[i])) {
        bad("position or velocity is not finite");
      }
      if (!(f.radius[i] > 0) || !std::isfinite(f.radius[i])) {
        char text[32];  // the value as written, shortest form
        const auto end_text = std::to_chars(text, text + sizeof text, f.radius[i]).ptr;
        bad("radius " + std::string(text, end_text) + " is not a positive number");
      }
      const double id = get(kId, static_cast<double>(i));
      if (!(id >= 0) || id > std::numeric_limits<std::uint32_t>::max() || id != std::floor(id)) {
        bad("id is not an unsigned 32-bit integer");
      }
      f.id[i] = static_cast<std::uint32_t>(id);
      const double state = get(kState, 0);
      if (state != 0 && state != 1 && state != 2) bad("state is not 0, 1 or 2");
      f.state[i] = static_cast<std::uint8_t>(state);
    }
    return f;
  }

  std::string_view data_;
  const std::string& name_;
};

}  // namespace

void write_ply(const std::string& path, const FrameData& f, UpAxis up) {
  check_sizes(f);
  const std::size_t n = f.size();
  const std::string header =
      "ply\n"
      "format binary_little_endian 1.0\n"
      "comment sandflow grains (state 0 ACTIVE, 1 INTERFACE, 2 STATIC)\n"
      "comment up_axis " +
      std::string(up_axis_name(up)) +
      "\n"
      "element vertex " +
      std::to_string(n) +
      "\n"
      "property float x\nproperty float y\nproperty float z\nproperty float radius\n"
      "property float vx\nproperty float vy\nproperty float vz\n"
      "property uint id\nproperty uchar state\n"
      "end_header\n";

  AtomicFile file(path, Sync::Later);  // a run flushes its frames before each checkpoint
  file.write(header);
  std::vector<unsigned char> buf(std::min(n, kChunkGrains) * kRecordBytes);
  for (std::size_t first = 0; first < n; first += kChunkGrains) {
    const std::size_t last = std::min(n, first + kChunkGrains);
    unsigned char* p = buf.data();
    for (std::size_t i = first; i < last; ++i) {
      const Vec3 x = to_up_axis(f.position[i], up);
      const Vec3 v = f.velocity.empty() ? Vec3{} : to_up_axis(f.velocity[i], up);
      put_le(p, static_cast<float>(x.x));
      put_le(p, static_cast<float>(x.y));
      put_le(p, static_cast<float>(x.z));
      put_le(p, static_cast<float>(f.radius[i]));
      put_le(p, static_cast<float>(v.x));
      put_le(p, static_cast<float>(v.y));
      put_le(p, static_cast<float>(v.z));
      put_le(p, f.id.empty() ? static_cast<std::uint32_t>(i) : f.id[i]);
      put_le(p, f.state.empty() ? std::uint8_t{0} : f.state[i]);
    }
    file.write(
        {reinterpret_cast<const char*>(buf.data()), static_cast<std::size_t>(p - buf.data())});
  }
  file.commit();
}

FrameData parse_frame_ply(std::string_view bytes, const std::string& name) {
  return Reader(bytes, name).read();
}

FrameData read_ply(const std::string& path) {
  return parse_frame_ply(read_whole_file(path, "frame", kAnyFileSize), path);
}

}  // namespace sandflow
