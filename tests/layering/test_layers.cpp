// The layers of src/ run one way (docs/design.md, "Layers"; issue 23): a folder includes only
// itself and the folders below it in kLayers. The test reads every file under src/, takes each
// #include of a project header ("folder/file.hpp", or <folder/...> where folder is one of src/'s
// folders), and fails naming file:line for each include that reaches up, into a folder that is
// not a layer, or out of its folder by a relative path. apps/ sits on top and may include anything,
// so it is not read. A new folder under src/ fails the test until it is given its place here and
// in docs/design.md.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace sandflow {
namespace {

namespace fs = std::filesystem;

/// The layers of src/, from the bottom. Written once; docs/design.md carries the same line.
const std::vector<std::string> kLayers = {"core",       "config",   "geometry", "dem",
                                          "surface",    "analysis", "sim",      "calibration",
                                          "checkpoint", "io",       "scene",    "report"};

/// One #include of a project header: the including file (relative to src/), its line, and the
/// first component of the included path (the folder it reaches).
struct Include {
  std::string file;
  int line = 0;
  std::string folder;
};

/// The messages for every include that breaks the order `layers` (bottom first): "file:line: ...".
/// A file's own folder is the first component of its path; a file outside every layer and an
/// include of a folder that is not a layer are reported too, so nothing escapes the order.
std::vector<std::string> layering_errors(const std::vector<std::string>& layers,
                                         const std::vector<Include>& includes) {
  auto rank = [&](const std::string& folder) {
    const auto it = std::find(layers.begin(), layers.end(), folder);
    return it == layers.end() ? -1 : static_cast<int>(it - layers.begin());
  };
  std::vector<std::string> errors;
  for (const Include& inc : includes) {
    const std::string where = "src/" + inc.file + ":" + std::to_string(inc.line) + ": ";
    const auto slash = inc.file.find('/');
    const std::string own = slash == std::string::npos ? std::string() : inc.file.substr(0, slash);
    const int from = rank(own), to = rank(inc.folder);
    if (from < 0) {
      errors.push_back(where + "the file is in no layer ('" + own + "' is not in the order)");
    } else if (to < 0) {
      errors.push_back(where + own + " includes '" + inc.folder + "', which is not a layer");
    } else if (to > from) {
      errors.push_back(where + own + " includes " + inc.folder + ", a layer above it");
    }
  }
  return errors;
}

/// The target of an `#include "x"` or `#include <x>` line, and whether it was quoted; false for
/// any other line. (By hand, not std::regex: GCC 12's <regex> warns inside itself under the
/// sanitizer build, and warnings are errors there.)
bool include_target(const std::string& line, bool& quoted, std::string& target) {
  std::size_t k = 0;
  auto skip_blanks = [&] {
    while (k < line.size() && (line[k] == ' ' || line[k] == '\t')) ++k;
  };
  skip_blanks();
  if (k >= line.size() || line[k] != '#') return false;
  ++k;
  skip_blanks();
  if (line.compare(k, 7, "include") != 0) return false;
  k += 7;
  skip_blanks();
  if (k >= line.size() || (line[k] != '"' && line[k] != '<')) return false;
  quoted = line[k] == '"';
  const std::size_t end = line.find_first_of("\">", k + 1);
  if (end == std::string::npos || end == k + 1) return false;
  target = line.substr(k + 1, end - k - 1);
  return true;
}

/// Every project include of every file under `src`, in a fixed order (paths sorted).
std::vector<Include> read_includes(const fs::path& src) {
  std::vector<std::string> folders;
  for (const auto& e : fs::directory_iterator(src)) {
    if (e.is_directory()) folders.push_back(e.path().filename().string());
  }
  std::vector<fs::path> files;
  for (const auto& e : fs::recursive_directory_iterator(src)) {
    if (e.is_regular_file()) files.push_back(e.path());
  }
  std::sort(files.begin(), files.end());

  std::vector<Include> out;
  for (const fs::path& path : files) {
    const std::string file = path.lexically_relative(src).generic_string();
    const auto slash = file.find('/');
    const std::string own = slash == std::string::npos ? std::string() : file.substr(0, slash);
    std::ifstream in(path);
    std::string text;
    for (int line = 1; std::getline(in, text); ++line) {
      bool quoted = false;
      std::string target;
      if (!include_target(text, quoted, target)) continue;
      const auto cut = target.find('/');
      if (cut == std::string::npos) {
        // "name.hpp" is found beside the including file: its own folder. <vector> is the system's.
        if (quoted) out.push_back({file, line, own});
        continue;
      }
      const std::string folder = target.substr(0, cut);
      const bool ours = std::find(folders.begin(), folders.end(), folder) != folders.end();
      if (quoted || ours) out.push_back({file, line, folder});  // "../x" gives "..": no layer
    }
  }
  return out;
}

std::string joined(const std::vector<std::string>& lines) {
  std::string s;
  for (const std::string& l : lines) s += l + "\n";
  return s;
}

TEST(Layers, NoFolderOfSrcIncludesALayerAboveIt) {
  const fs::path src = fs::path(SANDFLOW_SOURCE_DIR) / "src";
  const std::vector<Include> includes = read_includes(src);
  // the reader found the includes (a broken pattern must not pass by finding none)
  ASSERT_GT(includes.size(), 200u);
  const std::vector<std::string> errors = layering_errors(kLayers, includes);
  EXPECT_TRUE(errors.empty()) << "includes against the order of the layers (bottom first: core, "
                                 "config, ...; see docs/design.md):\n"
                              << joined(errors);
}

TEST(Layers, EveryFolderOfSrcHasItsPlaceInTheOrder) {
  std::vector<std::string> folders;
  for (const auto& e : fs::directory_iterator(fs::path(SANDFLOW_SOURCE_DIR) / "src")) {
    if (e.is_directory()) folders.push_back(e.path().filename().string());
  }
  std::sort(folders.begin(), folders.end());
  std::vector<std::string> layers = kLayers;
  std::sort(layers.begin(), layers.end());
  EXPECT_EQ(folders, layers);
}

TEST(Layers, DesignDocCarriesTheSameOrder) {
  std::ifstream in(fs::path(SANDFLOW_SOURCE_DIR) / "docs" / "design.md");
  ASSERT_TRUE(in) << "docs/design.md";
  std::stringstream doc;
  doc << in.rdbuf();
  std::string line = "Layers, from the bottom:";
  for (const std::string& l : kLayers) line += " " + l;
  EXPECT_NE(doc.str().find(line), std::string::npos) << "docs/design.md lacks the line\n" << line;
}

TEST(Layers, AnIncludeThatReachesUpIsReportedWithItsFileAndLine) {
  const std::vector<std::string> layers = {"core", "dem", "sim", "io"};
  const std::vector<Include> includes = {
      {"core/vec3.hpp", 3, "core"},   // its own folder
      {"sim/world.hpp", 12, "dem"},   // down
      {"dem/grains.hpp", 17, "sim"},  // up: the one to report
      {"io/ply.cpp", 4, "core"},      // down, over two layers
  };
  const std::vector<std::string> errors = layering_errors(layers, includes);
  ASSERT_EQ(errors.size(), 1u) << joined(errors);
  EXPECT_EQ(errors[0], "src/dem/grains.hpp:17: dem includes sim, a layer above it");
}

TEST(Layers, FoldersOutsideTheOrderAreReported) {
  const std::vector<std::string> layers = {"core", "sim"};
  const std::vector<std::string> errors = layering_errors(
      layers, {{"sim/world.cpp", 5, ".."}, {"tools/x.cpp", 2, "core"}, {"top.hpp", 1, "core"}});
  ASSERT_EQ(errors.size(), 3u) << joined(errors);
  EXPECT_EQ(errors[0], "src/sim/world.cpp:5: sim includes '..', which is not a layer");
  EXPECT_EQ(errors[1], "src/tools/x.cpp:2: the file is in no layer ('tools' is not in the order)");
  EXPECT_EQ(errors[2], "src/top.hpp:1: the file is in no layer ('' is not in the order)");
}

TEST(Layers, TheReaderFindsTheIncludesOfAFile) {
  // a small tree in the temporary folder: quoted, angled (ours and the system's), relative
  const fs::path root = fs::temp_directory_path() / "sandflow_layers_reader";
  fs::remove_all(root);
  fs::create_directories(root / "core");
  fs::create_directories(root / "sim");
  std::ofstream(root / "core" / "a.hpp") << "#pragma once\n#include <vector>\n";
  std::ofstream(root / "sim" / "b.cpp") << "#include \"sim/b.hpp\"\n"
                                           "\n"
                                           "  #  include <core/a.hpp>\n"
                                           "#include \"b_detail.hpp\"\n"
                                           "#include \"../core/a.hpp\"\n"
                                           "#include <fmt/format.h>\n"
                                           "// #include \"io/not_an_include.hpp\"\n";
  const std::vector<Include> got = read_includes(root);
  fs::remove_all(root);
  ASSERT_EQ(got.size(), 4u);
  auto is = [](const Include& i, const char* file, int line, const char* folder) {
    return i.file == file && i.line == line && i.folder == folder;
  };
  EXPECT_TRUE(is(got[0], "sim/b.cpp", 1, "sim"));
  EXPECT_TRUE(is(got[1], "sim/b.cpp", 3, "core"));
  EXPECT_TRUE(is(got[2], "sim/b.cpp", 4, "sim"));
  EXPECT_TRUE(is(got[3], "sim/b.cpp", 5, ".."));
}

}  // namespace
}  // namespace sandflow
