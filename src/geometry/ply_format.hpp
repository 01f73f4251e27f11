// The PLY format, for both PLY readers: obstacle meshes (geometry/ply_mesh_reader.cpp) and grain
// frames (io/ply.cpp). One piece of code parses a header into its elements and properties, names
// the scalar types and decodes binary values; each reader then reads the records it wants.
//
// The two readers were written apart and differ in what they accept and in how they word a
// problem; sharing the parser kept both as they were. A Dialect holds what each accepts (the
// frame reader refuses big-endian files and a property named twice; the mesh reader takes any
// blank between words and a last line without its newline) and its words for each Problem.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace sandflow::ply {

/// The scalar types of a property.
enum class Type { Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32, Float64 };

std::size_t type_size(Type t);
bool is_integer(Type t);
/// The type a header names: "char" or "int8", "uchar" or "uint8", ..., "double" or "float64";
/// false for any other word.
bool parse_type(std::string_view word, Type& t);
/// The value of type `t` stored at `p` in the given byte order; the caller has checked that the
/// bytes are there.
double decode(const unsigned char* p, Type t, bool big_endian);

enum class Encoding { Ascii, BinaryLittleEndian, BinaryBigEndian };

struct Property {
  std::string name;
  bool is_list = false;
  Type count_type = Type::UInt8;  ///< a list's length
  Type type = Type::Float32;      ///< the value, or a list's items
};

struct Element {
  std::string name;
  std::uint64_t count = 0;
  std::vector<Property> props;
  std::size_t line = 0;  ///< header line, for messages
};

/// The fewest bytes one record of `e` can take, to refuse a count the data cannot hold before
/// anything is allocated: a digit and a separator a property in ascii (a list's count included),
/// the value or the list's count in binary.
std::uint64_t min_record_bytes(Encoding encoding, const Element& e);

struct Header {
  Encoding encoding = Encoding::Ascii;
  std::vector<Element> elements;
  std::vector<std::string_view> comments;  ///< the 'comment' lines, whole
  std::size_t end_line = 0;                ///< the line of 'end_header'
  std::size_t body_offset = 0;             ///< the first byte after it
};

/// What is wrong with a header.
enum class Problem {
  NotPly,                 ///< line 1 is not "ply"
  NoEndHeader,            ///< the text ends before 'end_header'
  NoFormat,               ///< 'end_header' with no 'format' line before it
  BadFormatLine,          ///< not 'format <kind> 1.0'
  BigEndian,              ///< binary_big_endian, in a dialect without it
  UnknownFormat,          ///< {}: the kind
  BadElementLine,         ///< not 'element <name> <count>'
  BadCount,               ///< {}: the count
  PropertyBeforeElement,  ///< a 'property' line before any 'element'
  BadPropertyLine,        ///< neither 'property <type> <name>' nor 'property list <t> <t> <name>'
  ListCountNotInteger,    ///< {}: the list's count type
  UnknownType,            ///< {}: the type
  DuplicateProperty,      ///< {}: the name
  UnexpectedWord,         ///< {}: the first word of the line
  kCount
};

/// A reader's message for each Problem, in the order above; "{}" stands for the offending word
/// (its first 40 characters).
using Words = std::array<std::string_view, static_cast<std::size_t>(Problem::kCount)>;

/// Whether every Problem has its words (a table one entry short leaves the last one empty).
constexpr bool all_worded(const Words& words) {
  for (std::string_view w : words)
    if (w.empty()) return false;
  return true;
}

/// What a reader accepts besides the common grammar, and how it words a problem. The defaults are
/// the mesh reader's; the frame reader's dialect is narrower (io/ply.cpp). Each field but the last
/// two is a difference the two readers had before they shared this parser, kept so that no file
/// changed its fate.
struct Dialect {
  std::string_view blanks = " \t\r\v\f";  ///< the characters between the words of a line
  bool magic_only = false;     ///< line 1 need only start with "ply" and '\n' or '\r' (else: "ply")
  bool final_newline = false;  ///< every header line ends with '\n' (else the file's last need not)
  bool big_endian = true;      ///< binary_big_endian is accepted (else Problem::BigEndian)
  bool saturate_counts = true;     ///< a count past 2^64 - 1 reads as 2^64 - 1 (else BadCount)
  bool unique_properties = false;  ///< a property named twice in an element is refused
  std::size_t name_chars = std::string::npos;  ///< names are cut to this length
  std::string_view line_label = ":";  ///< "FILE" LABEL "LINE: what", e.g. ":" or ": header line "
  const Words* words = nullptr;       ///< required
};

/// Parses the header at the start of `data`, `file` standing for the file in messages. Throws
/// InputError "FILE" + line_label + "LINE: " + the dialect's words for the first problem.
Header parse_header(std::string_view data, const Dialect& dialect, const std::string& file);

/// The words of a line, separated by any of `blanks`.
std::vector<std::string_view> split_words(std::string_view line, std::string_view blanks);

}  // namespace sandflow::ply
