// PLY polygon meshes: ascii, binary_little_endian and binary_big_endian. The 'vertex' element
// gives x, y, z (any numeric type; other properties skipped); the 'face' element gives the list
// 'vertex_indices' (or 'vertex_index') of any integer types; polygons are fan-triangulated.
// Other elements are read past. Every count is checked against the limits and the bytes left
// before anything is allocated (mesh_io.hpp). The header is parsed by geometry/ply_format.hpp, as
// the frame reader's (io/ply.cpp) is.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

#include "geometry/mesh_io.hpp"
#include "geometry/mesh_io_detail.hpp"
#include "geometry/ply_format.hpp"

namespace sandflow::mesh_io {

namespace {

using ply::Element;
using ply::Encoding;
using ply::Property;
using ply::Type;

std::string number_text(double v) {
  if (std::isfinite(v) && v == std::floor(v) && std::fabs(v) < 1e18)
    return std::to_string(static_cast<std::int64_t>(v));
  return std::to_string(v);
}

// The properties of one record, in one encoding: where a value comes from and how to name the
// position when it is bad.
class RecordSource {
 public:
  virtual ~RecordSource() = default;
  virtual void begin(const Element& e, std::uint64_t index) = 0;
  virtual double scalar(Type t) = 0;
  virtual std::uint64_t list_count(Type t, Type item) = 0;
  virtual void end() = 0;
  [[noreturn]] virtual void fail(const std::string& what) const = 0;
};

class AsciiSource final : public RecordSource {
 public:
  AsciiSource(std::string_view data, std::size_t first_line, const std::string& file)
      : cursor_(data), first_line_(first_line), file_(file) {}

  // one record a line, as the PLY definition has it
  void begin(const Element& e, std::uint64_t index) override {
    element_ = &e;
    index_ = index;
    std::string_view line;
    do {
      if (!cursor_.next(line))
        fail_eof("unexpected end of file: expected " + e.name + " " + std::to_string(index) +
                 " of " + std::to_string(e.count) + " (file truncated?)");
    } while (Tokens(line).empty());
    tokens_ = Tokens(line);
  }
  double scalar(Type) override {
    std::string_view t;
    if (!tokens_.next(t)) fail("the record ends early: expected more values");
    Real v = 0;
    if (!parse_real(t, v)) fail("expected a number, found '" + std::string(t.substr(0, 40)) + "'");
    return v;
  }
  std::uint64_t list_count(Type, Type) override {
    const double n = scalar(Type::UInt32);
    if (!(n >= 0) || n != std::floor(n) || n > 1e9) fail("bad list length");
    return static_cast<std::uint64_t>(n);
  }
  void end() override {
    if (!tokens_.empty()) fail("more values than the header declares");
  }
  void fail(const std::string& what) const override {
    fail_line(file_, first_line_ + cursor_.line_number(),
              element_->name + " " + std::to_string(index_) + ": " + what);
  }
  // at the end of the data, the line where the missing record was expected
  [[noreturn]] void fail_eof(const std::string& what) const {
    fail_line(file_, first_line_ + cursor_.line_number() + 1, what);
  }

 private:
  LineCursor cursor_;
  Tokens tokens_{std::string_view()};
  std::size_t first_line_;
  const std::string& file_;
  const Element* element_ = nullptr;
  std::uint64_t index_ = 0;
};

class BinarySource final : public RecordSource {
 public:
  BinarySource(std::string_view data, std::size_t data_offset, bool big_endian,
               const std::string& file)
      : begin_(reinterpret_cast<const unsigned char*>(data.data())),
        p_(begin_ + data_offset),
        end_(begin_ + data.size()),
        big_endian_(big_endian),
        file_(file) {}

  void begin(const Element& e, std::uint64_t index) override {
    element_ = &e;
    index_ = index;
  }
  double scalar(Type t) override {
    value_start_ = p_;
    need(ply::type_size(t));
    const double v = ply::decode(p_, t, big_endian_);
    p_ += ply::type_size(t);
    return v;
  }
  std::uint64_t list_count(Type t, Type item) override {
    const double n = scalar(t);
    if (n < 0) fail("negative list length");
    // the list must fit in the bytes left before anything is allocated for it
    if (n * static_cast<double>(ply::type_size(item)) > static_cast<double>(end_ - p_))
      fail("a list of " + std::to_string(static_cast<std::uint64_t>(n)) +
           " items runs past the end of the file (file truncated?)");
    return static_cast<std::uint64_t>(n);
  }
  void end() override {}
  void fail(const std::string& what) const override {
    fail_file(file_, "byte " + std::to_string(value_start_ - begin_) + " (" + element_->name + " " +
                         std::to_string(index_) + "): " + what);
  }

