#include "report/report.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <functional>
#include <sstream>

#include <fmt/format.h>

#include "core/error.hpp"
#include "core/file_kind.hpp"
#include "core/read_file.hpp"
#include "report/html.hpp"
#include "report/svg_plot.hpp"

namespace sandflow {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr const char* kDash = "\u2014";  // a value the file does not hold

// ---- reading the summary's values without ever throwing: a missing key shows as a dash ----

/// The values a page reads as numbers that its files hold as something else (a hand-edited or
/// foreign file): each shows as a dash, and a note at the top of the page names it, so that a
/// dash never hides a value the file does hold. One per page being written, on its thread.
class WrongTypes {
 public:
  explicit WrongTypes(std::vector<std::pair<const json*, std::string>> files)
      : files_(std::move(files)), outer_(current_) {
    current_ = this;
  }
  ~WrongTypes() { current_ = outer_; }
  WrongTypes(const WrongTypes&) = delete;
  WrongTypes& operator=(const WrongTypes&) = delete;

  /// `value`, read as `expected`, is not that: named by its file and its place in it.
  static void found(const json& value, const char* expected) {
    if (!current_) return;
    std::string where = "a value";
    for (const auto& [root, name] : current_->files_)
      if (std::string key; locate(*root, &value, key)) {
        where = fmt::format("{}: '{}'", name, key);
        break;
      }
    const std::string what = fmt::format("{} is {} {}, not {}; shown as {}", where,
                                         value.is_array() || value.is_object() ? "an" : "a",
                                         value.type_name(), expected, kDash);
    auto& seen = current_->found_;
    if (std::find(seen.begin(), seen.end(), what) == seen.end()) seen.push_back(what);
  }
  const std::vector<std::string>& list() const { return found_; }

 private:
  static thread_local WrongTypes* current_;
  std::vector<std::pair<const json*, std::string>> files_;
  WrongTypes* outer_;
  std::vector<std::string> found_;

