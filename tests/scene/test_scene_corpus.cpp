// The malformed scene corpus tests/data/scenes/bad/ (written by make_scenes.py, also the fuzzing
// seeds): truncated files, absurd counts and grids, NaN and infinity, negative sizes, wrong types,
// unknown and duplicate keys, binary garbage, and what the TOML library cannot be given safely.
// Each file starts with "# expect: TEXT"; loading it must raise InputError whose message starts
// with "PATH:LINE:COL: " and contains TEXT, and `sandflow run FILE --check` must exit with 2.
#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "../app/cli_runner.hpp"
#include "core/error.hpp"
#include "scene/scene_loader.hpp"

namespace sandflow {
namespace {

namespace fs = std::filesystem;

const fs::path kCorpus = fs::path(SANDFLOW_SOURCE_DIR) / "tests/data/scenes/bad";

std::vector<std::string> corpus_files() {
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(kCorpus))
    if (entry.path().extension() == ".toml") names.push_back(entry.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

// The text after "# expect: " on the file's first line.
std::string expected_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::string first;
  std::getline(in, first);
  const std::string tag = "# expect: ";
  return first.rfind(tag, 0) == 0 ? first.substr(tag.size()) : std::string();
}

// "LINE:COLUMN: ..." (std::regex would do, but GCC 12 warns falsely inside it under ASan).
bool starts_with_line_column(const std::string& s) {
  std::size_t i = 0;
  for (int field = 0; field < 2; ++field) {
    const std::size_t digits = i;
    while (i < s.size() && std::isdigit(static_cast<unsigned char>(s[i]))) ++i;
    if (i == digits || i >= s.size() || s[i] != ':') return false;
    ++i;
  }
  return i < s.size() && s[i] == ' ';
}

class SceneCorpus : public ::testing::TestWithParam<std::string> {};

TEST_P(SceneCorpus, RefusedWithFileLineColumnAndWhat) {
  const fs::path path = kCorpus / GetParam();
  const std::string expect = expected_text(path);
  ASSERT_FALSE(expect.empty()) << path << " has no '# expect: TEXT' first line";
  try {
    load_scene(path.string());
    FAIL() << "no error for " << path;
  } catch (const InputError& e) {
    const std::string msg = e.what();
    const std::string prefix = path.string() + ":";
    ASSERT_EQ(msg.rfind(prefix, 0), 0u) << msg;
    EXPECT_TRUE(starts_with_line_column(msg.substr(prefix.size()))) << "no line:column in " << msg;
    EXPECT_NE(msg.find(expect), std::string::npos) << "expected '" << expect << "' in " << msg;
  }
}

INSTANTIATE_TEST_SUITE_P(Bad, SceneCorpus, ::testing::ValuesIn(corpus_files()),
                         [](const ::testing::TestParamInfo<std::string>& p) {
                           std::string n = p.param.substr(0, p.param.find('.'));
                           for (char& c : n)
                             if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
                           return n;
                         });

TEST(SceneCorpusCli, CheckExitsWithTwoOnEveryFile) {
  // the whole command, not only the loader: no crash, status 2, the error names the file
  int checked = 0;
  for (const std::string& name : corpus_files()) {
    const fs::path path = kCorpus / name;
    std::string out;
    const int rc = sandflow_test::run_sandflow("run \"" + path.string() + "\" --check", &out);
    EXPECT_EQ(rc, 2) << name << ":\n" << out;
    EXPECT_NE(out.find("error: " + path.string() + ":"), std::string::npos) << name << ":\n" << out;
    ++checked;
  }
  EXPECT_GE(checked, 40);
}

TEST(SceneLimits, OverlongFileIsRefusedBeforeParsing) {
  const std::string big(kMaxSceneBytes + 1, '#');
  try {
    load_scene_from_string(big, "big.toml");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), "big.toml: the scene is " + std::to_string(big.size()) +
                                         " bytes, more than the limit of " +
                                         std::to_string(kMaxSceneBytes));
  }
}

