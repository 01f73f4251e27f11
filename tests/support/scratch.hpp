// A scratch folder for each test and whole-file reads and writes: tests that write files use
// these, so every test cleans up after itself the same way.
#pragma once

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <system_error>

#include <unistd.h>

namespace sandflow::test {

/// The whole of a file, byte for byte ("" when it cannot be read).
inline std::string read_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

/// Writes `bytes` as the whole of a file.
inline void write_bytes(const std::string& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary);
  out << bytes;
}

/// A fresh folder for the running test, named after its suite, its name and the process (ctest
/// runs tests in parallel processes), removed with everything in it when it goes out of scope.
class ScratchFolder {
 public:
  ScratchFolder() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = std::filesystem::temp_directory_path() /
           ("sandflow_" + std::string(info->test_suite_name()) + "_" + info->name() + "_" +
            std::to_string(::getpid()));
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  ~ScratchFolder() {
    std::error_code ec;  // a failed removal must not hide the test's own result
    std::filesystem::remove_all(dir_, ec);
  }
  ScratchFolder(const ScratchFolder&) = delete;
  ScratchFolder& operator=(const ScratchFolder&) = delete;

  const std::filesystem::path& dir() const { return dir_; }
  /// A file in the folder.
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  /// Writes `text` as the file `name` (its folders made as needed); returns its path.
  std::string write(const std::string& name, const std::string& text) const {
    std::filesystem::create_directories((dir_ / name).parent_path());
    write_bytes(path(name), text);
    return path(name);
  }

 private:
  std::filesystem::path dir_;
};

/// A fixture whose tests each get a ScratchFolder, as dir_.
class ScratchTest : public ::testing::Test {
 protected:
  std::string path(const std::string& name) const { return folder_.path(name); }

  ScratchFolder folder_;
  std::filesystem::path dir_ = folder_.dir();
};

}  // namespace sandflow::test
