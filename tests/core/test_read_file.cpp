// The one whole-file reader (core/read_file.hpp): the bytes as they are on the disk, and for
// anything that is not a readable regular file within the limit, an error that names the file,
// what it was read as and why, before any byte is read where the type or size already says so.
#include "core/read_file.hpp"

#include <gtest/gtest.h>

#include <string>

#include <sys/stat.h>
#include <unistd.h>

#include "core/error.hpp"
#include "support/input_error.hpp"
#include "support/scratch.hpp"

namespace sandflow {
namespace {

using test::input_error;

TEST(ReadWholeFile, ReturnsTheBytesAsTheyAre) {
  const test::ScratchFolder box;
  std::string bytes(200'000, '\0');  // several pieces, with NULs and every byte value
  for (std::size_t i = 0; i < bytes.size(); ++i) bytes[i] = static_cast<char>(i * 7919 % 256);
  const std::string path = box.write("data.bin", bytes);
  EXPECT_EQ(read_whole_file(path, "frame", kAnyFileSize), bytes);
  EXPECT_EQ(read_whole_file(box.write("empty", ""), "frame", 0), "");
  // the limit is the largest size read, not the first refused
  EXPECT_EQ(read_whole_file(path, "frame", bytes.size()), bytes);
}

TEST(ReadWholeFile, RefusesWhatIsNoRegularFileByItsType) {
  const test::ScratchFolder box;
  EXPECT_EQ(input_error([] { read_whole_file("/dev/zero", "frame", kAnyFileSize); }),
            "/dev/zero: the frame is a character device, not a file");
  EXPECT_EQ(input_error([&] { read_whole_file(box.dir().string(), "scene file", 100); }),
            box.dir().string() + ": the scene file is a folder, not a file");
  const std::string fifo = box.path("fifo");
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  // (opened, it would wait for a writer for ever)
  EXPECT_EQ(input_error([&] { read_whole_file(fifo, "image", 100); }),
            fifo + ": the image is a FIFO, not a file");
}

TEST(ReadWholeFile, SaysWhyItCannotOpen) {
  const test::ScratchFolder box;
  const std::string missing = box.path("missing.toml");
  EXPECT_EQ(input_error([&] { read_whole_file(missing, "scene file", 100); }),
            missing + ": cannot open the scene file: No such file or directory");
  if (::geteuid() != 0) {  // (root reads anything)
    const std::string locked = box.write("locked.toml", "x = 1\n");
    ::chmod(locked.c_str(), 0);
    EXPECT_EQ(input_error([&] { read_whole_file(locked, "scene file", 100); }),
              locked + ": cannot open the scene file: Permission denied");
  }
}

TEST(ReadWholeFile, RefusesAFileOverTheLimit) {
  const test::ScratchFolder box;
  const std::string path = box.write("big.ply", std::string(1001, 'x'));
  EXPECT_EQ(input_error([&] { read_whole_file(path, "frame", 1000); }),
            path + ": the frame is larger than the limit of 1000 bytes");
}

// A file a command writes later (a run's summary) may not be there yet; anything else that is
// wrong with it is still said.
TEST(ReadWholeFile, AFileNotThereYetIsNothingNotAnError) {
  const test::ScratchFolder box;
  EXPECT_EQ(read_file_if_present(box.path("summary.json"), "summary", 100), std::nullopt);
  EXPECT_EQ(read_file_if_present(box.write("summary.json", "{}"), "summary", 100), "{}");
  ASSERT_EQ(::symlink("/dev/zero", box.path("zero").c_str()), 0);
  EXPECT_EQ(input_error([&] { read_file_if_present(box.path("zero"), "summary", 100); }),
            box.path("zero") + ": the summary is a character device, not a file");
  EXPECT_EQ(input_error([&] { read_file_if_present(box.write("big", "12345"), "summary", 4); }),
            box.path("big") + ": the summary is larger than the limit of 4 bytes");
}

}  // namespace
}  // namespace sandflow
