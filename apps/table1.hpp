// `sandflow table1`: the paper's Table 1 (Zhu & Yang 2010) measured again, each scene run in both
// modes by the same code as `sandflow compare`. This header holds the paper's figures and the
// formatting of the table (CSV, Markdown, text); running the scenes is in table1.cpp.
//
// The rows of the CSV are the scenes that ran, numbers only, so it reads as data; the Markdown
// and the printed table also list the scenes that were skipped (no scene file), failed (with
// the error) or not yet run (an interrupted run), so nothing is silently left out.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include <fmt/format.h>

namespace sandflow {

/// One row of the paper's Table 1 ("Particle numbers and timing data"), measured on the paper's
/// hardware (a dual-core 2.66 GHz CPU with 4 GB of memory), surface-flow method only.
struct PaperScene {
  std::string_view name;   ///< the scene file's stem: scenes/<name>.toml
  std::string_view title;  ///< as the paper names it
  std::int64_t total;      ///< grains in the scene
  std::int64_t surface;    ///< grains simulated with DEM by the surface-flow method
  double seconds_per_frame;
};

inline constexpr std::array<PaperScene, 5> kPaperTable1 = {{
    {"floor", "Floor", 107687, 28410, 8.62},
    {"terrain", "Terrain", 199039, 48423, 18.27},
    {"bowl", "Bowl", 318053, 24710, 11.01},
    {"dragon", "Dragon", 192975, 40043, 30.05},
    {"armadillo", "Armadillo", 207020, 58540, 21.54},
}};

/// The paper's plain DEM figure: only the Floor has one, in the text of §4 ("approximately 9s per
/// frame on average, compared to 68s in standard DEM method").
inline constexpr double kPaperFloorDemSecondsPerFrame = 68.0;

inline const PaperScene* find_paper_scene(std::string_view name) {
  for (const PaperScene& p : kPaperTable1)
    if (p.name == name) return &p;
  return nullptr;
}

inline std::string known_scene_names() {
  std::string s;
  for (const PaperScene& p : kPaperTable1) s += (s.empty() ? "" : ", ") + std::string(p.name);
  return s;
}

/// Grains of a scene at `scale`: round(scale x the paper's count).
inline std::int64_t scaled_count(const PaperScene& p, double scale) {
  return static_cast<std::int64_t>(std::llround(scale * static_cast<double>(p.total)));
}

enum class RowStatus { Pending, Missing, Failed, Done };

/// One measured row. The figures are valid when status == Done.
struct Table1Row {
  std::string scene;
  RowStatus status = RowStatus::Pending;
  std::string message;       ///< why a scene is missing or failed
  std::int64_t total = 0;    ///< the scene's grains: round(scale x the paper's count)
  std::int64_t emitted = 0;  ///< grains present at the end (fewer if the run ended mid-pour)
  double surface_simulated_mean = 0, surface_s_per_frame = 0;
  double dem_simulated_mean = 0, dem_s_per_frame = 0;
  double speedup = 0;
  double surface_rms_rel = 0;  ///< RMS distance of the final surfaces over the scene's height
  std::int64_t inside_dem = 0, inside_surface = 0;  ///< grains inside geometry at the end
  double max_overlap_surface = 0;  ///< largest overlap of the surface runs, of a diameter
  double impact_overlap = 0;       ///< the scene's stiffness.impact_overlap
  double energy_woken = 0;         ///< energy added by waking and dislodging (mean per run) [J]
};

inline constexpr std::string_view kTable1CsvHeader =
    "scene,total,emitted,surface_simulated_mean,surface_s_per_frame,dem_simulated_mean,"
    "dem_s_per_frame,speedup,surface_rms_rel,grains_inside_geometry,max_overlap_surface_rel,"
    "impact_overlap,energy_added_by_waking_j";

/// table1.csv: the header and one row per scene that ran; grains_inside_geometry is the sum of
/// both modes.
inline std::string table1_csv(const std::vector<Table1Row>& rows) {
  std::string s = std::string(kTable1CsvHeader) + "\n";
  for (const Table1Row& r : rows)
    if (r.status == RowStatus::Done)
      s += fmt::format(
          "{},{},{},{:.1f},{:.6g},{:.1f},{:.6g},{:.6g},{:.6g},{},{:.6g},{:.6g},{:.6g}\n", r.scene,
          r.total, r.emitted, r.surface_simulated_mean, r.surface_s_per_frame, r.dem_simulated_mean,
          r.dem_s_per_frame, r.speedup, r.surface_rms_rel, r.inside_dem + r.inside_surface,
          r.max_overlap_surface, r.impact_overlap, r.energy_woken);
  return s;
}

/// 107687 -> "107,687".
inline std::string thousands(std::int64_t n) {
  std::string digits = std::to_string(n < 0 ? -n : n), s;
  for (std::size_t k = 0; k < digits.size(); ++k) {
    if (k > 0 && (digits.size() - k) % 3 == 0) s += ',';
    s += digits[k];
  }
  return n < 0 ? "-" + s : s;
}

/// The cells of a row as the Markdown and the printed table show them.
inline std::array<std::string, 10> table1_cells(const Table1Row& r) {
  switch (r.status) {
    case RowStatus::Pending:
      return {r.scene, "not run", "", "", "", "", "", "", "", ""};
    case RowStatus::Missing:
      return {r.scene, "missing", "", "", "", "", "", "", "", ""};
    case RowStatus::Failed:
      return {r.scene, "failed", "", "", "", "", "", "", "", ""};
    case RowStatus::Done:
      break;
  }
  const double frac = r.total > 0 ? r.surface_simulated_mean / static_cast<double>(r.total) : 0;
  return {
      r.scene,
      r.emitted < r.total ? fmt::format("{} ({} poured)", thousands(r.total), thousands(r.emitted))
                          : thousands(r.total),
      fmt::format("{} ({:.0f} %)",
                  thousands(static_cast<std::int64_t>(std::llround(r.surface_simulated_mean))),
                  100 * frac),
      fmt::format("{:.3g}", r.surface_s_per_frame),
      fmt::format("{:.3g}", r.dem_s_per_frame),
      fmt::format("{:.2f}x", r.speedup),
      std::isnan(r.surface_rms_rel) ? std::string("n/a")
                                    : fmt::format("{:.1f} %", 100 * r.surface_rms_rel),
      fmt::format("{} ({} + {})", r.inside_dem + r.inside_surface, r.inside_dem, r.inside_surface),
      fmt::format("{:.1f} % (of {:.0f} %)", 100 * r.max_overlap_surface, 100 * r.impact_overlap),
      fmt::format("{:.3g} J", r.energy_woken)};
}

inline constexpr std::array<std::string_view, 10> kTable1Titles = {
    "scene",
    "total",
    "surface simulated (mean)",
    "surface s/frame",
    "DEM s/frame",
    "speed-up",
    "surface_rms_rel",
    "grains inside geometry (DEM + surface)",
    "surface max overlap (of impact_overlap)",
    "energy added by waking"};

/// Why the scenes that did not run did not: one line each, or nothing.
inline std::string table1_notes(const std::vector<Table1Row>& rows, std::string_view bullet) {
  std::string s;
  for (const Table1Row& r : rows)
    if (r.status == RowStatus::Missing || r.status == RowStatus::Failed)
      s += fmt::format("{}{}: {}: {}\n", bullet, r.scene,
                       r.status == RowStatus::Missing ? "skipped" : "failed", r.message);
  return s;
}

/// The paper's figures, quoted for reference.
inline std::string paper_reference() {
  std::string s =
      "The paper's Table 1 (Zhu & Yang 2010, measured on the paper's hardware, a dual-core "
      "2.66 GHz CPU with 4 GB of memory; surface-flow method only): ";
  for (std::size_t k = 0; k < kPaperTable1.size(); ++k) {
    const PaperScene& p = kPaperTable1[k];
    s += fmt::format("{}{} {} grains in total, {} simulated, {:.2f} s/frame", k ? "; " : "",
                     p.title, thousands(p.total), thousands(p.surface), p.seconds_per_frame);
  }
  s += fmt::format(
      ". Its text gives plain DEM on the Floor, every one of the 107,687 grains simulated, as "
      "{:.0f} s/frame, against about 9 s with the surface flow.",
      kPaperFloorDemSecondsPerFrame);
  return s;
}

/// What the Markdown records of the run besides the table.
struct Table1Context {
  std::string command;  ///< the command line as typed
  std::string date;     ///< local date and time, ISO 8601
  int cores = 0;        ///< logical processors of this machine
  int threads = 0;      ///< OpenMP threads the runs used
  double scale = 1;
  int frames = 0;  ///< 0: each scene's own
};

/// table1.md: the measured table, the notes on scenes not run, the run and the paper's figures.
inline std::string table1_markdown(const std::vector<Table1Row>& rows, const Table1Context& c) {
  std::string s = "# Table 1 of Zhu & Yang 2010, measured by sandflow\n\n|";
  for (std::string_view t : kTable1Titles) s += fmt::format(" {} |", t);
  s += "\n|";
  for (std::size_t k = 0; k < kTable1Titles.size(); ++k) s += k == 0 ? "---|" : "---:|";
  s += "\n";
  for (const Table1Row& r : rows) {
    s += "|";
    for (const std::string& cell : table1_cells(r)) s += fmt::format(" {} |", cell);
    s += "\n";
  }
  const std::string notes = table1_notes(rows, "- ");
  if (!notes.empty()) s += "\n" + notes;
  s += fmt::format(
      "\nCommand `{}`, {}, on {} logical cores with {} threads; grain counts {} x the paper's, {}. "
      "Surface simulated: mean over the frames of the grains in the DEM (active + interface); "
      "speed-up: plain DEM's wall time over the surface flow's; surface_rms_rel: RMS distance "
      "between the two final sand surfaces, over the height of the cone that holds all the "
      "scene's grains (docs/physics.md, Sameness); surface max overlap: the largest overlap of "
      "any frame of the surface runs, in diameters, beside the scene's stiffness.impact_overlap; "
      "energy added by waking: the work of the springs of woken and dislodged grains' contacts "
      "(docs/physics.md, Transitions and energy).\n",
      c.command, c.date, c.cores, c.threads, c.scale,
      c.frames > 0 ? fmt::format("{} frames each", c.frames) : std::string("each scene's frames"));
  s += "\n" + paper_reference() + "\n";
  return s;
}

/// The table as printed on the terminal: aligned columns, then the notes.
inline std::string table1_text(const std::vector<Table1Row>& rows) {
  std::vector<std::array<std::string, 10>> cells;
  std::array<std::string, 10> titles;
  for (std::size_t k = 0; k < titles.size(); ++k) titles[k] = std::string(kTable1Titles[k]);
  titles[7] = "inside geometry";
  titles[8] = "surface max overlap";
  cells.push_back(titles);
  for (const Table1Row& r : rows) cells.push_back(table1_cells(r));
  std::array<std::size_t, 10> width{};
  for (const auto& row : cells)
    for (std::size_t k = 0; k < row.size(); ++k) width[k] = std::max(width[k], row[k].size());
  std::string s;
  for (const auto& row : cells) {
    std::string line;
    for (std::size_t k = 0; k < row.size(); ++k)
      line += k == 0 ? fmt::format("{:<{}}", row[k], width[k])
                     : fmt::format("  {:>{}}", row[k], width[k]);
    s += line.substr(0, line.find_last_not_of(' ') + 1) + "\n";
  }
  const std::string notes = table1_notes(rows, "");
  return notes.empty() ? s : s + "\n" + notes;
}

}  // namespace sandflow
