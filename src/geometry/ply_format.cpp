#include "geometry/ply_format.hpp"

#include <algorithm>
#include <bit>
#include <charconv>
#include <cstring>
#include <limits>
#include <system_error>
#include <utility>

#include "core/error.hpp"

namespace sandflow::ply {

std::size_t type_size(Type t) {
  switch (t) {
    case Type::Int8:
    case Type::UInt8:
      return 1;
    case Type::Int16:
    case Type::UInt16:
      return 2;
    case Type::Int32:
    case Type::UInt32:
    case Type::Float32:
      return 4;
    case Type::Float64:
      return 8;
  }
  return 8;
}

bool is_integer(Type t) {
  return t != Type::Float32 && t != Type::Float64;
}

bool parse_type(std::string_view word, Type& t) {
  struct Name {
    std::string_view a, b;
    Type t;
  };
  static constexpr Name kNames[] = {
      {"char", "int8", Type::Int8},        {"uchar", "uint8", Type::UInt8},
      {"short", "int16", Type::Int16},     {"ushort", "uint16", Type::UInt16},
      {"int", "int32", Type::Int32},       {"uint", "uint32", Type::UInt32},
      {"float", "float32", Type::Float32}, {"double", "float64", Type::Float64},
  };
  for (const Name& n : kNames)
    if (word == n.a || word == n.b) {
      t = n.t;
      return true;
    }
  return false;
}

namespace {

template <class T>
double load(const unsigned char* p, bool big_endian) {
  unsigned char b[sizeof(T)];
  std::memcpy(b, p, sizeof(T));
  if (big_endian != (std::endian::native == std::endian::big)) std::reverse(b, b + sizeof(T));
  T v;
  std::memcpy(&v, b, sizeof(T));
  return static_cast<double>(v);
}

// A count of records: digits only; past 2^64 - 1 it saturates or is refused.
bool parse_count(std::string_view word, bool saturate, std::uint64_t& count) {
  const char* end = word.data() + word.size();
  const auto [ptr, ec] = std::from_chars(word.data(), end, count);
  if (ptr != end || word.empty()) return false;
  if (ec == std::errc::result_out_of_range && saturate) {
    count = std::numeric_limits<std::uint64_t>::max();
    return true;
  }
  return ec == std::errc();
}

// The header's lines and the problems found in them; the grammar is in parse().
class HeaderParser {
 public:
  HeaderParser(std::string_view text, const Dialect& dialect, const std::string& file)
      : text_(text), dialect_(dialect), file_(file) {}

  Header parse() {
    // line 1: the magic word
    std::string_view line;
    const bool have_line = next_line(line);
    if (dialect_.magic_only) {
      if (text_.substr(0, 3) != "ply" || text_.size() < 4 || (text_[3] != '\n' && text_[3] != '\r'))
        fail(Problem::NotPly);
      if (!have_line) fail(Problem::NoEndHeader, 1);
    } else if (!have_line || line != "ply") {
      fail(Problem::NotPly);
    }
    bool have_format = false;
    while (true) {
      if (!next_line(line)) fail(Problem::NoEndHeader, line_ + 1);
      const std::vector<std::string_view> w = split_words(line, dialect_.blanks);
      if (w.empty()) continue;
      if (w[0] == "comment") {
        header_.comments.push_back(line);
      } else if (w[0] == "obj_info") {
        continue;
      } else if (w[0] == "end_header") {
        if (!have_format) fail(Problem::NoFormat, line_);
        header_.end_line = line_;
        header_.body_offset = pos_;
        return std::move(header_);
      } else if (w[0] == "format") {
        read_format(w);
        have_format = true;
      } else if (w[0] == "element") {
        read_element(w);
      } else if (w[0] == "property") {
        read_property(w);
      } else {
        fail(Problem::UnexpectedWord, line_, w[0]);
      }
    }
  }

 private:
  [[noreturn]] void fail(Problem p, std::size_t line = 1, std::string_view word = {}) const {
    std::string what((*dialect_.words)[static_cast<std::size_t>(p)]);
    if (const std::size_t at = what.find("{}"); at != std::string::npos)
      what.replace(at, 2, word.substr(0, 40));
    throw InputError(file_ + std::string(dialect_.line_label) + std::to_string(line) + ": " + what);
  }

