// The report pages assembled from run and compare folders written here (no simulation): every
// section, one polyline per series with a point per frame, pictures embedded, nothing external,
// every string escaped, and what is missing said rather than crashed on.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "core/error.hpp"
#include "html_check.hpp"
#include "io/png_gray.hpp"
#include "report/html.hpp"
#include "report/report.hpp"
#include "support/scratch.hpp"

using namespace sandflow;
using sandflow_test::html_problem;
using sandflow_test::occurrences;
using sandflow_test::polylines;
using sandflow_test::section_of;
namespace fs = std::filesystem;

namespace {

using TempDir = sandflow::test::ScratchFolder;

std::string fmt_frame(int f) {
  char buf[16];
  std::snprintf(buf, sizeof buf, "%04d", f);
  return buf;
}

/// A run folder of `frames` frames: stats.csv, summary.json (unless `summary` is false).
void write_run(const fs::path& dir, const std::string& mode, int frames, bool summary = true,
               const std::string& scene = "tiny") {
  fs::create_directories(dir / "frames");
  std::ofstream csv(dir / "stats.csv");
  csv << "frame,time,substeps,dt,n_total,n_active,n_interface,n_static,contacts,wall_contacts,"
         "max_overlap_rel,kinetic_energy,rebuilds,trapped,dislodged,slept,woken,surface_updates,"
         "wall_seconds\n";
  for (int f = 1; f <= frames; ++f) {
    const int stat = mode == "dem" ? 0 : 20 * f, inter = mode == "dem" ? 0 : 10;
    csv << f << "," << f / 30.0 << ",300," << (mode == "dem" ? 6e-5 : 1e-4) << ",400,"
        << 400 - stat - inter << "," << inter << "," << stat << ",900,30,0.01,0.001,2,"
        << (mode == "dem" ? 0 : 3) << ",1,2,0,5," << 0.01 * f << "\n";
    std::ofstream(dir / "frames" / (fmt_frame(f) + ".ply")) << "x";
  }
  if (!summary) return;
  const nlohmann::json s = {{"scene", scene},
                            {"scene_file", "scenes/" + scene + ".toml"},
                            {"mode", mode},
                            {"frames", frames},
                            {"fps", 30},
                            {"n_total", 400},
                            {"n_simulated_mean", 320.5},
                            {"seconds_per_frame", 0.02},
                            {"dt_mean", 1e-4},
                            {"k_n", 1207.0},
                            {"repose_angle_deg", 31.5},
                            {"heap", {{"height", 0.05}, {"base_radius", 0.08}}},
                            {"grains_inside_geometry", 0},
                            {"state_hash", "00112233aabbccdd"}};
  std::ofstream(dir / "summary.json") << s.dump(2);
}

}  // namespace

TEST(ReportPage, RunHasEverySectionAndAPolylinePerSeries) {
  TempDir t;
  write_run(t.dir(), "surface", 5);
  RunReportData run = load_run_report_data(t.dir().string());
  run.sheet_note = "No frame is rendered yet.";
  const std::string html = run_report_html(run);
  EXPECT_EQ(html_problem(html), "");
  for (const char* id : {"summary", "plots", "contact-sheet", "plot-grains", "plot-seconds",
                         "plot-dt", "plot-transitions"})
    EXPECT_NE(html.find(std::string("id=\"") + id + "\""), std::string::npos) << id;
  // total, simulated, interface, static; seconds; dt; trapped, dislodged, slept, woken
  const auto lines = polylines(html);
  ASSERT_EQ(lines.size(), 10u);
  for (const auto& l : lines) EXPECT_EQ(l.points, 5u) << l.series;
  EXPECT_EQ(html.find("http://"), std::string::npos);
  EXPECT_EQ(html.find("https://"), std::string::npos);
  EXPECT_EQ(html.find("<script"), std::string::npos);
  // the summary's figures, readable
  const std::string summary = section_of(html, "summary");
  EXPECT_NE(summary.find("31.5\u00b0"), std::string::npos);
  EXPECT_NE(summary.find("1,207 N/m"), std::string::npos);
  EXPECT_NE(summary.find("00112233aabbccdd"), std::string::npos);
  EXPECT_NE(section_of(html, "contact-sheet").find("No frame is rendered yet."), std::string::npos);
}

TEST(ReportPage, PicturesAreEmbeddedAsDataUris) {
  TempDir t;
  write_run(t.dir(), "surface", 4);
  fs::create_directories(t.dir() / "render");
  const std::string png = (t.dir() / "render" / "0004.png").string();
  write_gray_png(png, 8, 6, std::vector<double>(48, 0.25), 8);
  RunReportData run = load_run_report_data(t.dir().string());
  run.sheet.push_back({4, png});
  const std::string html = run_report_html(run);
  EXPECT_EQ(html_problem(html), "");
  std::stringstream bytes;
  bytes << std::ifstream(png, std::ios::binary).rdbuf();
  const std::string sheet = section_of(html, "contact-sheet");
  EXPECT_NE(sheet.find("src=\"data:image/png;base64," + base64_encode(bytes.str()) + "\""),
            std::string::npos);
  EXPECT_NE(sheet.find("width=\"8\" height=\"6\""), std::string::npos);
  EXPECT_NE(sheet.find("frame 4, t = 0.13 s"), std::string::npos);  // its stats row
  // a picture that vanished is said, not crashed on
  run.sheet = {{3, (t.dir() / "render" / "0003.png").string()}};
  EXPECT_NE(
      run_report_html(run).find("0003.png: cannot open the picture: No such file or directory"),
      std::string::npos);
}

