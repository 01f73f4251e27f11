// What the report reads back: stats.csv (good, malformed, cut short), JSON files, frame lists,
// the contact sheet's choice of frames and PNG sizes.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "core/error.hpp"
#include "io/png_gray.hpp"
#include "report/run_data.hpp"
#include "support/input_error.hpp"
#include "support/scratch.hpp"

using namespace sandflow;
namespace fs = std::filesystem;

namespace {

const char* kHeader =
    "frame,time,substeps,dt,n_total,n_active,n_interface,n_static,contacts,wall_contacts,"
    "max_overlap_rel,kinetic_energy,rebuilds,trapped,dislodged,slept,woken,surface_updates,"
    "wall_seconds\n";

std::string row(int frame, int n_total) {
  return std::to_string(frame) + ",0.033333,328,1.01e-04," + std::to_string(n_total) +
         ",150,50,100,400,20,1.0e-02,1.0e-03,3,5,1,2,0,10,0.0123\n";
}

using TempDir = sandflow::test::ScratchFolder;

using sandflow::test::input_error;

}  // namespace

TEST(StatsCsv, ReadsEveryRowByColumnName) {
  TempDir t;
  const std::string path = t.write("stats.csv", kHeader + row(1, 300) + row(2, 300) + row(3, 280));
  const StatsTable s = read_stats_csv(path);
  EXPECT_EQ(s.frames(), 3u);
  EXPECT_EQ(s.note, "");
  EXPECT_EQ(s.column("frame"), (std::vector<double>{1, 2, 3}));
  EXPECT_EQ(s.column("n_total"), (std::vector<double>{300, 300, 280}));
  EXPECT_DOUBLE_EQ(s.column("dt")[0], 1.01e-4);
  EXPECT_DOUBLE_EQ(s.column("wall_seconds")[2], 0.0123);
  EXPECT_NE(input_error([&] { s.column("nope"); }).find("no column 'nope'"), std::string::npos);
  // a run that stopped before its first frame: the header only
  EXPECT_EQ(read_stats_csv(t.write("empty_run.csv", kHeader)).frames(), 0u);
}

TEST(StatsCsv, MalformedFilesNameTheFileAndLine) {
  TempDir t;
  // a row with fields missing in the middle of the file
  std::string bad = row(2, 300);
  bad = bad.substr(0, bad.find(",150,"));
  std::string path = t.write("a/stats.csv", kHeader + row(1, 300) + bad + "\n" + row(3, 300));
  std::string msg = input_error([&] { read_stats_csv(path); });
  EXPECT_NE(msg.find(path + ":3: 5 fields; expected 19"), std::string::npos) << msg;
  // a field that is not a number
  std::string r = row(2, 300);
  r.replace(r.find("300"), 3, "30x");
  path = t.write("b/stats.csv", kHeader + row(1, 300) + r);
  msg = input_error([&] { read_stats_csv(path); });
  EXPECT_NE(msg.find(path + ":3: column 'n_total' (field 5) is \"30x\"; expected a number"),
            std::string::npos)
      << msg;
  // a header without a column the report plots
  std::string header = kHeader;
  header.replace(header.find("n_static"), 8, "n_stat");
  path = t.write("c/stats.csv", header + row(1, 300));
  msg = input_error([&] { read_stats_csv(path); });
  EXPECT_NE(msg.find(path + ":1: the header has no column 'n_static'"), std::string::npos) << msg;
  // an empty file, and none at all
  path = t.write("d/stats.csv", "");
  EXPECT_NE(input_error([&] { read_stats_csv(path); }).find(path + ":1: empty file"),
            std::string::npos);
  path = (t.dir() / "e" / "stats.csv").string();
  EXPECT_NE(input_error([&] { read_stats_csv(path); }).find(path + ": cannot read"),
            std::string::npos);
}

