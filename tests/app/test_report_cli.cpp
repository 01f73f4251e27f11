// `sandflow report` end to end on tiny runs: every section, a point per frame, nothing external,
// both modes for a comparison, and clear errors for folders that are not runs.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "../report/html_check.hpp"
#include "cli_runner.hpp"

namespace fs = std::filesystem;

namespace {

using sandflow_test::html_problem;
using sandflow_test::polylines;
using sandflow_test::read_text;
using sandflow_test::run_sandflow;
using sandflow_test::Sandbox;
using sandflow_test::section_of;

// 300 grains dropped a few centimetres onto a floor: a second of work per run
const std::string kReportScene = sandflow_test::tiny_block_scene(300);

}  // namespace

TEST(ReportCli, TinyRunReportHasEverySection) {
  Sandbox box;
  const auto scene = box.write("tiny.toml", kReportScene);
  const auto out = box.dir / "run";
  std::string log;
  ASSERT_EQ(run_sandflow("run " + scene.string() + " --frames 4 --out " + out.string(), &log), 0)
      << log;
  // the run wrote its report already, and said where
  EXPECT_TRUE(fs::exists(out / "report.html"));
  EXPECT_NE(log.find("report           " + (out / "report.html").string()), std::string::npos)
      << log;
  fs::remove(out / "report.html");

  ASSERT_EQ(run_sandflow("report " + out.string() + " --no-render", &log), 0) << log;
  EXPECT_NE(log.find((out / "report.html").string()), std::string::npos) << log;
  const std::string html = read_text(out / "report.html");
  EXPECT_EQ(html_problem(html), "");
  for (const char* id : {"summary", "plots", "contact-sheet"})
    EXPECT_NE(html.find(std::string("<section id=\"") + id + "\">"), std::string::npos) << id;
  // 4 grain counts, seconds, dt and 4 transitions, one point per frame each
  const auto lines = polylines(html);
  EXPECT_EQ(lines.size(), 10u);
  for (const auto& l : lines) EXPECT_EQ(l.points, 4u) << l.series;
  EXPECT_EQ(html.find("http://"), std::string::npos);
  EXPECT_EQ(html.find("https://"), std::string::npos);
  // --no-render: no picture, and the page says how to get them
  EXPECT_EQ(html.find("<img"), std::string::npos);
  EXPECT_NE(section_of(html, "contact-sheet").find("sandflow report " + out.string()),
            std::string::npos);
  EXPECT_FALSE(fs::exists(out / "render"));
}

TEST(ReportCli, TinyCompareReportHasBothModes) {
  Sandbox box;
  const auto scene = box.write("tiny.toml", kReportScene);
  const auto out = box.dir / "cmp";
  std::string log;
  ASSERT_EQ(
      run_sandflow("compare " + scene.string() + " --frames 3 --grains 200 --out " + out.string(),
                   &log),
      0)
      << log;
  EXPECT_NE(log.find((out / "report.html").string()), std::string::npos) << log;
  ASSERT_EQ(run_sandflow("report " + out.string() + " --no-render", &log), 0) << log;
  const std::string html = read_text(out / "report.html");
  EXPECT_EQ(html_problem(html), "");
  for (const char* id : {"summary", "speedup", "plots", "final-frames", "contact-sheet"})
    EXPECT_NE(html.find(std::string("<section id=\"") + id + "\">"), std::string::npos) << id;
  int dem = 0, surface = 0;
  for (const auto& l : polylines(html)) {
    EXPECT_EQ(l.points, 3u) << l.series;
    dem += l.series.rfind("plain DEM: ", 0) == 0;
    surface += l.series.rfind("surface flow: ", 0) == 0;
  }
  // no picture yet: the page names the command that adds them, for the comparison as a whole
  EXPECT_NE(section_of(html, "contact-sheet").find("sandflow report " + out.string() + "`"),
            std::string::npos);
  EXPECT_EQ(dem, 3);       // simulated, seconds, dt
  EXPECT_EQ(surface, 10);  // 4 counts, seconds, dt, 4 transitions
  EXPECT_EQ(html.find("http"), std::string::npos);
  // each run has its own page, linked
  EXPECT_EQ(html_problem(read_text(out / "surface" / "report.html")), "");
  EXPECT_EQ(html_problem(read_text(out / "dem" / "report.html")), "");
  EXPECT_NE(html.find("href=\"dem/report.html\""), std::string::npos);
  // a run of the comparison deleted since: named as the comparison's, with the way back
  fs::remove_all(out / "dem");
  EXPECT_EQ(run_sandflow("report " + out.string() + " --no-render", &log), 2) << log;
  EXPECT_NE(log.find(out.string() + ": the comparison's plain-DEM run is missing"),
            std::string::npos)
      << log;
  EXPECT_NE(log.find("sandflow compare --resume " + out.string()), std::string::npos) << log;
}