TEST(ReportPage, EveryStringIsEscaped) {
  TempDir t;
  write_run(t.dir(), "dem", 2, true, "<script>alert('x')</script> & co");
  const std::string html = run_report_html(load_run_report_data(t.dir().string()));
  EXPECT_EQ(html_problem(html), "");
  EXPECT_EQ(html.find("<script"), std::string::npos);
  EXPECT_NE(html.find("&lt;script&gt;alert(&#39;x&#39;)&lt;/script&gt; &amp; co"),
            std::string::npos);
}

TEST(ReportPage, AMissingSummaryOrNoFramesIsSaid) {
  TempDir t;
  write_run(t.dir() / "a", "surface", 3, false);
  std::string html = run_report_html(load_run_report_data((t.dir() / "a").string()));
  EXPECT_EQ(html_problem(html), "");
  EXPECT_NE(html.find("summary.json is missing"), std::string::npos);
  EXPECT_EQ(polylines(html).size(), 10u);
  // a run that stopped before its first frame: axes and "no data", no crash
  write_run(t.dir() / "b", "surface", 0);
  html = run_report_html(load_run_report_data((t.dir() / "b").string()));
  EXPECT_EQ(html_problem(html), "");
  EXPECT_NE(html.find("no frames recorded"), std::string::npos);
  EXPECT_EQ(occurrences(html, "no data</text>"), 4u);
  // no stats.csv at all: an error naming it
  fs::create_directories(t.dir() / "c");
  try {
    load_run_report_data((t.dir() / "c").string());
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find((t.dir() / "c" / "stats.csv").string()), std::string::npos);
  }
}

TEST(ReportPage, CompareShowsBothModesOnSharedAxes) {
  TempDir t;
  write_run(t.dir() / "surface", "surface", 6);
  write_run(t.dir() / "dem", "dem", 6);
  const nlohmann::json c = {{"scene", "tiny"},         {"frames", 6},
                            {"n_total", 400},          {"speedup", 2.5},
                            {"dt_dem", 6e-5},          {"dt_surface", 1e-4},
                            {"n_simulated_mean", 200}, {"n_simulated_mean_dem", 400},
                            {"surface_rms_rel", 0.04}, {"seconds_per_frame_dem", 0.05},
                            {"seconds_per_frame_surface", 0.02}};
  std::ofstream(t.dir() / "compare.json") << c.dump();
  CompareReportData data = load_compare_report_data(t.dir().string());
  data.final_note = "not rendered";
  const std::string html = compare_report_html(data);
  EXPECT_EQ(html_problem(html), "");
  for (const char* id : {"summary", "speedup", "plots", "final-frames", "contact-sheet"})
    EXPECT_NE(html.find(std::string("<section id=\"") + id + "\">"), std::string::npos) << id;
  // one seed: no range of speed-ups by seed; three: their range
  EXPECT_EQ(html.find("speed-up by seed"), std::string::npos);
  nlohmann::json seeds = c;
  seeds["seeds"] = 3;
  seeds["speedup_min"] = 2.25;
  seeds["speedup_max"] = 2.75;
  std::ofstream(t.dir() / "compare.json") << seeds.dump();
  const std::string three = compare_report_html(load_compare_report_data(t.dir().string()));
  EXPECT_NE(section_of(three, "speedup")
                .find("speed-up by seed, smallest to largest</th><td "
                      "class=\"num\">2.25\u00d7 to 2.75\u00d7"),
            std::string::npos)
      << section_of(three, "speedup");
  // surface: total, simulated, interface, static, seconds, dt, 4 transitions; DEM: simulated,
  // seconds, dt (no transitions), each with a point per frame
  const auto lines = polylines(html);
  ASSERT_EQ(lines.size(), 13u);
  int dem = 0;
  for (const auto& l : lines) {
    EXPECT_EQ(l.points, 6u) << l.series;
    dem += l.series.rfind("plain DEM: ", 0) == 0;
  }
  EXPECT_EQ(dem, 3);
  // one plot holds both modes' seconds per frame: shared axes
  const std::string plots = section_of(html, "plots");
  const std::size_t sec = plots.find("id=\"plot-seconds\"");
  const std::string seconds_plot = plots.substr(sec, plots.find("</svg>", sec) - sec);
  EXPECT_EQ(occurrences(seconds_plot, "<polyline"), 2u);
  // the speed-up and its two sources: dt 1e-4 / 6e-5 = 1.67, grains 400 / 200 = 2.00
  const std::string sp = section_of(html, "speedup");
  EXPECT_NE(sp.find("2.50\u00d7"), std::string::npos);
  EXPECT_NE(sp.find("1.67"), std::string::npos);
  EXPECT_NE(sp.find("2.00"), std::string::npos);
  EXPECT_NE(sp.find("3.33\u00d7"), std::string::npos);
  EXPECT_NE(section_of(html, "final-frames").find("not rendered"), std::string::npos);
  EXPECT_EQ(html.find("http"), std::string::npos);
}

