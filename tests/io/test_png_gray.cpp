// The grey PNG reader of heightmaps: the values of valid images (8 and 16 bits, interlaced, with
// alpha, 1 bit), and the malformed corpus tests/data/png/bad/ (written by make_pngs.py, also the
// fuzzing seeds): each file raises InputError naming the file, the byte where reading stopped and
// what is wrong.
#include "io/png_gray.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "core/error.hpp"

namespace sandflow {
namespace {

namespace fs = std::filesystem;

std::string png_path(const std::string& name) {
  return std::string(SANDFLOW_SOURCE_DIR) + "/tests/data/png/" + name;
}

std::string bytes_of(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

TEST(PngGray, ReadsEightAndSixteenBitValues) {
  // make_pngs.py: grey8 = (37 x + 91 y) mod 256, grey16 = (x + 10 y) * 1000, 5 x 4
  const GrayImage g8 = read_gray_png(png_path("grey8_5x4.png"), 4096);
  ASSERT_EQ(g8.width, 5);
  ASSERT_EQ(g8.height, 4);
  const GrayImage g16 = read_gray_png(png_path("grey16_5x4.png"), 4096);
  ASSERT_EQ(g16.value.size(), 20u);
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 5; ++x) {
      EXPECT_DOUBLE_EQ(g8.value[y * 5 + x], ((37 * x + 91 * y) % 256) / 255.0);
      EXPECT_DOUBLE_EQ(g16.value[y * 5 + x], (x + 10 * y) * 1000 / 65535.0);
    }
}

TEST(PngGray, InterlacedImageReadsAsTheSameImage) {
  // Adam7 sends the pixels in 7 passes; read row by row without putting the passes together,
  // the heights came out scrambled (row 1 read 4000, 0, 0, 0, 0).
  const GrayImage plain = read_gray_png(png_path("grey16_5x4.png"), 4096);
  const GrayImage inter = read_gray_png(png_path("grey16_5x4_interlaced.png"), 4096);
  ASSERT_EQ(inter.width, plain.width);
  ASSERT_EQ(inter.height, plain.height);
  EXPECT_EQ(inter.value, plain.value);
}

TEST(PngGray, AlphaIsIgnoredAndOneBitIsScaled) {
  const GrayImage ga = read_gray_png(png_path("grey_alpha_3x2.png"), 4096);
  ASSERT_EQ(ga.value.size(), 6u);
  for (int y = 0; y < 2; ++y)
    for (int x = 0; x < 3; ++x) EXPECT_DOUBLE_EQ(ga.value[y * 3 + x], ((50 * x + y) % 256) / 255.0);
  // rows 0xa5 = 10100101 and 0x0f = 00001111: a set bit is full grey
  const GrayImage g1 = read_gray_png(png_path("grey1_8x2.png"), 4096);
  ASSERT_EQ(g1.value.size(), 16u);
  const std::vector<double> want = {1, 0, 1, 0, 0, 1, 0, 1, 0, 0, 0, 0, 1, 1, 1, 1};
  EXPECT_EQ(g1.value, want);
}

TEST(PngGray, BytesEntryPointMatchesTheFile) {
  const std::string path = png_path("grey16_5x4_interlaced.png");
  const GrayImage from_file = read_gray_png(path, 4096);
  const GrayImage from_bytes = parse_gray_png(bytes_of(path), "x.png", 4096);
  EXPECT_EQ(from_bytes.value, from_file.value);
  // the side limit is the caller's
  try {
    parse_gray_png(bytes_of(path), "x.png", 4);
    FAIL() << "a 5 x 4 image passed a limit of 4";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "x.png: byte 16: the image is 5 x 4 pixels: at most 4 x 4");
  }
}

struct BadPng {
  const char* name;
  const char* position;  ///< after "PATH: "
  const char* what;
};

// Each file of tests/data/png/bad/, the byte where the reader stopped and what it says.
constexpr BadPng kBadPngs[] = {
    {"empty.png", "byte 0", "not a PNG image (expected the 8-byte PNG signature)"},
    {"text.png", "byte 0", "not a PNG image"},
    {"truncated_signature.png", "byte 0", "not a PNG image"},
    {"truncated_ihdr.png", "byte 20", "unexpected end of data (file truncated?)"},
    {"truncated_idat.png", "byte 53", "unexpected end of data (file truncated?)"},
    {"no_iend.png", "byte 75", "unexpected end of data (file truncated?)"},
    {"bad_ihdr_crc.png", "byte 33", "IHDR: CRC error"},
    {"huge_100000x100000.png", "byte 16",
     "the image is 100000 x 100000 pixels: at most 4096 x 4096"},
    {"huge_width_2_31.png", "byte 33", "PNG unsigned integer out of range"},
    {"zero_width.png", "byte 33", "Invalid IHDR data (Image width is zero in IHDR)"},
    {"rgb.png", "byte 25", "a colour PNG (RGB): a heightmap must be a grey-scale PNG"},
    {"palette.png", "byte 25", "a colour PNG (palette)"},
    {"bad_bit_depth.png", "byte 33", "(Invalid bit depth in IHDR)"},
    {"bad_interlace_method.png", "byte 33", "(Unknown interlace method in IHDR)"},
    {"idat_not_zlib.png", "byte 77", "IDAT: incorrect header check"},
    {"idat_too_short.png", "byte 73", "Not enough image data"},
    {"bad_filter_type.png", "byte 71", "bad adaptive filter value"},
    {"missing_ihdr.png", "byte 16", "Missing IHDR before IDAT"},
    {"chunk_length_huge.png", "byte 57", "(IDAT: chunk data is too large)"},
    {"garbage_after_signature.png", "byte 16", "invalid chunk type"},
    {"itxt_announces_1_4_gb.png", "byte 44", "(iTXt: chunk data is too large)"},
};

TEST(PngGray, MalformedCorpusGivesClearErrors) {
  for (const BadPng& bad : kBadPngs) {
    const std::string path = png_path(std::string("bad/") + bad.name);
    ASSERT_TRUE(fs::exists(path)) << path;
    try {
      read_gray_png(path, 4096);
      ADD_FAILURE() << "no error for " << bad.name;
    } catch (const InputError& e) {
      const std::string msg = e.what();
      EXPECT_EQ(msg.rfind(path + ": " + bad.position + ": ", 0), 0u) << msg;
      EXPECT_NE(msg.find(bad.what), std::string::npos) << bad.what << " in " << msg;
    }
  }
}

TEST(PngGray, EveryCorpusFileIsListed) {
  std::set<std::string> listed;
  for (const BadPng& bad : kBadPngs) listed.insert(bad.name);
  for (const auto& entry : fs::directory_iterator(png_path("bad")))
    EXPECT_TRUE(listed.count(entry.path().filename().string()))
        << entry.path() << " is not in kBadPngs: give it its expected message";
}

// Found by fuzzing: libpng 1.6.39 only warns that a text chunk announcing 1.4 GB is too large,
// then allocates and zeroes it (6 s and 1.4 GB for a 44-byte file). The reader skips ancillary
// chunks unread; 1 s is a generous bound for refusing 44 bytes.
TEST(PngGray, HugeTextChunkIsNotAllocated) {
  const auto start = std::chrono::steady_clock::now();
  EXPECT_THROW(read_gray_png(png_path("bad/itxt_announces_1_4_gb.png"), 4096), InputError);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_LT(seconds, 1.0);
}

TEST(PngGray, FileErrorsNameThePath) {
  const std::string missing = png_path("no_such_file.png");
  try {
    read_gray_png(missing, 4096);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(missing + ": cannot open the image"), std::string::npos)
        << e.what();
  }
  // a folder (or a FIFO, a device) is refused by its type, before it is opened
  try {
    read_gray_png(png_path("bad"), 4096);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(png_path("bad") + ": the image is a folder, not a file"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace sandflow
