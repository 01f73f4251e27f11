#include "io/ply.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include <unistd.h>

#include "core/error.hpp"
#include "core/rng.hpp"
#include "support/scratch.hpp"

namespace sandflow {
namespace {

namespace fs = std::filesystem;

using test::read_bytes;
using test::write_bytes;

class PlyTest : public test::ScratchTest {
 protected:
  // Expects read_ply to throw InputError whose message names the file and contains `what`.
  void expect_input_error(const std::string& p, const std::string& what) const {
    try {
      read_ply(p);
      FAIL() << "no error for " << p;
    } catch (const InputError& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find(p), std::string::npos) << msg;
      EXPECT_NE(msg.find(what), std::string::npos) << msg;
    }
  }

  fs::path dir_;
};

FrameData ply_sample_frame() {
  FrameData f;
  for (int i = 0; i < 100; ++i) {
    f.position.push_back({0.01 * i, -0.5 + 0.003 * i, 1.25 - 0.007 * i});
    f.radius.push_back(0.005 + 0.0001 * (i % 7));
    f.velocity.push_back({0.1 * (i % 3), -0.2, 0.05 * i});
    f.id.push_back(static_cast<std::uint32_t>(1000 + 3 * i));
    f.state.push_back(static_cast<std::uint8_t>(i % 2));
  }
  return f;
}

TEST_F(PlyTest, RoundTrip) {
  const FrameData f = ply_sample_frame();
  const std::string p = path("frame.ply");
  write_ply(p, f);
  EXPECT_FALSE(fs::exists(p + ".tmp"));
  // 33 bytes a grain after the header.
  const std::string bytes = read_bytes(p);
  const std::size_t body = bytes.find("end_header\n") + 11;
  EXPECT_EQ(bytes.size() - body, 33u * f.size());

  const FrameData g = read_ply(p);
  ASSERT_EQ(g.size(), f.size());
  for (std::size_t i = 0; i < f.size(); ++i) {
    // Stored as float: relative precision 2^-24.
    for (int k = 0; k < 3; ++k) {
      EXPECT_FLOAT_EQ(g.position[i][k], static_cast<float>(f.position[i][k]));
      EXPECT_FLOAT_EQ(g.velocity[i][k], static_cast<float>(f.velocity[i][k]));
    }
    EXPECT_FLOAT_EQ(g.radius[i], static_cast<float>(f.radius[i]));
    EXPECT_EQ(g.id[i], f.id[i]);
    EXPECT_EQ(g.state[i], f.state[i]);
  }
}

TEST_F(PlyTest, EmptyFrameAndDefaults) {
  FrameData f;
  write_ply(path("empty.ply"), f);
  EXPECT_EQ(read_ply(path("empty.ply")).size(), 0u);

  // Optional arrays left empty: velocity 0, id = index, state 0.
  f.position = {{1, 2, 3}, {4, 5, 6}};
  f.radius = {0.1, 0.2};
  write_ply(path("defaults.ply"), f);
  const FrameData g = read_ply(path("defaults.ply"));
  ASSERT_EQ(g.size(), 2u);
  EXPECT_EQ(g.id[1], 1u);
  EXPECT_EQ(g.velocity[1], Vec3(0, 0, 0));

  f.id = {7};  // wrong length: a caller bug
  EXPECT_THROW(write_ply(path("bad.ply"), f), std::invalid_argument);
}

TEST_F(PlyTest, OverwritesAtomically) {
  const std::string p = path("frame.ply");
  write_bytes(p, "old contents");
  write_ply(p, ply_sample_frame());
  EXPECT_EQ(read_ply(p).size(), 100u);
}

TEST_F(PlyTest, UnwritableFolderIsOutputError) {
  const std::string p = path("no/such/folder/frame.ply");
  try {
    write_ply(p, ply_sample_frame());
    FAIL() << "no error";
  } catch (const OutputError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find(p), std::string::npos) << msg;
    EXPECT_NE(msg.find("No such file or directory"), std::string::npos) << msg;
  }
}

TEST_F(PlyTest, TruncatedFileIsInputError) {
  const std::string p = path("frame.ply");
  write_ply(p, ply_sample_frame());
  std::string bytes = read_bytes(p);
  // Cut in the middle of a record, and then right after the header.
  write_bytes(p, bytes.substr(0, bytes.size() - 50));
  expect_input_error(p, "truncated");
  write_bytes(p, bytes.substr(0, bytes.find("end_header\n") + 11));
  expect_input_error(p, "truncated");
}

TEST_F(PlyTest, AbsurdCountIsInputError) {
  const std::string p = path("huge.ply");
  write_bytes(p,
              "ply\nformat binary_little_endian 1.0\nelement vertex 18446744073709551615\n"
              "property float x\nproperty float y\nproperty float z\nproperty float radius\n"
              "end_header\n0123456789abcdef");
  expect_input_error(p, "declares 18446744073709551615");
}

