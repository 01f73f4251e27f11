// The PLY header parser both PLY readers use (geometry/ply_format.hpp): what it reads from a
// header, how a dialect changes what it accepts, and how a problem is worded. The readers' own
// messages are checked by their corpora (test_ply_corpus.cpp, test_mesh_io.cpp).
#include "geometry/ply_format.hpp"

#include <gtest/gtest.h>

#include <string>

#include "core/error.hpp"

namespace sandflow::ply {
namespace {

constexpr Words kTestWords = {
    "not ply",         "no end",      "no format",  "bad format",     "big endian",
    "kind '{}'",       "bad element", "count '{}'", "early property", "bad property",
    "count type '{}'", "type '{}'",   "twice '{}'", "word '{}'",
};
static_assert(all_worded(kTestWords));

// The message parse_header throws for `text`, or "" when it parses.
std::string problem(std::string_view text, const Dialect& d) {
  try {
    parse_header(text, d, "f.ply");
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(PlyFormat, ReadsElementsPropertiesAndWhereTheDataStarts) {
  const std::string text =
      "ply\r\n"
      "format binary_big_endian 1.0\n"
      "comment up_axis y\n"
      "obj_info made by hand\n"
      "element vertex 3\n"
      "property float x\n"
      "property double y\n"
      "\n"
      "element face 2\n"
      "property list uchar int vertex_indices\n"
      "end_header\n"
      "DATA";
  const Header h = parse_header(text, Dialect{.words = &kTestWords}, "f.ply");
  EXPECT_EQ(h.encoding, Encoding::BinaryBigEndian);
  ASSERT_EQ(h.elements.size(), 2u);
  EXPECT_EQ(h.elements[0].name, "vertex");
  EXPECT_EQ(h.elements[0].count, 3u);
  EXPECT_EQ(h.elements[0].line, 5u);
  ASSERT_EQ(h.elements[0].props.size(), 2u);
  EXPECT_EQ(h.elements[0].props[1].type, Type::Float64);
  const Property& list = h.elements[1].props.at(0);
  EXPECT_TRUE(list.is_list);
  EXPECT_EQ(list.count_type, Type::UInt8);
  EXPECT_EQ(list.type, Type::Int32);
  ASSERT_EQ(h.comments.size(), 1u);
  EXPECT_EQ(h.comments[0], "comment up_axis y");
  EXPECT_EQ(h.end_line, 11u);
  EXPECT_EQ(text.substr(h.body_offset), "DATA");
  // a digit and a separator a property in ascii; the value, or a list's count, in binary
  EXPECT_EQ(min_record_bytes(Encoding::Ascii, h.elements[0]), 4u);
  EXPECT_EQ(min_record_bytes(Encoding::BinaryBigEndian, h.elements[0]), 12u);
  EXPECT_EQ(min_record_bytes(Encoding::BinaryLittleEndian, h.elements[1]), 1u);
}

TEST(PlyFormat, ADialectNarrowsWhatIsAcceptedAndWordsTheProblem) {
  const Dialect lenient{.words = &kTestWords};
  const Dialect strict{.blanks = " \t",
                       .magic_only = true,
                       .final_newline = true,
                       .big_endian = false,
                       .saturate_counts = false,
                       .unique_properties = true,
                       .name_chars = 4,
                       .line_label = ": header line ",
                       .words = &kTestWords};
  const std::string head = "ply\nformat ascii 1.0\n";
  // big-endian data
  EXPECT_EQ(problem("ply\nformat binary_big_endian 1.0\nend_header\n", lenient), "");
  EXPECT_EQ(problem("ply\nformat binary_big_endian 1.0\nend_header\n", strict),
            "f.ply: header line 2: big endian");
  // a property named twice, and names cut to name_chars
  const std::string twice = head + "element vertex 1\nproperty float xxxx1\nproperty int xxxx2\n";
  EXPECT_EQ(problem(twice + "end_header\n", lenient), "");
  EXPECT_EQ(problem(twice + "end_header\n", strict), "f.ply: header line 5: twice 'xxxx'");
  // a count past 2^64 - 1
  const std::string huge = head + "element vertex 18446744073709551616\nend_header\n";
  EXPECT_EQ(problem(huge, lenient), "");
  EXPECT_EQ(problem(huge, strict), "f.ply: header line 3: count '18446744073709551616'");
  // a vertical tab between words, and a last line without its newline
  EXPECT_EQ(problem(head + "element\vvertex 1\nend_header\n", lenient), "");
  EXPECT_EQ(problem(head + "element\vvertex 1\nend_header\n", strict),
            "f.ply: header line 3: word 'element\vvertex'");
  EXPECT_EQ(problem(head + "end_header", lenient), "");
  EXPECT_EQ(problem(head + "end_header", strict), "f.ply: header line 3: no end");
  // line 1: "ply" exactly, or only "ply" and a line end
  EXPECT_EQ(problem("ply\rjunk\nformat ascii 1.0\nend_header\n", lenient), "f.ply:1: not ply");
  EXPECT_EQ(problem("ply\rjunk\nformat ascii 1.0\nend_header\n", strict), "");
}

TEST(PlyFormat, EveryProblemNamesItsLine) {
  const Dialect d{.words = &kTestWords};
  EXPECT_EQ(problem("", d), "f.ply:1: not ply");
  EXPECT_EQ(problem("ply\nformat ascii 1.0\n", d), "f.ply:3: no end");
  EXPECT_EQ(problem("ply\ncomment\nend_header\n", d), "f.ply:3: no format");
  EXPECT_EQ(problem("ply\nformat ascii 1.1\n", d), "f.ply:2: bad format");
  EXPECT_EQ(problem("ply\nformat middle_endian 1.0\n", d), "f.ply:2: kind 'middle_endian'");
  EXPECT_EQ(problem("ply\nelement vertex\n", d), "f.ply:2: bad element");
  EXPECT_EQ(problem("ply\nelement vertex -1\n", d), "f.ply:2: count '-1'");
  EXPECT_EQ(problem("ply\nproperty float x\n", d), "f.ply:2: early property");
  EXPECT_EQ(problem("ply\nelement v 1\nproperty float\n", d), "f.ply:3: bad property");
  EXPECT_EQ(problem("ply\nelement v 1\nproperty list float int i\n", d),
            "f.ply:3: count type 'float'");
  EXPECT_EQ(problem("ply\nelement v 1\nproperty flaot x\n", d), "f.ply:3: type 'flaot'");
  EXPECT_EQ(problem("ply\n" + std::string(50, 'w') + "\n", d),
            "f.ply:2: word '" + std::string(40, 'w') + "'");
}

TEST(PlyFormat, TypesAndTheirBytes) {
  Type t{};
  ASSERT_TRUE(parse_type("ushort", t));
  EXPECT_EQ(t, Type::UInt16);
  ASSERT_TRUE(parse_type("float64", t));
  EXPECT_EQ(type_size(t), 8u);
  EXPECT_FALSE(parse_type("float16", t));
  EXPECT_TRUE(is_integer(Type::Int8));
  EXPECT_FALSE(is_integer(Type::Float32));
  const unsigned char bytes[4] = {0x01, 0x02, 0x03, 0xff};
  EXPECT_EQ(decode(bytes, Type::UInt16, false), 0x0201);
  EXPECT_EQ(decode(bytes, Type::UInt16, true), 0x0102);
  EXPECT_EQ(decode(bytes + 3, Type::Int8, false), -1);
  EXPECT_EQ(decode(bytes, Type::Int32, true), 0x010203ff);
}

TEST(PlyFormat, SplitsWordsAtTheDialectsBlanks) {
  const auto w = split_words("  a\tb\vc  ", " \t");
  ASSERT_EQ(w.size(), 2u);
  EXPECT_EQ(w[0], "a");
  EXPECT_EQ(w[1], "b\vc");
  EXPECT_TRUE(split_words(" \t ", " \t").empty());
}

}  // namespace
}  // namespace sandflow::ply
