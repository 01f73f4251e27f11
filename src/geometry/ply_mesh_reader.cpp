// PLY polygon meshes: ascii, binary_little_endian and binary_big_endian. The 'vertex' element
// gives x, y, z (any numeric type; other properties skipped); the 'face' element gives the list
// 'vertex_indices' (or 'vertex_index') of any integer types; polygons are fan-triangulated.
// Other elements are read past. Every count is checked against the limits and the bytes left
// before anything is allocated (mesh_io.hpp).
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <utility>
#include <vector>

#include "geometry/mesh_io.hpp"
#include "geometry/mesh_io_detail.hpp"

namespace sandflow::mesh_io {

namespace {

enum class Encoding { Ascii, BinaryLe, BinaryBe };
enum class Type { I8, U8, I16, U16, I32, U32, F32, F64 };

struct Property {
  std::string name;
  bool is_list = false;
  Type count_type = Type::U8;  ///< lists only
  Type type = Type::F32;       ///< the value, or a list's items
};

struct Element {
  std::string name;
  std::uint64_t count = 0;
  std::vector<Property> props;
  std::size_t line = 0;  ///< header line, for messages
};

std::size_t type_size(Type t) {
  switch (t) {
    case Type::I8:
    case Type::U8:
      return 1;
    case Type::I16:
    case Type::U16:
      return 2;
    case Type::I32:
    case Type::U32:
    case Type::F32:
      return 4;
    case Type::F64:
      return 8;
  }
  return 8;
}

std::string number_text(double v) {
  if (std::isfinite(v) && v == std::floor(v) && std::fabs(v) < 1e18)
    return std::to_string(static_cast<std::int64_t>(v));
  return std::to_string(v);
}

bool is_integer(Type t) {
  return t != Type::F32 && t != Type::F64;
}

bool parse_type(std::string_view s, Type& t) {
  struct Name {
    std::string_view name;
    Type type;
  };
  static constexpr Name kNames[] = {
      {"char", Type::I8},   {"int8", Type::I8},     {"uchar", Type::U8},   {"uint8", Type::U8},
      {"short", Type::I16}, {"int16", Type::I16},   {"ushort", Type::U16}, {"uint16", Type::U16},
      {"int", Type::I32},   {"int32", Type::I32},   {"uint", Type::U32},   {"uint32", Type::U32},
      {"float", Type::F32}, {"float32", Type::F32}, {"double", Type::F64}, {"float64", Type::F64}};
  for (const Name& n : kNames)
    if (s == n.name) {
      t = n.type;
      return true;
    }
  return false;
}

template <class T>
T load(const unsigned char* p, bool big_endian) {
  unsigned char b[sizeof(T)];
  std::memcpy(b, p, sizeof(T));
  if (big_endian != (std::endian::native == std::endian::big))
    for (std::size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(b[i], b[sizeof(T) - 1 - i]);
  T v;
  std::memcpy(&v, b, sizeof(T));
  return v;
}

double decode(const unsigned char* p, Type t, bool big_endian) {
  switch (t) {
    case Type::I8:
      return static_cast<std::int8_t>(p[0]);
    case Type::U8:
      return p[0];
    case Type::I16:
      return load<std::int16_t>(p, big_endian);
    case Type::U16:
      return load<std::uint16_t>(p, big_endian);
    case Type::I32:
      return load<std::int32_t>(p, big_endian);
    case Type::U32:
      return load<std::uint32_t>(p, big_endian);
    case Type::F32:
      return load<float>(p, big_endian);
    case Type::F64:
      return load<double>(p, big_endian);
  }
  return 0;
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
    const double n = scalar(Type::U32);
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
    need(type_size(t));
    const double v = decode(p_, t, big_endian_);
    p_ += type_size(t);
    return v;
  }
  std::uint64_t list_count(Type t, Type item) override {
    const double n = scalar(t);
    if (n < 0) fail("negative list length");
    // the list must fit in the bytes left before anything is allocated for it
    if (n * static_cast<double>(type_size(item)) > static_cast<double>(end_ - p_))
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

class PlyMeshReader {
 public:
  PlyMeshReader(std::string_view data, const std::string& file) : data_(data), file_(file) {}

  TriangleMesh read() {
    LineCursor header(data_);
    read_header(header);
    check_counts(header.bytes_left());
    find_mesh_properties();
    if (encoding_ == Encoding::Ascii) {
      AsciiSource source(data_.substr(header.offset()), header.line_number(), file_);
      read_elements(source);
    } else {
      BinarySource source(data_, header.offset(), encoding_ == Encoding::BinaryBe, file_);
      read_elements(source);
    }
    return std::move(mesh_);
  }

 private:
  // ---- header ----
  void read_header(LineCursor& cursor) {
    std::string_view line;
    if (!cursor.next(line) || line != "ply")
      fail_line(file_, 1, "not a PLY file (expected the first line 'ply')");
    bool have_format = false;
    while (true) {
      if (!cursor.next(line))
        fail_line(file_, cursor.line_number() + 1, "the header has no 'end_header' line");
      Tokens tokens(line);
      std::string_view word;
      if (!tokens.next(word) || word == "comment" || word == "obj_info") continue;
      const std::size_t n = cursor.line_number();
      if (word == "end_header") break;
      if (word == "format")
        have_format = read_format(tokens, n);
      else if (word == "element")
        read_element(tokens, n);
      else if (word == "property")
        read_property(tokens, n);
      else
        fail_line(file_, n, "unexpected '" + std::string(word.substr(0, 40)) + "' in the header");
    }
    if (!have_format)
      fail_line(file_, cursor.line_number(), "no 'format' line before 'end_header'");
  }

  bool read_format(Tokens& tokens, std::size_t line) {
    std::string_view kind, version;
    if (!tokens.next(kind) || !tokens.next(version) || version != "1.0" || !tokens.empty())
      fail_line(file_, line,
                "expected 'format <ascii|binary_little_endian|binary_big_endian> 1.0'");
    if (kind == "ascii")
      encoding_ = Encoding::Ascii;
    else if (kind == "binary_little_endian")
      encoding_ = Encoding::BinaryLe;
    else if (kind == "binary_big_endian")
      encoding_ = Encoding::BinaryBe;
    else
      fail_line(file_, line, "unknown format '" + std::string(kind.substr(0, 40)) + "'");
    return true;
  }

  void read_element(Tokens& tokens, std::size_t line) {
    std::string_view name, count;
    Element e;
    if (!tokens.next(name) || !tokens.next(count) || !tokens.empty() ||
        !parse_count(count, e.count))
      fail_line(file_, line, "expected 'element <name> <count>' with a non-negative count");
    e.name = std::string(name);
    e.line = line;
    elements_.push_back(std::move(e));
  }

  void read_property(Tokens& tokens, std::size_t line) {
    if (elements_.empty()) fail_line(file_, line, "'property' before any 'element'");
    std::string_view w[4];
    int n = 0;
    while (n < 4 && tokens.next(w[n])) ++n;
    Property p;
    bool ok = false;
    if (n == 4 && w[0] == "list" && tokens.empty()) {
      p.is_list = true;
      p.name = std::string(w[3]);
      ok = parse_type(w[1], p.count_type) && parse_type(w[2], p.type) && is_integer(p.count_type);
    } else if (n == 2) {
      p.name = std::string(w[1]);
      ok = parse_type(w[0], p.type);
    }
    if (!ok)
      fail_line(
          file_, line,
          "expected 'property <type> <name>' or 'property list <integer type> <type> <name>'");
    elements_.back().props.push_back(std::move(p));
  }

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
      if (!p.is_list || !is_integer(p.type))
        fail_line(file_, e.line, "'" + p.name + "' must be a list of integers");
      indices_ = static_cast<int>(k);
    }
  }

  // Refuses counts above the limits or beyond what the bytes after the header can hold.
  void check_counts(std::size_t bytes_left) {
    std::uint64_t left = bytes_left;
    for (const Element& e : elements_) {
      std::uint64_t min_bytes = 0;
      for (const Property& p : e.props)
        min_bytes +=
            encoding_ == Encoding::Ascii ? 2 : type_size(p.is_list ? p.count_type : p.type);
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