TEST(ReportCli, MissingOrBrokenInputsExitTwoNamingTheFile) {
  Sandbox box;
  std::string log;
  // a run folder without its stats.csv
  const auto run = box.dir / "run";
  fs::create_directories(run);
  box.write("run/summary.json", "{\"scene\": \"x\"}");
  EXPECT_EQ(run_sandflow("report " + run.string(), &log), 2) << log;
  EXPECT_NE(log.find((run / "stats.csv").string()), std::string::npos) << log;
  EXPECT_FALSE(fs::exists(run / "report.html"));
  // a comparison stopped before its compare.json: how to finish it
  fs::create_directories(box.dir / "cmp");
  box.write("cmp/compare_plan.json", "{\"seeds\": 2, \"equal_stiffness\": false}");
  EXPECT_EQ(run_sandflow("report " + (box.dir / "cmp").string(), &log), 2) << log;
  EXPECT_NE(log.find("a comparison that did not finish (no compare.json yet): go on with it with "
                     "sandflow compare --resume"),
            std::string::npos)
      << log;
  // a row cut short in the middle of stats.csv: the file and the line
  box.write("run/stats.csv",
            "frame,time,substeps,dt,n_total,n_active,n_interface,n_static,contacts,wall_contacts,"
            "max_overlap_rel,kinetic_energy,rebuilds,trapped,dislodged,slept,woken,"
            "surface_updates,wall_seconds\n"
            "1,0.03,10,1e-4,5,5,0,0,0,0,0,0,1,0,0,0,0,0,0.01\n"
            "2,0.06,10,1e-4,5\n"
            "3,0.10,10,1e-4,5,5,0,0,0,0,0,0,1,0,0,0,0,0,0.01\n");
  EXPECT_EQ(run_sandflow("report " + run.string(), &log), 2) << log;
  EXPECT_NE(log.find((run / "stats.csv").string() + ":3:"), std::string::npos) << log;
  // a summary that is not JSON
  box.write("run/stats.csv",
            "frame,time,substeps,dt,n_total,n_active,n_interface,n_static,contacts,wall_contacts,"
            "max_overlap_rel,kinetic_energy,rebuilds,trapped,dislodged,slept,woken,"
            "surface_updates,wall_seconds\n");
  box.write("run/summary.json", "{\"scene\": ");
  EXPECT_EQ(run_sandflow("report " + run.string(), &log), 2) << log;
  EXPECT_NE(log.find((run / "summary.json").string() + ": not valid JSON"), std::string::npos)
      << log;
  // not a run folder at all, and no folder
  fs::create_directories(box.dir / "empty");
  EXPECT_EQ(run_sandflow("report " + (box.dir / "empty").string(), &log), 2) << log;
  EXPECT_NE(log.find("not a run folder"), std::string::npos) << log;
  EXPECT_EQ(run_sandflow("report " + (box.dir / "nowhere").string(), &log), 2) << log;
  EXPECT_NE(log.find("no such folder"), std::string::npos) << log;
  EXPECT_EQ(run_sandflow("report " + run.string() + " --contact-sheet -1", &log), 2) << log;
}

