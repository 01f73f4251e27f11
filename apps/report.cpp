// `sandflow report`: DIR/report.html for a run, compare or table1 folder (src/report/ writes the
// page). This file decides which frames the page shows and renders the missing ones with
// `sandflow render`; `run` and `compare` call write_report() without rendering, so every run
// has a report.
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include "commands.hpp"
#include "console.hpp"
#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "io/folder_lock.hpp"
#include "io/media_check.hpp"
#include "io/pov_writer.hpp"
#include "report/report.hpp"
#include "stop_signals.hpp"

namespace fs = std::filesystem;

namespace sandflow {

namespace {

// the size of the contact sheet's pictures, and of the compare page's final frames when neither
// is rendered yet [px]
constexpr int kSheetWidth = 480, kSheetHeight = 270;
constexpr int kFinalWidth = 640, kFinalHeight = 360;

bool file_exists(const fs::path& p) {
  std::error_code ec;
  return fs::exists(p, ec);
}

/// A picture the page can show: there and whole. One cut short (a copy that stopped, a picture
/// of a sandflow older than the check in render_pov) is rendered again, or left out.
bool picture_ready(const std::string& path) {
  return png_problem(path).empty();
}

/// The render/ folders this report draws into, each locked from its first picture to the end of
/// the report: a second report (or a render) of the same run is refused while this one renders,
/// rather than finding its pictures refused one by one and writing its page without them.
using RenderLocks = std::map<std::string, std::unique_ptr<FolderLock>>;

/// Thrown when a stop signal ended a render: the report stops there, unwritten.
struct RenderStopped {
  int status;  ///< 128 + the signal
};

/// Renders frame `frame` of `dir` unless its PNG exists; "" on success, else why it failed.
std::string render_missing(const std::string& dir, int frame, int width, int height,
                           RenderLocks& locks) {
  if (g_stop_signal != 0) throw RenderStopped{128 + g_stop_signal};
  if (picture_ready(render_path(dir, frame))) return "";
  if (!locks.contains(dir))  // (refused: the report stops, exit status 2)
    locks[dir] = std::make_unique<FolderLock>(
        (fs::path(dir) / "render").string(),
        FolderUse{"render", "wait for it to end or stop it, then report again"});
  print_to_stderr("report: rendering {} frame {} at {}x{}\n", dir, frame, width, height);
  try {
    RenderOptions r;
    r.dir = dir;
    r.width = width;
    r.height = height;
    r.frame = frame;
    r.folder_held = true;
    if (const int status = render_command(r); status != 0) throw RenderStopped{status};
  } catch (const std::exception& e) {
    print_to_stderr("warning: report: {} frame {} could not be rendered: {}\n", dir, frame,
                    e.what());
    return e.what();
  }
  return picture_ready(render_path(dir, frame)) ? "" : "POV-Ray wrote no whole picture";
}

/// Why nothing can be rendered now ("" when rendering is possible and asked for).
std::string why_no_render(const std::string& dir, bool render) {
  if (!render)
    return fmt::format("Not rendered here: `sandflow report {}` renders the frames with POV-Ray.",
                       dir);
  if (find_povray().empty())
    return fmt::format(
        "POV-Ray is not installed, so no frame was rendered: sudo apt-get install povray, then "
        "`sandflow report {}`.",
        dir);
  return "";
}

/// The contact sheet: `n` frames evenly spaced, rendered when missing and `render`; otherwise the
/// PNGs already in DIR/render/. `top`: the folder to name in `sandflow report TOP` (a
/// comparison's, for its runs).
void fill_contact_sheet(RunReportData& run, int n, bool render, const std::string& top,
                        RenderLocks& locks) {
  if (n <= 0) {
    run.sheet_note = "No contact sheet asked for (--contact-sheet 0).";
    return;
  }
  const std::vector<int> frames = list_frames(run.dir);
  const std::string cannot = why_no_render(top, render);
  std::vector<int> chosen;
  if (cannot.empty()) {
    if (frames.empty()) {
      run.sheet_note = fmt::format(
          "{}/frames/ holds no frame: the run wrote none (output.write_frames = false?) or "
          "stopped before its first.",
          run.dir);
      return;
    }
    chosen = evenly_spaced(frames, n);
    for (int f : chosen) {
      const std::string err = render_missing(run.dir, f, kSheetWidth, kSheetHeight, locks);
      if (!err.empty()) {
        // the same cause would fail the others too (a scene file that moved, a POV-Ray error)
        run.sheet_note = fmt::format("Frame {} could not be rendered: {}", f, err);
        break;
      }
    }
  } else {
    chosen = evenly_spaced(list_renders(run.dir), n);
    run.sheet_note = chosen.empty() ? "No frame is rendered yet. " + cannot
                     : fmt::format("The frames already rendered in {}/render/. {}", run.dir, cannot);
  }
  for (int f : chosen)
    if (picture_ready(render_path(run.dir, f))) run.sheet.push_back({f, render_path(run.dir, f)});
}

/// The two last frames, rendered at one size: that of the one already rendered, if any.
void fill_final_frames(CompareReportData& c, bool render, RenderLocks& locks) {
  const std::vector<int> fs_ = list_frames(c.surface.dir), fd = list_frames(c.dem.dir);
  if (fs_.empty() || fd.empty()) {
    c.final_note = "A run has no frame files (frames/NNNN.ply), so there is no final frame to show.";
    return;
  }
  const int ls = fs_.back(), ld = fd.back();
  const std::string ps = render_path(c.surface.dir, ls), pd = render_path(c.dem.dir, ld);
  const std::string cannot = why_no_render(c.dir, render);
  if (cannot.empty()) {
    int w = kFinalWidth, h = kFinalHeight;
    if (const auto s = png_size(picture_ready(ps) ? ps : pd)) w = s->width, h = s->height;
    std::string err = render_missing(c.surface.dir, ls, w, h, locks);
    if (err.empty()) err = render_missing(c.dem.dir, ld, w, h, locks);
    if (!err.empty()) c.final_note = "The final frames could not be rendered: " + err;
  } else if (!picture_ready(ps) || !picture_ready(pd)) {
    c.final_note = cannot;
  }
  if (picture_ready(ps)) c.final_surface = ReportImage{ls, ps};
  if (picture_ready(pd)) c.final_dem = ReportImage{ld, pd};
  const auto ss = png_size(ps), sd = png_size(pd);
  if (ss && sd && (ss->width != sd->width || ss->height != sd->height))
    c.final_note = fmt::format(
        "The two pictures were rendered at different sizes ({}\u00d7{} and {}\u00d7{}); they are "
        "shown at the same width.",
        sd->width, sd->height, ss->width, ss->height);
}

std::string write_run_report(const std::string& dir, const ReportOptions& o, RenderLocks& locks) {
  RunReportData run = load_run_report_data(dir);
  fill_contact_sheet(run, o.contact_sheet, o.render, dir, locks);
  const std::string path = (fs::path(dir) / "report.html").string();
  write_file_atomic(path, run_report_html(run));
  return path;
}

std::string write_compare_report(const std::string& dir, const ReportOptions& o,
                                 RenderLocks& locks) {
  for (const auto& [folder, mode] :
       {std::pair{"surface", "surface"}, std::pair{"dem", "plain-DEM"}})
    if (const fs::path stats = fs::path(dir) / folder / "stats.csv"; !file_exists(stats))
      throw InputError(fmt::format(
          "{}: the comparison's {} run is missing ({}: moved or deleted?); sandflow compare "
          "--resume {} runs it again",
          dir, mode, stats.string(), dir));
  CompareReportData c = load_compare_report_data(dir);
  fill_final_frames(c, o.render, locks);
  fill_contact_sheet(c.surface, o.contact_sheet, o.render, dir, locks);
  fill_contact_sheet(c.dem, o.contact_sheet, o.render, dir, locks);
  // each run's own page too (its pictures are rendered already)
  write_file_atomic((fs::path(c.surface.dir) / "report.html").string(), run_report_html(c.surface));
  write_file_atomic((fs::path(c.dem.dir) / "report.html").string(), run_report_html(c.dem));
  c.run_reports = true;
  const std::string path = (fs::path(dir) / "report.html").string();
  write_file_atomic(path, compare_report_html(c));
  return path;
}

}  // namespace

std::string write_report(const ReportOptions& o) {
  std::error_code ec;
  if (const std::string problem = folder_problem(o.dir); !problem.empty())
    throw InputError(
        fmt::format("{}: {} (expected a run, compare or table1 folder)", o.dir, problem));
  const fs::path d(o.dir);
  RenderLocks locks;
  if (file_exists(d / "compare.json")) return write_compare_report(o.dir, o, locks);
  if (file_exists(d / "table1.csv")) {
    Table1ReportData t = load_table1_report_data(o.dir);
    // a page per scene that has a comparison, in the table's order
    for (const auto& row : t.rows) {
      const fs::path scene = d / row[0];
      if (!file_exists(scene / "compare.json")) {
        print_to_stderr("report: {} has no compare.json (not run, or not finished): left out\n",
                        scene.string());
        continue;
      }
      print_to_stderr("report: {}\n", scene.string());
      write_compare_report(scene.string(), o, locks);
      t.linked.push_back(row[0]);
    }
    const std::string path = (d / "report.html").string();
    write_file_atomic(path, table1_report_html(t));
    return path;
  }
  if (file_exists(d / "stats.csv") || file_exists(d / "summary.json"))
    return write_run_report(o.dir, o, locks);
  if (file_exists(d / "compare_plan.json"))
    throw InputError(fmt::format(
        "{}: a comparison that did not finish (no compare.json yet): go on with it with "
        "sandflow compare --resume {}",
        o.dir, o.dir));
  throw InputError(fmt::format(
      "{}: not a run folder (stats.csv), a compare folder (compare.json) or a table1 folder "
      "(table1.csv)",
      o.dir));
}

int report_command(const ReportOptions& o) {
  const StopSignals signals;  // (for the whole report: between two pictures too)
  try {
    const std::string path = write_report(o);
    fmt::print("report           {}\n", path);
  } catch (const RenderStopped& e) {
    print_to_stderr(
        "\ninterrupted while rendering: the report is not written (the pictures made "
        "are kept: `sandflow report {}` goes on from them)\n",
        shell_quote(o.dir));
    return e.status;
  }
  return 0;
}

}  // namespace sandflow