TEST(StatsCsv, ALastRowCutShortIsLeftOutAndNoted) {
  TempDir t;
  std::string cut = row(3, 300);
  cut = cut.substr(0, cut.size() / 2);  // an interrupted write: no line end
  const std::string path = t.write("stats.csv", kHeader + row(1, 300) + row(2, 300) + cut);
  const StatsTable s = read_stats_csv(path);
  EXPECT_EQ(s.frames(), 2u);
  EXPECT_NE(s.note.find(path + ":4: the last row has no line end"), std::string::npos) << s.note;
  // even with every field there, a last row without its line end may have its last number cut
  std::string whole = row(3, 300);
  whole.pop_back();
  EXPECT_EQ(read_stats_csv(t.write("s2.csv", kHeader + row(1, 300) + whole)).frames(), 1u);
}

TEST(JsonObject, BadFilesNameTheFileAndPlace) {
  TempDir t;
  std::string path = t.write("summary.json", "{\n  \"a\": 1,\n  \"b\": \n}\n");
  std::string msg = input_error([&] { read_json_object(path); });
  EXPECT_NE(msg.find(path + ": not valid JSON"), std::string::npos) << msg;
  EXPECT_NE(msg.find("line 4"), std::string::npos) << msg;
  path = t.write("array.json", "[1, 2]");
  msg = input_error([&] { read_json_object(path); });
  EXPECT_NE(msg.find("expected a JSON object"), std::string::npos) << msg;
  EXPECT_EQ(read_json_object(t.write("ok.json", "{\"n_total\": 3}"))["n_total"], 3);
}

TEST(ContactSheet, EvenlySpacedFramesEndWithTheLast) {
  std::vector<int> frames;
  for (int f = 1; f <= 120; ++f) frames.push_back(f);
  EXPECT_EQ(evenly_spaced(frames, 6), (std::vector<int>{20, 40, 60, 80, 100, 120}));
  EXPECT_EQ(evenly_spaced(frames, 1), (std::vector<int>{120}));
  EXPECT_EQ(evenly_spaced({1, 2, 3, 4}, 6), (std::vector<int>{1, 2, 3, 4}));
  EXPECT_EQ(evenly_spaced({1, 2, 3, 4, 5, 6, 7, 8, 9, 10}, 3), (std::vector<int>{3, 7, 10}));
  EXPECT_EQ(evenly_spaced({5, 9, 40}, 2), (std::vector<int>{9, 40}));  // gaps: from what exists
  EXPECT_TRUE(evenly_spaced(frames, 0).empty());
  EXPECT_TRUE(evenly_spaced({}, 6).empty());
}

TEST(ContactSheet, FramesAndPicturesOfAFolder) {
  TempDir t;
  for (const char* f : {"frames/0002.ply", "frames/0010.ply", "frames/0001.ply", "frames/x.ply",
                        "frames/0003.txt", "render/0010.png", "render/0010.pov"})
    t.write(f, "x");
  EXPECT_EQ(list_frames(t.dir().string()), (std::vector<int>{1, 2, 10}));
  EXPECT_EQ(list_renders(t.dir().string()), (std::vector<int>{10}));
  EXPECT_EQ(render_path(t.dir().string(), 7), (t.dir() / "render" / "0007.png").string());
  EXPECT_TRUE(list_frames((t.dir() / "none").string()).empty());
}

TEST(ContactSheet, PngSizeFromTheHeader) {
  TempDir t;
  const std::string png = (t.dir() / "g.png").string();
  write_gray_png(png, 37, 21, std::vector<double>(37 * 21, 0.5), 8);
  const auto s = png_size(png);
  ASSERT_TRUE(s.has_value());
  EXPECT_EQ(s->width, 37);
  EXPECT_EQ(s->height, 21);
  EXPECT_FALSE(png_size(t.write("not.png", "GIF89a, not a PNG at all")).has_value());
  EXPECT_FALSE(png_size((t.dir() / "missing.png").string()).has_value());
}