 private:
  void need(std::size_t n) {
    if (static_cast<std::size_t>(end_ - p_) < n)
      fail("unexpected end of file: expected " + std::to_string(n) +
           " more bytes (file truncated?)");
  }

  const unsigned char *begin_, *p_, *end_;
  const unsigned char* value_start_ = p_;  ///< where the value being read starts, for messages
  bool big_endian_;
  const std::string& file_;
  const Element* element_ = nullptr;
  std::uint64_t index_ = 0;
};

// The mesh reader's words for a problem in the header, after "FILE:LINE: ".
constexpr ply::Words kMeshWords = {
    "not a PLY file (expected the first line 'ply')",
    "the header has no 'end_header' line",
    "no 'format' line before 'end_header'",
    "expected 'format <ascii|binary_little_endian|binary_big_endian> 1.0'",
    "binary_big_endian PLY is not supported",  // (accepted)
    "unknown format '{}'",
    "expected 'element <name> <count>' with a non-negative count",
    "expected 'element <name> <count>' with a non-negative count",
    "'property' before any 'element'",
    "expected 'property <type> <name>' or 'property list <integer type> <type> <name>'",
    "expected 'property <type> <name>' or 'property list <integer type> <type> <name>'",
    "expected 'property <type> <name>' or 'property list <integer type> <type> <name>'",
    "duplicate property '{}'",  // (accepted)
    "unexpected '{}' in the header",
};
static_assert(ply::all_worded(kMeshWords));

// The mesh reader accepts all the PLY grammar allows (ply_format.hpp): any blank between words,
// a last line without its newline, both byte orders, and a count past 2^64 - 1, which the limits
// then refuse.
constexpr ply::Dialect kMeshDialect{.line_label = ":", .words = &kMeshWords};

class PlyMeshReader {
 public:
  PlyMeshReader(std::string_view data, const std::string& file) : data_(data), file_(file) {}

  TriangleMesh read() {
    ply::Header header = ply::parse_header(data_, kMeshDialect, file_);
    encoding_ = header.encoding;
    elements_ = std::move(header.elements);
    check_counts(data_.size() - header.body_offset);
    find_mesh_properties();
    if (encoding_ == Encoding::Ascii) {
      AsciiSource source(data_.substr(header.body_offset), header.end_line, file_);
      read_elements(source);
    } else {
      BinarySource source(data_, header.body_offset, encoding_ == Encoding::BinaryBigEndian, file_);
      read_elements(source);
    }
    return std::move(mesh_);
  }

 private:
  // ---- header ----
  void find_mesh_properties() {
    int vertex_elements = 0, face_elements = 0;
    for (const Element& e : elements_) {
      if (e.name == "vertex" && vertex_elements++ == 0) find_xyz(e);
      if (e.name == "face" && face_elements++ == 0) find_indices(e);
      if (vertex_elements > 1 || face_elements > 1)
        fail_line(file_, e.line, "a second '" + e.name + "' element (expected one)");
    }
    if (xyz_[0] < 0) fail_file(file_, "no 'vertex' element with x, y, z in the header");
    if (indices_ < 0)
      fail_file(file_, "no 'face' element with a 'vertex_indices' list in the header");
  }

  void find_xyz(const Element& e) {
    static constexpr const char* kNames[3] = {"x", "y", "z"};
    for (int c = 0; c < 3; ++c) {
      for (std::size_t k = 0; k < e.props.size(); ++k)
        if (e.props[k].name == kNames[c] && !e.props[k].is_list) xyz_[c] = static_cast<int>(k);
      if (xyz_[c] < 0)
        fail_line(file_, e.line,
                  std::string("the vertex element has no scalar property '") + kNames[c] + "'");
    }
    vertex_count_ = e.count;
  }