TEST(SceneLimits, ADeviceIsRefusedByItsType) {
  // /dev/zero never ends, and a FIFO blocks until a writer comes: neither is opened
  try {
    load_scene("/dev/zero");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("/dev/zero: the scene file is a character device, not a file"),
              std::string::npos)
        << e.what();
  }
}

TEST(SceneLimits, KeysUpToSixteenPartsAndStringsWithAnythingAreRead) {
  // the guard in front of toml++ must not refuse valid text: 16 parts, dots and non-ASCII
  // characters inside strings and comments, a float, an escaped quote in a multi-line string
  const std::string key16 = "a.b.c.d.e.f.g.h.i.j.k.l.m.n.o.p";
  try {
    load_scene_from_string(key16 + " = 1\n[[emitter]]\ncount = 1\n", "k.toml");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("k.toml:1:1: a is not a key of a scene file"),
              std::string::npos)
        << e.what();
  }
  const SceneConfig c = load_scene_from_string(
      "# sable fin, 0.1 mm \u00e9tal\u00e9\n"
      "[scene]\nname = \"d\u00fcne a.b.c.d.e.f.g.h.i.j.k.l.m.n.o.p.q.r\"\n"
      "description = \"\"\"a \\\"\"\" quote, \u00e0 la "
      "ligne\nx.y.z.a.b.c.d.e.f.g.h.i.j.k.l.m.n.o\"\"\"\n"
      "[material]\nfriction = 0.5  # \u00b1 0.1\n[[emitter]]\ncount = 1\n",
      "ok.toml");
  EXPECT_EQ(c.name, "d\u00fcne a.b.c.d.e.f.g.h.i.j.k.l.m.n.o.p.q.r");
  EXPECT_EQ(c.material.friction, 0.5);
}

TEST(SceneLimits, NonAsciiInStringsAndCommentsIsReadWhereverAStringMayStand) {
  // Each text is valid TOML with non-ASCII characters only in strings and comments: the guard in
  // front of toml++ must let it through (the loader then refuses the unknown keys).
  const char* texts[] = {
      R"(x = "é")",
      R"(x = ['é', "ü", '''ö''', """ä
ß"""])",
      R"(x = [
  # é
  "é",
  ["ü"],
])",
      R"(x = {"clé" = "é", b = ['ü'], c = {d = "ö"}})",
      R"(x = [{a = "é"}, {b = "ü"}])",
      R"(["té"]
a."é".'ü' = 1)",
      R"([["lé"]]
x = 1 # é)",
      R"(x = 1979-05-27 07:32:00 # é
y = +inf # é
z = 1.5e-3 # é)",
  };
  for (const char* t : texts) {
    std::string msg;
    try {
      load_scene_from_string(t, "u.toml");
    } catch (const InputError& e) {
      msg = e.what();
    }
    EXPECT_EQ(msg.find("non-ASCII"), std::string::npos) << t << "\n" << msg;
    EXPECT_EQ(msg.find("Error while parsing"), std::string::npos) << t << "\n" << msg;
  }
}

TEST(SceneLimits, OverrideValuesGoThroughTheSameGuard) {
  // a value toml++ cannot read safely is taken as a string, as any text that is not TOML is
  const std::string deep = "{" + std::string("a.a.a.a.a.a.a.a.a.a.a.a.a.a.a.a.a.a.a.a") + " = 1}";
  const SceneConfig c =
      load_scene_from_string("[[emitter]]\ncount = 1\n", "o.toml", {{"scene.name", deep}});
  EXPECT_EQ(c.name, deep);
}

TEST(SceneLimits, TotalGrainsOverTheLimitAreRefusedAtTheEmitterThatPassesIt) {
  const std::string e = "[[emitter]]\ncount = 900_000_000\n";
  EXPECT_NO_THROW(load_scene_from_string(e + e, "g.toml"));
  try {
    load_scene_from_string(e + e + e, "g.toml");
    FAIL() << "no error";
  } catch (const InputError& err) {
    EXPECT_STREQ(err.what(),
                 "g.toml:6:1: emitter[2].count = 900000000 brings the scene to 2700000000 grains, "
                 "more than the limit of 2000000000 in all");
  }
}

}  // namespace
}  // namespace sandflow
