// A picture or movie is whole by its structure, not by its program's exit status: every cut of a
// real PNG and MP4 is found, and a movie cut by a full disk (ffmpeg 5.1 exits 0 there) is refused.
#include "io/media_check.hpp"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "core/process.hpp"
#include "io/png_gray.hpp"
#include "io/pov_writer.hpp"
#include "support/scratch.hpp"
#include "support/small_disk.hpp"

namespace sandflow {
namespace {

namespace fs = std::filesystem;
using test::read_bytes;
using test::ScratchFolder;
using test::write_bytes;

// `count` pictures of grey noise, FOLDER/0001.png on: noise so that the movie of them is large
// (about 3.5 kB a frame at 128 x 96).
void write_noise_frames(const fs::path& folder, int count, int width = 128, int height = 96) {
  fs::create_directories(folder);
  std::uint32_t state = 12345;
  std::vector<double> value(static_cast<std::size_t>(width) * height);
  for (int k = 1; k <= count; ++k) {
    for (double& v : value) {
      state = state * 1664525u + 1013904223u;
      v = (state >> 8) / 16777216.0;
    }
    char name[16];
    std::snprintf(name, sizeof name, "%04d.png", k);
    write_gray_png((folder / name).string(), width, height, value, 8);
  }
}

TEST(PngProblem, AWholePictureHasNoneAndEveryCutOneIsFound) {
  ScratchFolder box;
  write_noise_frames(box.dir(), 1, 20, 10);
  const std::string png = box.path("0001.png");
  EXPECT_EQ(png_problem(png), "");
  const std::string bytes = read_bytes(png);
  for (std::size_t cut = 0; cut < bytes.size(); ++cut) {
    write_bytes(box.path("cut.png"), bytes.substr(0, cut));
    EXPECT_NE(png_problem(box.path("cut.png")), "") << "cut after " << cut << " bytes";
  }
  write_bytes(box.path("cut.png"), bytes.substr(0, bytes.size() - 1));
  EXPECT_NE(png_problem(box.path("cut.png")).find("without its IEND chunk"), std::string::npos);
  write_bytes(box.path("text.png"), std::string(100, 'x'));
  EXPECT_NE(png_problem(box.path("text.png")).find("not a PNG"), std::string::npos);
  EXPECT_NE(png_problem(box.path("absent.png")).find("cannot read it: No such file"),
            std::string::npos);
  // a FIFO where a picture should be is refused by its type, not waited on for a writer
  ASSERT_EQ(::mkfifo(box.path("fifo.png").c_str(), 0600), 0);
  EXPECT_EQ(png_problem(box.path("fifo.png")), "it is a FIFO, not a file");
}

class Mp4Problem : public ::testing::Test {
 protected:
  void SetUp() override {
    if (find_program("ffmpeg").empty()) GTEST_SKIP() << "ffmpeg is not installed";
  }
  ScratchFolder box;
};

TEST_F(Mp4Problem, AWholeMovieHasNoneAndEveryCutOneIsFound) {
  write_noise_frames(box.dir() / "frames", 6, 32, 24);
  const std::string movie = box.path("movie.mp4");
  encode_movie({(box.dir() / "frames").string()}, 1, 6, 30.0, movie);
  EXPECT_EQ(mp4_problem(movie, 6), "");
  EXPECT_EQ(mp4_problem(movie, 7), "it holds 6 frames, not 7");
  const std::string bytes = read_bytes(movie);
  ASSERT_GT(bytes.size(), 1000u);
  for (std::size_t cut = 0; cut < bytes.size(); ++cut) {
    write_bytes(box.path("cut.mp4"), bytes.substr(0, cut));
    EXPECT_NE(mp4_problem(box.path("cut.mp4"), 6), "") << "cut after " << cut << " bytes";
  }
  write_bytes(box.path("cut.mp4"), bytes.substr(0, bytes.size() - 1));
  EXPECT_NE(mp4_problem(box.path("cut.mp4"), 6).find("cut short"), std::string::npos);
  write_bytes(box.path("text.mp4"), std::string(100, 'x'));
  EXPECT_NE(mp4_problem(box.path("text.mp4"), 6).find("not an MP4"), std::string::npos);
}

// ffmpeg 5.1 on a full disk logs "Error writing trailer ...: No space left on device" and exits
// with status 0, its movie cut after a few kilobytes: the movie is refused, and the disk named.
TEST_F(Mp4Problem, AMovieCutByAFullDiskIsRefusedThoughFfmpegEndsWell) {
  const fs::path small = box.dir() / "small";
  const test::SmallDisk disk(small, 1 << 20);
  if (!disk.mounted()) GTEST_SKIP() << disk.why_not();
  write_noise_frames(box.dir() / "frames", 20);
  // 24 kB left: room for ffmpeg's log (about 3 kB), not for the movie (about 70 kB)
  ASSERT_TRUE(disk.fill_to(24'000));
  const std::string movie = (small / "movie.mp4").string();
  try {
    encode_movie({(box.dir() / "frames").string()}, 1, 20, 30.0, movie);
    ADD_FAILURE() << "a movie was made on a full disk";
  } catch (const OutputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(movie + ": ffmpeg ended as if done, but what it wrote is not whole: "),
              std::string::npos)
        << what;
    EXPECT_NE(what.find("; the disk holding " + small.string() + " is full ("), std::string::npos)
        << what;
  }
  EXPECT_FALSE(fs::exists(movie));
  EXPECT_FALSE(fs::exists(movie + ".partial"));
  // with room made, the same call makes the whole movie
  fs::remove(disk.filler());
  encode_movie({(box.dir() / "frames").string()}, 1, 20, 30.0, movie);
  EXPECT_EQ(mp4_problem(movie, 20), "");
}

}  // namespace
}  // namespace sandflow