  /// The key path of `target` within `tree` ("heap.height", "emitters[0].count").
  static bool locate(const json& tree, const json* target, std::string& key) {
    if (&tree == target) return true;
    const std::size_t mark = key.size();
    if (tree.is_object()) {
      for (const auto& [k, v] : tree.items()) {
        key += (mark ? "." : "") + k;
        if (locate(v, target, key)) return true;
        key.resize(mark);
      }
    } else if (tree.is_array()) {
      for (std::size_t n = 0; n < tree.size(); ++n) {
        key += fmt::format("[{}]", n);
        if (locate(tree[n], target, key)) return true;
        key.resize(mark);
      }
    }
    return false;
  }
};
thread_local WrongTypes* WrongTypes::current_ = nullptr;

const json* find(const json& j, std::initializer_list<const char*> path) {
  const json* p = &j;
  for (const char* k : path) {
    if (!p->is_object() || !p->contains(k)) return nullptr;
    p = &(*p)[k];
  }
  return p;
}

std::optional<double> number(const json& j, std::initializer_list<const char*> path) {
  const json* p = find(j, path);
  if (p && !p->is_number() && !p->is_null()) WrongTypes::found(*p, "a number");
  if (!p || !p->is_number()) return std::nullopt;
  return p->get<double>();
}

std::string text(const json& j, std::initializer_list<const char*> path) {
  const json* p = find(j, path);
  if (!p || p->is_null()) return kDash;
  return p->is_string() ? p->get<std::string>() : p->dump();
}

/// 20000 -> "20,000"
std::string count(double v) {
  if (!std::isfinite(v)) return fmt::format("{}", v);
  std::string s = fmt::format("{:.0f}", v);
  const std::size_t start = s[0] == '-' ? 1 : 0;
  for (std::size_t k = s.size(); k > start + 3; k -= 3) s.insert(k - 3, ",");
  return s;
}

std::string count(const json& j, std::initializer_list<const char*> path) {
  const auto v = number(j, path);
  return v ? count(*v) : kDash;
}

std::string fixed(const json& j, std::initializer_list<const char*> path, int decimals,
                  const std::string& unit = "") {
  const auto v = number(j, path);
  return v ? fmt::format("{:.{}f}{}", *v, decimals, unit) : kDash;
}

/// 3 significant digits; small values as 1.01e-04 rather than 0.000101
std::string general(const json& j, std::initializer_list<const char*> path,
                    const std::string& unit = "") {
  const auto v = number(j, path);
  if (!v) return kDash;
  const bool sci = *v != 0 && std::abs(*v) < 1e-3;
  return sci ? fmt::format("{:.2e}{}", *v, unit) : fmt::format("{:.3g}{}", *v, unit);
}

std::string percent(const json& j, std::initializer_list<const char*> path) {
  const auto v = number(j, path);
  return v ? fmt::format("{:.1f} %", 100 * *v) : kDash;
}

std::string mode_title(const std::string& mode) {
  if (mode == "surface") return "surface flow (height field + DEM)";
  if (mode == "dem") return "plain DEM";
  return mode;
}

// ---- page parts ----

constexpr const char* kCss = R"(
body { font-family: system-ui, sans-serif; margin: 0 auto; padding: 1em 1.5em 3em;
       max-width: 1280px; color: #222; background: #fff; line-height: 1.4; }
h1 { font-size: 1.5em; margin-bottom: 0.2em; }
h2 { font-size: 1.2em; border-bottom: 1px solid #ccc; padding-bottom: 0.2em; margin-top: 1.6em; }
h3 { font-size: 1.05em; }
nav a { margin-right: 1em; }
.sub { color: #555; margin-top: 0; }
table { border-collapse: collapse; margin: 0.5em 0; }
th, td { text-align: left; padding: 0.2em 0.9em 0.2em 0; border-bottom: 1px solid #eee;
         vertical-align: top; }
td.num { text-align: right; font-variant-numeric: tabular-nums; }
th { color: #444; }
.note { background: #fff6e0; border-left: 4px solid #e69f00; padding: 0.4em 0.8em; }
.plots { display: grid; grid-template-columns: repeat(auto-fill, minmax(560px, 1fr)); gap: 1em; }
svg.plot { width: 100%; height: auto; max-width: 640px; }
.sheet { display: grid; grid-template-columns: repeat(auto-fill, minmax(280px, 1fr)); gap: 0.8em; }
.wide { overflow-x: auto; }
.pair { display: grid; grid-template-columns: 1fr 1fr; gap: 1em; }
figure { margin: 0; }
figure img { width: 100%; height: auto; border: 1px solid #ccc; display: block; }
figcaption { font-size: 0.9em; color: #444; }
pre { background: #f6f6f6; padding: 0.6em; overflow-x: auto; }
code { background: #f3f3f3; padding: 0 0.2em; }
footer { margin-top: 3em; color: #777; font-size: 0.85em; }
)";

std::string page(const std::string& title, const std::string& subtitle,
                 const std::vector<std::pair<std::string, std::string>>& nav,
                 const std::string& body, const std::string& dir) {
  std::string o = "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\"/>\n";
  o += "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\"/>\n";
  o += "<title>" + html_escape(title) + "</title>\n<style>" + kCss + "</style>\n</head>\n<body>\n";
  o += "<header>\n<h1>" + html_escape(title) + "</h1>\n<p class=\"sub\">" +
       html_escape(subtitle) + "</p>\n<nav>";
  for (const auto& [id, name] : nav)
    o += "<a href=\"#" + html_escape(id) + "\">" + html_escape(name) + "</a>";
  o += "</nav>\n</header>\n" + body;
  o += fmt::format("<footer>Written by sandflow {} from the folder <code>{}</code>.</footer>\n",
                   SANDFLOW_VERSION, html_escape(dir));
  return o + "</body>\n</html>\n";
}

std::string note(const std::string& t) { return "<p class=\"note\">" + html_escape(t) + "</p>\n"; }

/// A two-column table of (what, value), values already formatted as text.
std::string table(const std::vector<std::pair<std::string, std::string>>& rows) {
  std::string o = "<table>\n";
  for (const auto& [k, v] : rows)
    o += "<tr><th>" + html_escape(k) + "</th><td>" + html_escape(v) + "</td></tr>\n";
  return o + "</table>\n";
}

/// A PNG as an <img> with a data: URI, or a note when it cannot be read.
std::string image(const std::string& png, const std::string& alt) {
  std::string bytes;
  try {
    bytes = read_whole_file(png, "picture", kAnyFileSize);
  } catch (const InputError& e) {
    return note(e.what());  // (gone, a folder, unreadable: the page says so and goes on)
  }
  if (bytes.compare(0, 8, "\x89PNG\r\n\x1a\n") != 0) return note(png + ": not a PNG picture");
  std::string size;
  if (const auto s = png_size(png)) size = fmt::format(" width=\"{}\" height=\"{}\"", s->width, s->height);
  return "<img src=\"data:image/png;base64," + base64_encode(bytes) + "\" alt=\"" +
         html_escape(alt) + "\"" + size + "/>";
}

/// The statistics row of a frame (by the frame column), or null.
const std::vector<double>* stats_row(const StatsTable& t, int frame) {
  const std::vector<double> frames = t.column("frame");
  for (std::size_t k = 0; k < frames.size(); ++k)
    if (static_cast<int>(frames[k]) == frame) return &t.rows[k];
  return nullptr;
}

std::string figure(const RunReportData& run, const ReportImage& im, const std::string& label) {
  std::string cap = fmt::format("{}frame {}", label.empty() ? "" : label + ", ", im.frame);
  if (const auto* row = stats_row(run.stats, im.frame)) {
    auto col = [&](const char* name) {
      return (*row)[static_cast<std::size_t>(
          std::find(run.stats.columns.begin(), run.stats.columns.end(), name) -
          run.stats.columns.begin())];
    };
    cap += fmt::format(", t = {:.2f} s, {} of {} grains simulated", col("time"),
                       count(col("n_active") + col("n_interface")), count(col("n_total")));
  }
  if (const auto s = png_size(im.png)) cap += fmt::format(" ({}\u00d7{} px)", s->width, s->height);
  return "<figure>" + image(im.png, cap) + "<figcaption>" + html_escape(cap) +
         "</figcaption></figure>\n";
}

std::string contact_sheet(const RunReportData& run, const std::string& label) {
  std::string o;
  if (!run.sheet_note.empty()) o += note(run.sheet_note);
  if (run.sheet.empty()) return o;
  o += "<div class=\"sheet\">\n";
  for (const ReportImage& im : run.sheet) o += figure(run, im, label);
  return o + "</div>\n";
}

// ---- the summary of one run ----

std::vector<std::pair<std::string, std::string>> run_rows(const json& s) {
  std::vector<std::pair<std::string, std::string>> rows;
  rows.push_back({"scene", text(s, {"scene"}) + " (" + text(s, {"scene_file"}) + ")"});
  rows.push_back({"mode", mode_title(text(s, {"mode"}))});
  rows.push_back({"grains", count(s, {"n_total"})});
  {
    std::string v = count(s, {"frames"}) + " at " + general(s, {"fps"}) + " fps";
    if (const auto f = number(s, {"frames"}), fps = number(s, {"fps"}); f && fps && *fps > 0)
      v += fmt::format(" ({:.2f} s simulated)", *f / *fps);
    rows.push_back({"frames", v});
  }
  rows.push_back({"simulated grains (active + interface)",
                  "mean " + count(s, {"n_simulated_mean"}) + ", final " +
                      count(s, {"n_simulated_final"})});
  rows.push_back({"final state", "active " + count(s, {"n_active_final"}) + ", interface " +
                                     count(s, {"n_interface_final"}) + ", static " +
                                     count(s, {"n_static_final"})});
  rows.push_back({"seconds per frame (wall clock)",
                  fixed(s, {"seconds_per_frame"}, 3, " s") + " (total " +
                      fixed(s, {"wall_seconds"}, 1, " s") + ", " + count(s, {"threads"}) +
                      " threads)"});
  rows.push_back({"dt", general(s, {"dt_mean"}, " s") + " (" + count(s, {"substeps_per_frame"}) +
                            " substeps per frame; contact time t_c = " +
                            general(s, {"t_c"}, " s") + ")"});
  {
    std::string v = count(s, {"k_n"}) + " N/m";
    if (const json* st = find(s, {"stiffness", "from_load"}); st && st->is_boolean())
      v += st->get<bool>() ? " (from the load: [stiffness] from_load)" : " (set in the scene)";
    rows.push_back({"normal stiffness k_n", v});
  }
  if (const std::optional<double> angle = number(s, {"repose_angle_deg"}))
    rows.push_back({"angle of repose", fmt::format("{:.1f}\u00b0 (heap height {}, base radius {})",
                                                   *angle, fixed(s, {"heap", "height"}, 3, " m"),
                                                   fixed(s, {"heap", "base_radius"}, 3, " m"))});
  else
    rows.push_back({"angle of repose", "n/a (" + text(s, {"heap", "reason"}) + ")"});
  rows.push_back({"largest overlap", percent(s, {"max_overlap_rel"}) + " of a diameter"});
  rows.push_back({"grains inside geometry", count(s, {"grains_inside_geometry"})});
  if (find(s, {"transitions"}))
    rows.push_back({"transitions (whole run)",
                    "trapped " + count(s, {"transitions", "trapped"}) + ", dislodged " +
                        count(s, {"transitions", "dislodged"}) + ", slept " +
                        count(s, {"transitions", "slept"}) + ", woken " +
                        count(s, {"transitions", "woken"})});
  if (find(s, {"height_field"}))
    rows.push_back({"height field",
                    count(s, {"height_field", "nx"}) + " \u00d7 " + count(s, {"height_field", "ny"}) +
                        " cells of " + general(s, {"height_field", "cell_size"}, " m") +
                        ", static volume " +
                        general(s, {"height_field", "static_volume"}, " m\u00b3") +
                        ", rolling layer mean " +
                        general(s, {"height_field", "rolling_mean"}, " m")});
  if (const json* e = find(s, {"emitters"}); e && e->is_array())
    for (const json& em : *e)
      rows.push_back({"emitter '" + text(em, {"name"}) + "'",
                      count(em, {"emitted"}) + " of " + count(em, {"count"}) + " grains emitted, " +
                          count(em, {"delayed_by_occupied_slots"}) + " waited for a free slot" +
                          (find(em, {"left_out_by_occupied_slots"})
                               ? ", " + count(em, {"left_out_by_occupied_slots"}) +
                                     " left out (their places were taken)"
                               : std::string())});
  if (const json* st = find(s, {"stage_seconds"}); st && st->is_object()) {
    std::string v;
    for (const auto& [k, x] : st->items())
      if (x.is_number())
        v += fmt::format("{}{} {:.2f} s", v.empty() ? "" : ", ", k, x.get<double>());
      else
        WrongTypes::found(x, "a number");
    rows.push_back({"seconds per stage", v});
  }
  rows.push_back({"state hash", text(s, {"state_hash"})});
  rows.push_back({"sandflow version", text(s, {"sandflow_version"})});
  return rows;
}

// ---- plots ----

PlotSeries series(const StatsTable& t, const std::string& name,
                  const std::function<double(const std::vector<double>&)>& y,
                  const std::string& color, bool dashed = false) {
  PlotSeries s;
  s.name = name;
  s.color = color;
  s.dashed = dashed;
  const auto time = static_cast<std::size_t>(
      std::find(t.columns.begin(), t.columns.end(), "time") - t.columns.begin());
  for (const auto& row : t.rows) {
    s.x.push_back(row[time]);
    s.y.push_back(y(row));
  }
  return s;
}

/// y(row) = the named column
std::function<double(const std::vector<double>&)> col(const StatsTable& t, const std::string& name) {
  const auto c = static_cast<std::size_t>(
      std::find(t.columns.begin(), t.columns.end(), name) - t.columns.begin());
  return [c](const std::vector<double>& row) { return row[c]; };
}

std::function<double(const std::vector<double>&)> simulated(const StatsTable& t) {
  auto a = col(t, "n_active"), i = col(t, "n_interface");
  return [a, i](const std::vector<double>& row) { return a(row) + i(row); };
}

const char* kBlue = "#0072B2";
const char* kOrange = "#E69F00";
const char* kGreen = "#009E73";
const char* kRed = "#D55E00";
const char* kPurple = "#CC79A7";
const char* kGrey = "#999999";

/// One run's (or both modes') plots. `runs` pairs each run with its legend prefix.
std::string plots(const std::vector<std::pair<const RunReportData*, std::string>>& runs) {
  const bool both = runs.size() > 1;
  auto name = [&](const std::string& prefix, const std::string& what) {
    return both ? prefix + ": " + what : what;
  };
  LinePlot grains{"plot-grains", "Grains per frame", "simulated time t [s]", "grains", {}};
  LinePlot seconds{"plot-seconds", "Wall-clock seconds per frame", "simulated time t [s]",
                   "wall-clock time per frame [s]", {}};
  LinePlot dt{"plot-dt", "Time step dt", "simulated time t [s]", "dt [s]", {}};
  LinePlot trans{"plot-transitions", "Transitions per frame", "simulated time t [s]",
                 "grains per frame", {}};
  std::string notes;
  for (const auto& [run, prefix] : runs) {
    const StatsTable& t = run->stats;
    const bool dem = both ? prefix == "plain DEM"
                          : text(run->summary, {"mode"}) == "dem";
    // in a comparison the DEM run's lines are dashed, and their colours those of the same figure
    if (!both || !dem) {
      grains.series.push_back(series(t, name(prefix, "total"), col(t, "n_total"), kGrey, true));
      grains.series.push_back(series(t, name(prefix, "simulated (active + interface)"),
                                     simulated(t), kBlue));
      grains.series.push_back(series(t, name(prefix, "interface"), col(t, "n_interface"), kOrange));
      grains.series.push_back(series(t, name(prefix, "static"), col(t, "n_static"), kGreen));
    } else {
      grains.series.push_back(series(t, name(prefix, "simulated (all)"), simulated(t), kRed, true));
    }
    seconds.series.push_back(series(t, name(prefix, "seconds per frame"), col(t, "wall_seconds"),
                                    dem && both ? kRed : kBlue, dem && both));
    dt.series.push_back(series(t, name(prefix, "dt"), col(t, "dt"), dem && both ? kRed : kBlue,
                               dem && both));
    if (both && dem) continue;  // plain DEM has no transitions
    trans.series.push_back(series(t, name(prefix, "trapped"), col(t, "trapped"), kBlue));
    trans.series.push_back(series(t, name(prefix, "dislodged"), col(t, "dislodged"), kRed));
    trans.series.push_back(series(t, name(prefix, "slept"), col(t, "slept"), kGreen));
    trans.series.push_back(series(t, name(prefix, "woken"), col(t, "woken"), kPurple));
    if (dem) notes += note("Plain DEM has no height field: every grain stays active, so it has "
                           "no transitions.");
  }
  std::string o;
  for (const auto& [run, prefix] : runs)
    if (run->stats.frames() == 0)
      o += note(run->stats.path + ": no frames recorded (the run stopped before its first frame)");
  o += "<div class=\"plots\">\n";
  for (const LinePlot* p : {&grains, &seconds, &dt, &trans}) o += svg_line_plot(*p);
  o += "</div>\n";
  if (both)
    o += "<p>Solid lines: surface flow. Dashed: plain DEM. Plain DEM has no transitions (every "
         "grain stays active), so the last plot shows the surface-flow run only.</p>\n";
  return o + notes;
}

std::string notes_of(const RunReportData& run) {
  std::string o;
  for (const std::string& n : run.notes) o += note(n);
  return o;
}

std::string notes_of(const WrongTypes& wrong) {
  std::string o;
  for (const std::string& n : wrong.list()) o += note(n);
  return o;
}

std::string summary_path(const RunReportData& run) {
  return (fs::path(run.dir) / "summary.json").string();
}

std::string section(const std::string& id, const std::string& title, const std::string& body) {
  return "<section id=\"" + html_escape(id) + "\">\n<h2>" + html_escape(title) + "</h2>\n" + body +
         "</section>\n";
}

}  // namespace

// ---- loading ----

RunReportData load_run_report_data(const std::string& dir) {
  RunReportData r;
  r.dir = dir;
  r.stats = read_stats_csv((fs::path(dir) / "stats.csv").string());
  if (!r.stats.note.empty()) r.notes.push_back(r.stats.note);
  const std::string summary = summary_path(r);
  std::error_code ec;
  if (fs::exists(summary, ec))
    r.summary = read_json_object(summary);
  else
    r.notes.push_back(summary +
                      " is missing: the run did not finish, so only its statistics are shown");
  return r;
}

CompareReportData load_compare_report_data(const std::string& dir) {
  CompareReportData c;
  c.dir = dir;
  c.compare = read_json_object((fs::path(dir) / "compare.json").string());
  c.surface = load_run_report_data((fs::path(dir) / "surface").string());
  c.dem = load_run_report_data((fs::path(dir) / "dem").string());
  return c;
}

Table1ReportData load_table1_report_data(const std::string& dir) {
  Table1ReportData t;
  t.dir = dir;
  const std::string csv = (fs::path(dir) / "table1.csv").string();
  std::istringstream in(read_whole_file(csv, "table", kAnyFileSize));
  std::string line;
  int line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty()) continue;
    std::vector<std::string> fields;
    std::size_t start = 0;
    for (;;) {
      const std::size_t comma = line.find(',', start);
      fields.push_back(line.substr(start, comma - start));
      if (comma == std::string::npos) break;
      start = comma + 1;
    }
    if (t.columns.empty()) {
      if (fields[0] != "scene")
        throw InputError(fmt::format("{}:1: expected the header scene,total,...", csv));
      t.columns = fields;
    } else if (fields.size() != t.columns.size()) {
      throw InputError(fmt::format("{}:{}: {} fields; expected {} as in the header", csv, line_no,
                                   fields.size(), t.columns.size()));
    } else if (const std::string& scene = fields[0]; !is_plain_folder_name(scene)) {
      // (a scene's name is its folder under DIR: one that leads elsewhere is no scene of it)
      throw InputError(fmt::format("{}:{}: scene '{}' is not the name of a folder in {}", csv,
                                   line_no, scene, dir));
    } else {
      t.rows.push_back(fields);
    }
  }
  if (t.columns.empty()) throw InputError(fmt::format("{}:1: empty file; expected a header", csv));
  const fs::path md_path = fs::path(dir) / "table1.md";
  t.table_md = read_file_if_present(md_path.string(), "table", kAnyFileSize).value_or("");
  return t;
}

// ---- the pages ----

std::string run_report_html(const RunReportData& run) {
  const json& s = run.summary;
  const WrongTypes wrong({{&s, summary_path(run)}});
  const std::string mode = text(s, {"mode"});
  std::string body;
  body += section("summary", "Summary",
                  s.is_null() ? note("No summary.json: the run did not finish.") : table(run_rows(s)));
  body += section("plots", "Statistics per frame (stats.csv)", plots({{&run, mode_title(mode)}}));
  body += section("contact-sheet", "Contact sheet", contact_sheet(run, ""));
  const std::string title = fmt::format("sandflow report: {}", s.is_null() ? fs::path(run.dir).filename().string()
                                                                          : text(s, {"scene"}));
  const std::string sub = fmt::format("{}, {} grains, {} frames", mode_title(mode),
                                      count(s, {"n_total"}), count(double(run.stats.frames())));
  body = notes_of(run) + notes_of(wrong) + body;
  return page(title, sub,
              {{"summary", "Summary"}, {"plots", "Plots"}, {"contact-sheet", "Contact sheet"}}, body,
              run.dir);
}

std::string compare_report_html(const CompareReportData& c) {
  const json& j = c.compare;
  const json &ss = c.surface.summary, &sd = c.dem.summary;
  const WrongTypes wrong({{&j, (fs::path(c.dir) / "compare.json").string()},
                          {&ss, summary_path(c.surface)},
                          {&sd, summary_path(c.dem)}});
  std::string body;

  // summary: the two modes side by side
  auto row = [](const std::string& what, const std::string& dem, const std::string& surf) {
    return "<tr><th>" + html_escape(what) + "</th><td class=\"num\">" + html_escape(dem) +
           "</td><td class=\"num\">" + html_escape(surf) + "</td></tr>\n";
  };
  std::string sum = table({{"scene", text(j, {"scene"}) + " (" + text(j, {"scene_file"}) + ")"},
                           {"grains", count(j, {"n_total"})},
                           {"frames", count(j, {"frames"})},
                           {"threads", count(j, {"threads"})}});
  sum += "<table>\n<tr><th></th><th>plain DEM</th><th>surface flow</th></tr>\n";
  sum += row("simulated grains, mean", count(sd, {"n_simulated_mean"}),
             count(ss, {"n_simulated_mean"}));
  sum += row("simulated grains, final", count(sd, {"n_simulated_final"}),
             count(ss, {"n_simulated_final"}));
  sum += row("final state: active / interface / static",
             count(sd, {"n_active_final"}) + " / " + count(sd, {"n_interface_final"}) + " / " +
                 count(sd, {"n_static_final"}),
             count(ss, {"n_active_final"}) + " / " + count(ss, {"n_interface_final"}) + " / " +
                 count(ss, {"n_static_final"}));
  sum += row("seconds per frame", fixed(j, {"seconds_per_frame_dem"}, 3, " s"),
             fixed(j, {"seconds_per_frame_surface"}, 3, " s"));
  sum += row("wall-clock time", fixed(j, {"wall_seconds_dem"}, 1, " s"),
             fixed(j, {"wall_seconds_surface"}, 1, " s"));
  sum += row("k_n", count(j, {"k_n_dem"}) + " N/m", count(j, {"k_n_surface"}) + " N/m");
  sum += row("dt", general(j, {"dt_dem"}, " s"), general(j, {"dt_surface"}, " s"));
  // a scene with a bed makes a crater, not a heap (compare.json says so)
  const bool crater = find(j, {"crater_bed_height"}) != nullptr;
  if (crater) {
    sum += row("crater depth (mean over the seeds)", fixed(j, {"crater_depth_dem"}, 4, " m"),
               fixed(j, {"crater_depth_surface"}, 4, " m"));
    sum += row("rim height (mean over the seeds)", fixed(j, {"rim_height_dem"}, 4, " m"),
               fixed(j, {"rim_height_surface"}, 4, " m"));
    sum += row("craters measured, of the seeds",
               count(j, {"crater_fits", "dem"}) + " of " + count(j, {"seeds"}),
               count(j, {"crater_fits", "surface"}) + " of " + count(j, {"seeds"}));
  } else {
    sum += row("angle of repose (mean over the seeds)",
               fixed(j, {"repose_angle_dem_deg"}, 1, "\u00b0"),
               fixed(j, {"repose_angle_surface_deg"}, 1, "\u00b0"));
  }
  sum += row("largest overlap, of a diameter (all seeds)", percent(j, {"max_overlap_dem_rel"}),
             percent(j, {"max_overlap_surface_rel"}));
  sum += row("grains inside geometry", count(j, {"grains_inside_geometry_dem"}),
             count(j, {"grains_inside_geometry_surface"}));
  sum += row("state hash", text(sd, {"state_hash"}), text(ss, {"state_hash"}));
  sum += "</table>\n";
  if (c.run_reports)
    sum += "<p>Each run's own report: <a href=\"surface/report.html\">surface flow</a>, "
           "<a href=\"dem/report.html\">plain DEM</a>.</p>\n";
  body += section("summary", "Summary", sum);

  // the speed-up and where it comes from
  std::string sp = "<table>\n";
  auto kv = [&](const std::string& what, const std::string& v) {
    sp += "<tr><th>" + html_escape(what) + "</th><td class=\"num\">" + html_escape(v) +
          "</td></tr>\n";
  };
  kv("speed-up (DEM wall-clock time / surface flow's)", fixed(j, {"speedup"}, 2, "\u00d7"));
  if (number(j, {"speedup_min"}) && number(j, {"seeds"}).value_or(1) > 1)
    kv("speed-up by seed, smallest to largest",
       fixed(j, {"speedup_min"}, 2, "\u00d7") + " to " + fixed(j, {"speedup_max"}, 2, "\u00d7"));
  const auto dt_d = number(j, {"dt_dem"}), dt_s = number(j, {"dt_surface"});
  const auto n_d = number(j, {"n_simulated_mean_dem"}), n_s = number(j, {"n_simulated_mean"});
  const bool ratios = dt_d && dt_s && n_d && n_s && *dt_d > 0 && *n_s > 0;
  kv("dt ratio (surface / DEM)", ratios ? fmt::format("{:.2f}", *dt_s / *dt_d) : kDash);
  kv("simulated-grain ratio, mean (DEM / surface)",
     ratios ? fmt::format("{:.2f}", *n_d / *n_s) : kDash);
  kv("their product: the speed-up if cost were proportional to simulated grain-steps",
     ratios ? fmt::format("{:.2f}\u00d7", (*dt_s / *dt_d) * (*n_d / *n_s)) : kDash);
  kv("simulated fraction: mean / last half / final",
     percent(j, {"simulated_fraction_mean"}) + " / " + percent(j, {"simulated_fraction_last_half"}) +
         " / " + percent(j, {"simulated_fraction_final"}));
  kv("speed-up at equal stiffness (plain DEM at the surface run's k_n and dt)",
     fixed(j, {"speedup_equal_stiffness"}, 2, "\u00d7"));
  kv("seeds per mode", count(j, {"seeds"}));
  kv("final sand surfaces, RMS distance (surface flow to plain DEM)",
     fixed(j, {"surface_rms"}, 4, " m") + " = " + fixed(j, {"surface_rms_d"}, 2, " d") + " = " +
         percent(j, {"surface_rms_rel"}) + " of the scene's height (" +
         fixed(j, {"reference_height"}, 3, " m") + ")");
  kv("the same between plain-DEM seeds: the noise floor",
     fixed(j, {"surface_rms_dem_vs_dem"}, 4, " m") + " = " +
         fixed(j, {"surface_rms_dem_vs_dem_d"}, 2, " d") + " = " +
         percent(j, {"surface_rms_dem_vs_dem_rel"}));
  if (crater) {
    auto within = [&](const char* key) {
      const json* w = find(j, {key});
      if (w && !w->is_boolean() && !w->is_null()) WrongTypes::found(*w, "true or false");
      return w && w->is_boolean() ? (w->get<bool>() ? "yes" : "no") : kDash;
    };
    kv("crater depth, difference of the means", fixed(j, {"crater_depth_diff"}, 4, " m"));
    kv("crater depth, spread of the plain-DEM seeds",
       fixed(j, {"crater_depth_dem_spread"}, 4, " m"));
    kv("crater depth, difference within the spread", within("crater_depth_within_spread"));
    kv("rim height, difference of the means", fixed(j, {"rim_height_diff"}, 4, " m"));
    kv("rim height, spread of the plain-DEM seeds", fixed(j, {"rim_height_dem_spread"}, 4, " m"));
    kv("rim height, difference within the spread", within("rim_height_within_spread"));
    kv("angle of repose", text(j, {"repose_angle_skipped"}));
  } else {
    kv("angles of repose, difference of the means",
       fixed(j, {"repose_angle_diff_deg"}, 1, "\u00b0"));
    kv("angles of repose, spread of the plain-DEM seeds",
       fixed(j, {"repose_angle_dem_spread_deg"}, 1, "\u00b0"));
  }
  kv("energy added by waking / removed by trapping (mean per run)",
     general(j, {"energy_added_by_waking_j"}, " J") + " / " +
         general(j, {"energy_removed_by_trapping_j"}, " J"));
  sp += "</table>\n";
  body += section("speedup", "Speed-up and sameness", sp);

  body += section("plots", "Statistics per frame, both modes",
                  plots({{&c.surface, "surface flow"}, {&c.dem, "plain DEM"}}));

  // the last frames next to each other
  std::string ff;
  if (!c.final_note.empty()) ff += note(c.final_note);
  if (c.final_dem || c.final_surface) {
    ff += "<div class=\"pair\">\n";
    ff += c.final_dem ? figure(c.dem, *c.final_dem, "plain DEM") : note("plain DEM: no picture");
    ff += c.final_surface ? figure(c.surface, *c.final_surface, "surface flow")
                          : note("surface flow: no picture");
    ff += "</div>\n";
  }
  body += section("final-frames", "Final frames", ff);

  body += section("contact-sheet", "Contact sheets",
                  "<h3>Surface flow</h3>\n" + contact_sheet(c.surface, "") +
                      "<h3>Plain DEM</h3>\n" + contact_sheet(c.dem, ""));
  const std::string sub = fmt::format("plain DEM against surface flow, {} grains, {} frames",
                                      count(j, {"n_total"}), count(j, {"frames"}));
  body = notes_of(c.surface) + notes_of(c.dem) + notes_of(wrong) + body;
  return page("sandflow comparison: " + text(j, {"scene"}), sub,
              {{"summary", "Summary"},
               {"speedup", "Speed-up"},
               {"plots", "Plots"},
               {"final-frames", "Final frames"},
               {"contact-sheet", "Contact sheets"}},
              body, c.dir);
}

/// table1.csv's columns as the page heads them, and how their numbers read
struct Table1Column {
  const char* name;
  const char* head;
  std::string (*format)(double);
};
const Table1Column kTable1Columns[] = {
    {"total", "grains", [](double v) { return count(v); }},
    {"surface_simulated_mean", "surface flow: simulated grains (mean)",
     [](double v) { return count(v); }},
    {"surface_s_per_frame", "surface flow: s/frame",
     [](double v) { return fmt::format("{:.3f}", v); }},
    {"dem_simulated_mean", "plain DEM: simulated grains (mean)", [](double v) { return count(v); }},
    {"dem_s_per_frame", "plain DEM: s/frame", [](double v) { return fmt::format("{:.3f}", v); }},
    {"speedup", "speed-up", [](double v) { return fmt::format("{:.2f}\u00d7", v); }},
    {"surface_rms_rel", "surfaces apart (RMS / scene height)",
     [](double v) { return fmt::format("{:.1f} %", 100 * v); }},
    {"grains_inside_geometry", "grains inside geometry", [](double v) { return count(v); }},
    {"max_overlap_surface_rel", "surface flow: largest overlap",
     [](double v) { return fmt::format("{:.1f} %", 100 * v); }},
    {"impact_overlap", "impact_overlap", [](double v) { return fmt::format("{:.0f} %", 100 * v); }},
    {"energy_added_by_waking_j", "energy added by waking",
     [](double v) { return fmt::format("{:.3g} J", v); }},
};

std::string table1_report_html(const Table1ReportData& t) {
  auto column = [](const std::string& name) -> const Table1Column* {
    for (const Table1Column& c : kTable1Columns)
      if (name == c.name) return &c;
    return nullptr;
  };
  std::string tab = "<div class=\"wide\"><table>\n<tr>";
  for (const std::string& c : t.columns)
    tab += "<th>" + html_escape(column(c) ? column(c)->head : c) + "</th>";
  tab += "</tr>\n";
  for (const auto& r : t.rows) {
    tab += "<tr>";
    for (std::size_t k = 0; k < r.size(); ++k) {
      if (k == 0) {
        const bool link = std::find(t.linked.begin(), t.linked.end(), r[0]) != t.linked.end();
        tab += "<td>" + (link ? "<a href=\"" + html_escape(r[0]) + "/report.html\">" +
                                    html_escape(r[0]) + "</a>"
                              : html_escape(r[0])) +
               "</td>";
        continue;
      }
      // a number of a known column formatted, anything else as written
      std::string v = r[k];
      double x = 0;
      const auto [end, ec] = std::from_chars(r[k].data(), r[k].data() + r[k].size(), x);
      const Table1Column* c = k < t.columns.size() ? column(t.columns[k]) : nullptr;
      if (c && ec == std::errc() && end == r[k].data() + r[k].size()) v = c->format(x);
      tab += "<td class=\"num\">" + html_escape(v) + "</td>";
    }
    tab += "</tr>\n";
  }
  tab += "</table></div>\n";
  if (t.rows.empty()) tab += note("table1.csv has no rows: no scene has finished yet.");
  std::string body = section("summary", "Table 1 (table1.csv)", tab);
  std::string scenes;
  if (t.linked.empty())
    scenes += note("No scene folder with a compare.json: no scene's report.");
  else {
    scenes += "<ul>\n";
    for (const std::string& s : t.linked)
      scenes += "<li><a href=\"" + html_escape(s) + "/report.html\">" + html_escape(s) + "</a></li>\n";
    scenes += "</ul>\n";
  }
  if (!t.table_md.empty()) scenes += "<h3>table1.md</h3>\n<pre>" + html_escape(t.table_md) + "</pre>\n";
  body += section("scenes", "Scenes", scenes);
  return page("sandflow Table 1", "the paper's scenes, each in both modes",
              {{"summary", "Table 1"}, {"scenes", "Scenes"}}, body, t.dir);
}

}  // namespace sandflow