  void find_indices(const Element& e) {
    for (std::size_t k = 0; k < e.props.size(); ++k) {
      const Property& p = e.props[k];
      if (p.name != "vertex_indices" && p.name != "vertex_index") continue;
      if (!p.is_list || !ply::is_integer(p.type))
        fail_line(file_, e.line, "'" + p.name + "' must be a list of integers");
      indices_ = static_cast<int>(k);
    }
  }

  // Refuses counts above the limits or beyond what the bytes after the header can hold.
  void check_counts(std::size_t bytes_left) {
    std::uint64_t left = bytes_left;
    for (const Element& e : elements_) {
      const std::uint64_t min_bytes = ply::min_record_bytes(encoding_, e);
      const std::uint64_t limit = e.name == "vertex" ? kMaxMeshVertices : kMaxMeshTriangles;
      const std::string where =
          file_ + ":" + std::to_string(e.line) + ": element '" + e.name + "': ";
      check_count(e.count, limit, left, min_bytes, e.name + " records", where);
      left -= std::min(left, e.count * min_bytes);
    }
  }

  // ---- data ----
  void read_elements(RecordSource& source) {
    for (const Element& e : elements_) {
      // a record without properties holds nothing (and takes no bytes, so no count check bounds
      // its loop: 50 such elements of 20 M records took seconds for nothing)
      if (e.props.empty()) continue;
      const bool is_vertex = e.name == "vertex", is_face = e.name == "face";
      if (is_vertex) mesh_.vertices.reserve(e.count);
      if (is_face) mesh_.triangles.reserve(e.count);
      for (std::uint64_t i = 0; i < e.count; ++i) {
        source.begin(e, i);
        for (std::size_t k = 0; k < e.props.size(); ++k)
          read_property_value(source, e, k, is_vertex, is_face);
        source.end();
        if (is_vertex) mesh_.vertices.push_back({xyz_value_[0], xyz_value_[1], xyz_value_[2]});
        if (is_face) add_polygon(source);
      }
    }
  }

  void read_property_value(RecordSource& source, const Element& e, std::size_t k, bool is_vertex,
                           bool is_face) {
    const Property& p = e.props[k];
    if (!p.is_list) {
      const double v = source.scalar(p.type);
      for (int c = 0; c < 3; ++c)
        if (is_vertex && xyz_[c] == static_cast<int>(k)) {
          if (!std::isfinite(v))
            source.fail(std::string("coordinate ") + "xyz"[c] + " is not finite");
          xyz_value_[c] = v;
        }
      return;
    }
    const std::uint64_t n = source.list_count(p.count_type, p.type);
    const bool wanted = is_face && indices_ == static_cast<int>(k);
    if (wanted) polygon_.clear();
    for (std::uint64_t j = 0; j < n; ++j) {
      const double v = source.scalar(p.type);
      if (wanted) polygon_.push_back(vertex_index(source, v));
    }
  }

  std::uint32_t vertex_index(RecordSource& source, double v) {
    if (!(v >= 0) || v != std::floor(v) || v >= static_cast<double>(vertex_count_))
      source.fail("vertex index " + number_text(v) + " is out of range [0, " +
                  std::to_string(vertex_count_) + ")");
    return static_cast<std::uint32_t>(v);
  }

  void add_polygon(RecordSource& source) {
    if (polygon_.size() < 3)
      source.fail("a face needs at least 3 vertices, found " + std::to_string(polygon_.size()));
    if (mesh_.triangles.size() + polygon_.size() - 2 > kMaxMeshTriangles)
      source.fail("more than the limit of " + std::to_string(kMaxMeshTriangles) + " triangles");
    add_fan(mesh_, polygon_.data(), polygon_.size());
  }

  std::string_view data_;
  const std::string& file_;
  Encoding encoding_ = Encoding::Ascii;
  std::vector<Element> elements_;
  int xyz_[3] = {-1, -1, -1};
  int indices_ = -1;
  std::uint64_t vertex_count_ = 0;
  double xyz_value_[3] = {0, 0, 0};
  std::vector<std::uint32_t> polygon_;
  TriangleMesh mesh_;
};

}  // namespace

TriangleMesh read_ply(std::string_view data, const std::string& file) {
  return PlyMeshReader(data, file).read();
}

}  // namespace sandflow::mesh_io