TEST(ReportCli, ContactSheetIsRenderedWithPovray) {
  if (std::system("command -v povray > /dev/null 2>&1") != 0)
    GTEST_SKIP() << "povray is not installed";
  Sandbox box;
  const auto scene = box.write("tiny.toml", kReportScene);
  const auto out = box.dir / "run";
  std::string log;
  ASSERT_EQ(
      run_sandflow("run " + scene.string() + " --frames 3 --grains 50 --out " + out.string(), &log),
      0)
      << log;
  // one picture (a second of POV-Ray): the last frame
  ASSERT_EQ(run_sandflow("report " + out.string() + " --contact-sheet 1", &log), 0) << log;
  EXPECT_TRUE(fs::exists(out / "render" / "0003.png"));
  const std::string html = read_text(out / "report.html");
  EXPECT_EQ(html_problem(html), "");
  const std::string sheet = section_of(html, "contact-sheet");
  EXPECT_EQ(sandflow_test::occurrences(sheet, "<img src=\"data:image/png;base64,"), 1u);
  EXPECT_NE(sheet.find("frame 3"), std::string::npos);
  // --no-render now shows the picture already there
  ASSERT_EQ(run_sandflow("report " + out.string() + " --no-render", &log), 0) << log;
  EXPECT_EQ(sandflow_test::occurrences(read_text(out / "report.html"), "<img "), 1u);
}

TEST(ReportCli, Table1FolderGetsAnIndexOfTheScenesReports) {
  Sandbox box;
  const auto out = box.dir / "t1";
  std::string log;
  // the floor at a hundredth of the paper's count (1,077 grains), two frames per mode
  ASSERT_EQ(run_sandflow("table1 --scale 0.01 --frames 2 --scenes floor --out " + out.string() +
                             " --scene-dir " + SANDFLOW_SOURCE_DIR + "/scenes",
                         &log),
            0)
      << log;
  EXPECT_TRUE(fs::exists(out / "floor" / "report.html"));  // compare_scene writes it
  ASSERT_EQ(run_sandflow("report " + out.string() + " --no-render", &log), 0) << log;
  const std::string html = read_text(out / "report.html");
  EXPECT_EQ(html_problem(html), "");
  for (const char* id : {"summary", "scenes"})
    EXPECT_NE(html.find(std::string("<section id=\"") + id + "\">"), std::string::npos) << id;
  EXPECT_NE(html.find("<a href=\"floor/report.html\">floor</a>"), std::string::npos);
  EXPECT_NE(html.find("1,077"), std::string::npos);
  EXPECT_EQ(html_problem(read_text(out / "floor" / "report.html")), "");
  // a row of table1.csv cut short: the file and the line
  const std::string csv = read_text(out / "table1.csv");
  box.write("t1/table1.csv", csv + "bowl,3181,12\n");
  EXPECT_EQ(run_sandflow("report " + out.string() + " --no-render", &log), 2) << log;
  EXPECT_NE(log.find((out / "table1.csv").string() + ":3: 3 fields"), std::string::npos) << log;
  // a scene named as a path out of the folder: report wrote that folder's report.html
  const std::size_t row = csv.find('\n') + 1;  // floor,...
  box.write("t1/table1.csv", csv.substr(0, row) + "../run" + csv.substr(csv.find(',', row)));
  EXPECT_EQ(run_sandflow("report " + out.string() + " --no-render", &log), 2) << log;
  EXPECT_NE(log.find(":2: scene '../run' is not the name of a folder in"), std::string::npos)
      << log;
}

TEST(ReportCli, WithoutPovrayTheSheetSaysHowToGetIt) {
  Sandbox box;
  const auto scene = box.write("tiny.toml", kReportScene);
  const auto out = box.dir / "run";
  std::string log;
  ASSERT_EQ(
      run_sandflow("run " + scene.string() + " --frames 2 --grains 50 --out " + out.string(), &log),
      0)
      << log;
  // a PATH without povray (the binary itself is called by its full path)
  const std::string path = std::getenv("PATH") ? std::getenv("PATH") : "";
  setenv("PATH", (box.dir / "no-such-bin").c_str(), 1);
  const int rc = run_sandflow("report " + out.string(), &log);
  setenv("PATH", path.c_str(), 1);
  ASSERT_EQ(rc, 0) << log;
  const std::string sheet = section_of(read_text(out / "report.html"), "contact-sheet");
  EXPECT_NE(sheet.find("POV-Ray is not installed"), std::string::npos) << sheet;
  EXPECT_NE(sheet.find("sudo apt-get install povray"), std::string::npos) << sheet;
  EXPECT_FALSE(fs::exists(out / "render"));
}