TEST_F(PlyTest, BadHeaderIsInputError) {
  const std::string p = path("bad.ply");
  write_bytes(p, "PLX\nformat ascii 1.0\nend_header\n");
  expect_input_error(p, "not a PLY file");
  write_bytes(p, "ply\nformat ascii 1.0\nelement vertex 1\nproperty flaot x\nend_header\n");
  expect_input_error(p, "header line 4: unknown property type 'flaot'");
  write_bytes(p, "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n");
  expect_input_error(p, "no 'end_header'");
  write_bytes(p, "ply\nformat binary_big_endian 1.0\nend_header\n");
  expect_input_error(p, "binary_big_endian");
  write_bytes(p, "ply\nformat ascii 1.0\nelement vertex -3\nend_header\n");
  expect_input_error(p, "not a non-negative integer");
  write_bytes(p,
              "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
              "property float z\nend_header\n1 2 3\n");
  expect_input_error(p, "no 'radius' property");
  expect_input_error(path("missing.ply"), "cannot open");
}

TEST_F(PlyTest, AsciiAnyOrderExtraPropertiesAndElements) {
  // A face element before the vertices, extra properties, another order, CRLF header lines.
  const std::string p = path("ascii.ply");
  write_bytes(p,
              "ply\r\nformat ascii 1.0\r\ncomment made by hand\r\n"
              "element face 2\r\nproperty list uchar int vertex_indices\r\n"
              "element vertex 2\r\nproperty double radius\r\nproperty uchar red\r\n"
              "property float z\r\nproperty float y\r\nproperty float x\r\nproperty int id\r\n"
              "end_header\r\n"
              "3 0 1 2\n4 0 1 2 3\n"
              "0.5 255 3 2 1 42\n"
              "0.25 0 -3e-1 .5 7 43\n");
  const FrameData f = read_ply(p);
  ASSERT_EQ(f.size(), 2u);
  EXPECT_EQ(f.position[0], Vec3(1, 2, 3));
  EXPECT_DOUBLE_EQ(f.position[1].z, -0.3);
  EXPECT_EQ(f.radius[1], 0.25);
  EXPECT_EQ(f.id[1], 43u);
  EXPECT_EQ(f.state[1], 0u);

  write_bytes(p,
              "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
              "property float z\nproperty float radius\nend_header\n1 2 3 0.1\n1 2 x 0.1\n");
  expect_input_error(p, "record 1: 'x' is not a number");
  write_bytes(p,
              "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
              "property float z\nproperty float radius\nend_header\n1 2 3 -0.1\n");
  expect_input_error(p, "vertex 0: radius");
}

TEST_F(PlyTest, BinaryWithListAndDoubles) {
  // binary_little_endian with a list property inside the vertex element and double coordinates.
  const std::string p = path("bin.ply");
  std::string bytes =
      "ply\nformat binary_little_endian 1.0\nelement vertex 2\nproperty double x\n"
      "property list uchar float extra\nproperty double y\nproperty double z\n"
      "property float radius\nend_header\n";
  auto put = [&bytes](auto v) { bytes.append(reinterpret_cast<const char*>(&v), sizeof v); };
  put(1.5);
  put(std::uint8_t{2});
  put(9.0f);
  put(9.0f);
  put(2.5);
  put(3.5);
  put(0.01f);
  put(-1.0);
  put(std::uint8_t{0});
  put(-2.0);
  put(-3.0);
  put(0.02f);
  write_bytes(p, bytes);
  const FrameData f = read_ply(p);
  ASSERT_EQ(f.size(), 2u);
  EXPECT_EQ(f.position[0], Vec3(1.5, 2.5, 3.5));
  EXPECT_EQ(f.position[1], Vec3(-1, -2, -3));
  EXPECT_FLOAT_EQ(f.radius[1], 0.02f);
  EXPECT_EQ(f.id[1], 1u);

  // A list that claims more items than the file holds.
  bytes[bytes.find("end_header\n") + 11 + 8] = static_cast<char>(200);
  write_bytes(p, bytes);
  expect_input_error(p, "list runs past the end");
}

TEST_F(PlyTest, CorruptFilesNeverCrash) {
  // Random byte flips and truncations of valid binary and ascii files: each read either succeeds
  // or throws InputError (run under the sanitizer build to catch out-of-bounds reads).
  const std::string p = path("fuzz.ply");
  FrameData f = ply_sample_frame();
  f.position.resize(5);
  f.radius.resize(5);
  f.velocity.resize(5);
  f.id.resize(5);
  f.state.resize(5);
  write_ply(p, f);
  const std::string binary = read_bytes(p);
  const std::string ascii =
      "ply\nformat ascii 1.0\nelement face 1\nproperty list uchar int vertex_indices\n"
      "element vertex 2\nproperty float x\nproperty float y\nproperty float z\n"
      "property float radius\nproperty uchar state\nend_header\n3 0 1 2\n1 2 3 0.1 1\n"
      "4 5 6 0.2 0\n";
  Rng rng(12345);
  int ok = 0, errors = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    std::string bytes = trial % 2 ? binary : ascii;
    const int flips = 1 + static_cast<int>(rng.next() % 4);
    for (int k = 0; k < flips; ++k) {
      bytes[rng.next() % bytes.size()] = static_cast<char>(rng.next() & 0xff);
    }
    if (rng.next() % 4 == 0) bytes.resize(rng.next() % bytes.size());
    // A fresh file each time: rewriting one in place makes ext4 flush it to disk (slow).
    fs::remove(p);
    write_bytes(p, bytes);
    try {
      read_ply(p);
      ++ok;
    } catch (const InputError&) {
      ++errors;
    }
  }
  EXPECT_EQ(ok + errors, 2000);
  EXPECT_GT(errors, 0);
}

}  // namespace
}  // namespace sandflow