  // The next line without its '\n' (and a '\r' before it); false at the end of the text.
  bool next_line(std::string_view& line) {
    if (pos_ >= text_.size()) return false;
    std::size_t nl = text_.find('\n', pos_);
    if (nl == std::string_view::npos) {
      if (dialect_.final_newline) return false;
      nl = text_.size();
    }
    line = text_.substr(pos_, nl - pos_);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    pos_ = std::min(nl + 1, text_.size());
    ++line_;
    return true;
  }

  std::string name(std::string_view word) const {
    return std::string(word.substr(0, dialect_.name_chars));
  }

  // format <ascii|binary_little_endian|binary_big_endian> 1.0
  void read_format(const std::vector<std::string_view>& w) {
    if (w.size() != 3 || w[2] != "1.0") fail(Problem::BadFormatLine, line_);
    if (w[1] == "ascii") {
      header_.encoding = Encoding::Ascii;
    } else if (w[1] == "binary_little_endian") {
      header_.encoding = Encoding::BinaryLittleEndian;
    } else if (w[1] == "binary_big_endian") {
      if (!dialect_.big_endian) fail(Problem::BigEndian, line_);
      header_.encoding = Encoding::BinaryBigEndian;
    } else {
      fail(Problem::UnknownFormat, line_, w[1]);
    }
  }

  // element <name> <count>
  void read_element(const std::vector<std::string_view>& w) {
    if (w.size() != 3) fail(Problem::BadElementLine, line_);
    Element e;
    e.name = name(w[1]);
    e.line = line_;
    if (!parse_count(w[2], dialect_.saturate_counts, e.count)) fail(Problem::BadCount, line_, w[2]);
    header_.elements.push_back(std::move(e));
  }

  // property <type> <name>, or property list <integer type> <type> <name>
  void read_property(const std::vector<std::string_view>& w) {
    if (header_.elements.empty()) fail(Problem::PropertyBeforeElement, line_);
    Property p;
    if (w.size() == 5 && w[1] == "list") {
      p.is_list = true;
      if (!parse_type(w[2], p.count_type) || !is_integer(p.count_type))
        fail(Problem::ListCountNotInteger, line_, w[2]);
      if (!parse_type(w[3], p.type)) fail(Problem::UnknownType, line_, w[3]);
      p.name = name(w[4]);
    } else if (w.size() == 3) {
      if (!parse_type(w[1], p.type)) fail(Problem::UnknownType, line_, w[1]);
      p.name = name(w[2]);
    } else {
      fail(Problem::BadPropertyLine, line_);
    }
    std::vector<Property>& props = header_.elements.back().props;
    if (dialect_.unique_properties)
      for (const Property& q : props)
        if (q.name == p.name) fail(Problem::DuplicateProperty, line_, p.name);
    props.push_back(std::move(p));
  }

  std::string_view text_;
  const Dialect& dialect_;
  const std::string& file_;
  std::size_t pos_ = 0, line_ = 0;  ///< the next line's first byte; the lines read
  Header header_;
};

}  // namespace

double decode(const unsigned char* p, Type t, bool big_endian) {
  switch (t) {
    case Type::Int8:
      return static_cast<std::int8_t>(p[0]);
    case Type::UInt8:
      return p[0];
    case Type::Int16:
      return load<std::int16_t>(p, big_endian);
    case Type::UInt16:
      return load<std::uint16_t>(p, big_endian);
    case Type::Int32:
      return load<std::int32_t>(p, big_endian);
    case Type::UInt32:
      return load<std::uint32_t>(p, big_endian);
    case Type::Float32:
      return load<float>(p, big_endian);
    case Type::Float64:
      return load<double>(p, big_endian);
  }
  return 0;
}

std::uint64_t min_record_bytes(Encoding encoding, const Element& e) {
  std::uint64_t n = 0;
  for (const Property& p : e.props)
    n += encoding == Encoding::Ascii ? 2 : type_size(p.is_list ? p.count_type : p.type);
  return n;
}

Header parse_header(std::string_view data, const Dialect& dialect, const std::string& file) {
  return HeaderParser(data, dialect, file).parse();
}

std::vector<std::string_view> split_words(std::string_view line, std::string_view blanks) {
  std::vector<std::string_view> words;
  std::size_t i = 0;
  while (i < line.size()) {
    i = line.find_first_not_of(blanks, i);
    if (i == std::string_view::npos) break;
    std::size_t j = line.find_first_of(blanks, i);
    if (j == std::string_view::npos) j = line.size();
    words.push_back(line.substr(i, j - i));
    i = j;
  }
  return words;
}

}  // namespace sandflow::ply
