// The run report, DIR/report.html: one static page that opens anywhere with no network and no
// JavaScript. CSS is inline, the plots are inline SVG (svg_plot.hpp) and the pictures are PNGs
// embedded as base64 data: URIs, so the file can be mailed or archived alone.
//
// Sections, each with a stable id that tests and links rely on:
//   run folder:     summary, plots, contact-sheet
//   compare folder: summary, speedup, plots, final-frames, contact-sheet
//   table1 folder:  summary, scenes (the index of the scenes' own reports)
// A section whose data is missing still appears and says what is missing and how to get it.
// Rendering is not done here (the library never runs POV-Ray for a report): the caller renders
// what it wants shown and passes the PNG paths.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "report/run_data.hpp"

namespace sandflow {

/// A rendered frame to show: its number and the PNG file (read when the page is written).
struct ReportImage {
  int frame = 0;
  std::string png;
};

/// One run folder as the report shows it.
struct RunReportData {
  std::string dir;
  nlohmann::json summary;          ///< null when summary.json is missing
  std::vector<std::string> notes;  ///< what is missing or left out
  StatsTable stats;
  std::vector<ReportImage> sheet;  ///< the contact sheet, in frame order
  std::string sheet_note;          ///< why the sheet is empty or short, and how to fill it
};

/// Reads DIR/stats.csv (required: InputError naming it when missing or malformed) and
/// DIR/summary.json (a note when missing: the run did not finish; InputError when malformed).
RunReportData load_run_report_data(const std::string& dir);

/// The page of a run folder.
std::string run_report_html(const RunReportData& run);

/// A compare folder: compare.json and its two runs.
struct CompareReportData {
  std::string dir;
  nlohmann::json compare;
  RunReportData surface, dem;
  std::optional<ReportImage> final_surface, final_dem;  ///< the last frames, side by side
  std::string final_note;
  bool run_reports = false;  ///< surface/report.html and dem/report.html exist: link them
};

/// Reads DIR/compare.json (InputError when missing or malformed) and both runs.
CompareReportData load_compare_report_data(const std::string& dir);

/// The page of a compare folder: both modes on shared axes.
std::string compare_report_html(const CompareReportData& c);

/// A table1 folder's index: DIR/table1.csv as a table, linking each SCENE/report.html.
struct Table1ReportData {
  std::string dir;
  std::vector<std::string> columns;
  std::vector<std::vector<std::string>> rows;  ///< table1.csv's rows, as text
  std::vector<std::string> linked;             ///< the scenes whose SCENE/report.html exists
  std::string table_md;                        ///< table1.md, shown as text (may be empty)
};

/// Reads DIR/table1.csv (InputError naming the file and line when missing or malformed) and
/// DIR/table1.md (optional).
Table1ReportData load_table1_report_data(const std::string& dir);

std::string table1_report_html(const Table1ReportData& t);

}  // namespace sandflow