// A scene with a bed: the crater's figures in place of the angle of repose, which says why not
TEST(ReportPage, CompareOfABedSceneShowsTheCraterNotAnAngle) {
  TempDir t;
  write_run(t.dir() / "surface", "surface", 3);
  write_run(t.dir() / "dem", "dem", 3);
  const nlohmann::json c = {{"scene", "impact"},
                            {"frames", 3},
                            {"seeds", 2},
                            {"repose_angle_dem_deg", nullptr},
                            {"repose_angle_skipped", "not measured in a scene with a bed"},
                            {"crater_bed_height", 0.05},
                            {"crater_fits", {{"dem", 2}, {"surface", 1}}},
                            {"crater_depth_dem", 0.0139},
                            {"crater_depth_surface", 0.0121},
                            {"crater_depth_dem_spread", 0.0036},
                            {"crater_depth_diff", 0.0018},
                            {"crater_depth_within_spread", true},
                            {"rim_height_dem", 0.0029},
                            {"rim_height_surface", nullptr},
                            {"rim_height_dem_spread", 0.0001},
                            {"rim_height_diff", nullptr},
                            {"rim_height_within_spread", nullptr}};
  std::ofstream(t.dir() / "compare.json") << c.dump();
  const std::string html = compare_report_html(load_compare_report_data(t.dir().string()));
  EXPECT_EQ(html_problem(html), "");
  const std::string sum = section_of(html, "summary");
  EXPECT_EQ(sum.find("angle of repose"), std::string::npos);
  EXPECT_NE(sum.find("0.0139 m"), std::string::npos);
  EXPECT_NE(sum.find("0.0121 m"), std::string::npos);
  EXPECT_NE(sum.find("1 of 2"), std::string::npos);
  const std::string sp = section_of(html, "speedup");
  EXPECT_NE(sp.find("0.0018 m"), std::string::npos);
  EXPECT_NE(sp.find("0.0036 m"), std::string::npos);
  EXPECT_NE(sp.find(">yes<"), std::string::npos);  // 0.0018 m within the spread of 0.0036 m
  EXPECT_NE(sp.find("not measured in a scene with a bed"), std::string::npos);
  EXPECT_EQ(sp.find("angles of repose"), std::string::npos);
}

// A value of the wrong type (a hand-edited or foreign file) shows as a dash, and a note names its
// file and its place in it; a missing value shows as a dash with no note.
TEST(ReportPage, AValueOfTheWrongTypeIsNamedNotOnlyDashed) {
  TempDir t;
  write_run(t.dir() / "surface", "surface", 3);
  write_run(t.dir() / "dem", "dem", 3);
  const fs::path summary = t.dir() / "surface" / "summary.json";
  nlohmann::json s = nlohmann::json::parse(std::ifstream(summary));
  s["repose_angle_deg"] = "31.5";
  s["k_n"] = nlohmann::json::array({1207.0});
  s["stage_seconds"] = {{"forces+integration", true}};
  std::ofstream(summary) << s.dump(2);
  const std::string run = run_report_html(load_run_report_data((t.dir() / "surface").string()));
  EXPECT_EQ(html_problem(run), "");
  for (const std::string key : {"'repose_angle_deg' is a string", "'k_n' is an array",
                                "'stage_seconds.forces+integration' is a boolean"})
    EXPECT_NE(run.find(html_escape(summary.string() + ": " + key + ", not a number")),
              std::string::npos)
        << key;
  // the correct file beside it: no note
  const std::string dem = run_report_html(load_run_report_data((t.dir() / "dem").string()));
  EXPECT_EQ(dem.find("not a number"), std::string::npos);

  // in a comparison: compare.json's own values, and the runs' summaries, by file
  const nlohmann::json c = {{"scene", "tiny"},
                            {"frames", 3},
                            {"n_total", 400},
                            {"speedup", "fast"},
                            {"emitters", nullptr}};
  std::ofstream(t.dir() / "compare.json") << c.dump();
  const std::string cmp = compare_report_html(load_compare_report_data(t.dir().string()));
  EXPECT_EQ(html_problem(cmp), "");
  EXPECT_NE(cmp.find(html_escape((t.dir() / "compare.json").string() +
                                 ": 'speedup' is a string, not a number")),
            std::string::npos);
  EXPECT_EQ(occurrences(cmp, "not a number"), 1u);  // (the summaries' angle is not on this page)
}
