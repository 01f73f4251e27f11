// The one atomic file writer (core/atomic_file.hpp): a file appears whole or not at all, the
// temporary file never stays behind, and failures name the path and the system's reason.
#include "core/atomic_file.hpp"

#include <gtest/gtest.h>

#include <cerrno>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>

#include <unistd.h>

#include "core/error.hpp"
#include "support/scratch.hpp"

namespace sandflow {
namespace {

namespace fs = std::filesystem;

class AtomicFileTest : public test::ScratchTest {
 protected:
  static std::string read_text(const std::string& p) { return test::read_bytes(p); }

  // Expects `f` to throw OutputError whose message contains `what`.
  template <class F>
  static void expect_output_error(F f, const std::string& what) {
    try {
      f();
      FAIL() << "no error, expected " << what;
    } catch (const OutputError& e) {
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  }

  fs::path dir_;
};

TEST_F(AtomicFileTest, StreamedPiecesBecomeTheFileAtCommit) {
  for (const Sync sync : {Sync::Now, Sync::Later}) {
    const std::string p = path("out.txt");
    {
      AtomicFile file(p, sync);
      file.write("first ");
      file.write("");
      file.write("second");
      EXPECT_FALSE(fs::exists(p));  // nothing under the name until the commit
      EXPECT_TRUE(fs::exists(p + ".tmp"));
      file.commit();
    }
    EXPECT_EQ(read_text(p), "first second");
    EXPECT_FALSE(fs::exists(p + ".tmp"));
    fs::remove(p);
  }
}

TEST_F(AtomicFileTest, UncommittedLeavesTheOldFileAndNoTemporary) {
  const std::string p = path("keep.txt");
  write_file_atomic(p, "old");
  try {
    AtomicFile file(p);
    file.write("half of the new");
    throw std::runtime_error("the writer failed");
  } catch (const std::runtime_error&) {
  }
  EXPECT_EQ(read_text(p), "old");
  EXPECT_FALSE(fs::exists(p + ".tmp"));
}

TEST_F(AtomicFileTest, ReplacesAnExistingFile) {
  const std::string p = path("f.bin");
  write_file_atomic(p, std::string("a\0b", 3));
  write_file_atomic(p, "new", Sync::Later);
  EXPECT_EQ(read_text(p), "new");
}

TEST_F(AtomicFileTest, WriterByNameIsCommittedOrCleanedUp) {
  const std::string p = path("img.png");
  write_file_atomic_by_name(p, [](const std::string& tmp) {
    EXPECT_EQ(fs::path(tmp).filename(), "img.png.tmp");
    std::ofstream(tmp) << "pixels";
  });
  EXPECT_EQ(read_text(p), "pixels");
  EXPECT_FALSE(fs::exists(p + ".tmp"));
  // a writer that fails halfway: its exception passes on, the temporary goes, the file stays
  EXPECT_THROW(write_file_atomic_by_name(p,
                                         [](const std::string& tmp) {
                                           std::ofstream(tmp) << "half";
                                           throw OutputError(tmp + ": cannot write the PNG");
                                         }),
               OutputError);
  EXPECT_EQ(read_text(p), "pixels");
  EXPECT_FALSE(fs::exists(p + ".tmp"));
}

TEST_F(AtomicFileTest, FailuresNameThePathAndTheReason) {
  const std::string missing = path("no/such/folder/f.txt");
  expect_output_error([&] { write_file_atomic(missing, "x"); },
                      missing + ": cannot create " + missing + ".tmp: No such file or directory");
  // the target is a non-empty folder: the rename fails, and the temporary goes
  const std::string folder = path("folder");
  fs::create_directories(fs::path(folder) / "inside");
  expect_output_error([&] { write_file_atomic(folder, "x", Sync::Later); },
                      folder + ": cannot rename " + folder + ".tmp: ");
  EXPECT_FALSE(fs::exists(folder + ".tmp"));
  expect_output_error([&] { sync_dir(path("nowhere")); },
                      path("nowhere") + ": cannot flush the folder to the disk: No such file");
}

TEST(SystemReason, NamesTheErrorOrSaysItIsUnknown) {
  EXPECT_EQ(system_reason(ENOENT), "No such file or directory");
  EXPECT_EQ(system_reason(0), "unknown I/O error");
}

}  // namespace
}  // namespace sandflow
