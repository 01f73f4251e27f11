// The commands of `sandflow`, one file each (run.cpp, compare.cpp, table1.cpp, render.cpp), and
// what they share: the options of a run, the run driver and the comparison of two runs.
// main() in sandflow.cpp parses the command line and maps the errors to exit codes.
#pragma once

#include <csignal>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "analysis/crater.hpp"
#include "analysis/heap.hpp"
#include "analysis/surface_diff.hpp"
#include "calibration/calibration.hpp"
#include "checkpoint/checkpoint.hpp"
#include "sim/world.hpp"

namespace sandflow {

struct RunOptions {
  std::string scene;
  std::string mode;
  std::string out;
  int frames = 0;
  std::int64_t grains = 0;
  int threads = 0;
  std::vector<std::string> sets;
  bool check = false;
  bool force = false;
  bool profile = false;
  std::optional<std::string> exports;  ///< --export LIST (overrides output.export)
  std::string up_axis;                 ///< --up-axis z|y (overrides output.up_axis)
  std::string resume;         ///< --resume DIR: continue the run in DIR
  int checkpoint_every = -1;  ///< frames between checkpoints; -1: the default (or the run's own)
};

/// Frames between checkpoints when --checkpoint-every is not given: one second of simulated time
/// at the default 30 fps (docs/checkpoints.md says why).
constexpr int kDefaultCheckpointEvery = 30;

struct Table1Options {
  double scale = 1;
  int frames = 0;
  int threads = 0;
  std::string out = "out/table1";
  std::string scene_dir;
  std::vector<std::string> scenes;
  bool force = false;
  bool resume = false;  ///< keep what OUT holds: finished scenes are read back, stopped ones go on
  int seeds = 1;        ///< runs per mode of each scene (CompareOptions::seeds)
};

struct RenderOptions {
  std::string dir;  ///< a run folder, or a comparison's (surface/ and dem/)
  int width = 1280, height = 720;
  int frame = 0;                  ///< 0: the last (unless `frames` is given)
  std::string frames;             ///< "N", "A:B", "A:", ":B", "all" or ":"; "": `frame`
  std::string quality = "final";  ///< "final" (antialiased, soft light) or "draft"
  int jobs = 0;                   ///< frames rendered at once; 0: one per core
  bool movie = false;             ///< also encode DIR/render/movie.mp4 with ffmpeg
  bool keep_pov = false;          ///< keep each picture's .pov scene and the logs
  bool again = false;             ///< make every picture, also those made from the same input
  std::string scene;              ///< scene file; "": the one DIR/summary.json names
  std::vector<std::string> sets;  ///< --set camera.KEY=... or geometry.N.render=...
  bool folder_held = false;       ///< the caller holds DIR/render/'s lock (a report's pictures)
};

/// `sandflow report` (report.cpp)
struct ReportOptions {
  std::string dir;
  int contact_sheet = 6;  ///< frames on the contact sheet (0: none)
  bool render = true;     ///< render the frames the page shows that have no PNG yet
};

std::string mode_name(Mode m);
/// `a` as a shell word: quoted when it has anything but letters, digits and _-+./=:,@%.
std::string shell_quote(const std::string& a);
/// What is wrong with `dir` as a folder to read: "" (it is one), "no such folder", or that it is
/// a file.
std::string folder_problem(const std::string& dir);
/// The options a run folder's run.json records (its scene file made absolute from the folder the
/// run was started in), the record itself and the scene text the run was started with.
RunOptions read_run_record(const std::string& dir, nlohmann::json& record, std::string& text);
/// The scene of a recorded run, as read_run_record returned it: its text with the run's options.
SceneConfig recorded_scene(const RunOptions& r, const std::string& text,
                           const nlohmann::json& record);
/// The scene of a run: the file, its --set overrides, --mode, --grains, --frames, --threads,
/// --export, --up-axis.
SceneConfig load_for_run(const RunOptions& o);
int thread_count(const SceneConfig& scene);

/// Prints "warning: TEXT" on stderr once per command: compare and table1 load a scene for each
/// of their runs, and its warnings printed at every one bury the rest of the output.
void warn_once(const std::string& text);

/// `sandflow calibrate` (calibrate.cpp): measures (or, unless `again`, reads from the cache) the
/// angles of the scene's material with `trials` seeds, prints and caches them.
int calibrate_command(const RunOptions& o, int trials, bool again, const RigSettings& rig);
/// Where measured calibrations are kept: $SANDFLOW_CACHE_DIR/calibration, else
/// $XDG_CACHE_HOME/sandflow/calibration, else ~/.cache/sandflow/calibration.
std::string calibration_cache_dir();
/// The cached calibration of `key` (calibration_key), if a valid one is there.
std::optional<nlohmann::json> cached_calibration(const std::string& key);
/// Why measured calibrations cannot be kept (the cache folder cannot be made or written), or ""
/// when they can; makes the folder.
std::string calibration_cache_problem();
/// Thrown by measure_calibration when SIGINT or SIGTERM asked it to stop: nothing is kept.
struct CalibrationInterrupted {
  int signal;
};
/// Measures the scene's material with `trials` seeds, printing progress, and caches the result
/// when `keep`; SIGINT or SIGTERM stops it within a frame of the rig (CalibrationInterrupted).
nlohmann::json measure_calibration(const SceneConfig& scene, int trials,
                                   const RigSettings& rig = {}, bool keep = true);
/// Trials of a calibration measured for a run (and by `sandflow calibrate` by default).
constexpr int kDefaultCalibrationTrials = 3;
/// True when SANDFLOW_NO_CALIBRATION is set (and not "0"): a surface run whose scene leaves the
/// angles unset then takes the built-in defaults (32 degrees, + 6) instead of measuring them.
bool calibration_disabled();
/// True for a surface-mode scene that leaves surface.repose_angle or max_angle unset.
bool needs_calibration(const SceneConfig& scene);
/// Fills the angles a surface-mode scene leaves unset from its material's calibration (cached,
/// or measured now) and returns what the run uses: repose_angle_deg, max_angle_deg, source.
nlohmann::json resolve_surface_angles(SceneConfig& scene);
/// Sets the angles `resolve_surface_angles` returned (a resumed run's, from its run.json).
void apply_surface_angles(SceneConfig& scene, const nlohmann::json& angles);

/// What a finished run leaves for the caller: its summary and its final grains.
struct RunResult {
  nlohmann::json summary;
  std::vector<FrameStats> frames;
  std::vector<Vec3> x;  ///< every grain's centre at the end
  std::vector<Real> r;
  double wall_seconds = 0;
  HeapFit heap;
};

/// What makes a run resumable (`sandflow run`; compare and table1 leave it empty).
struct RunControl {
  std::string start_record;   ///< how the run was started, hashed into its checkpoints ("": none)
  int checkpoint_every = 0;   ///< frames between checkpoints (and one after the last); 0: none
  Checkpoint* resume = nullptr;  ///< continue from this state (moved from)
  /// `out` holds a stopped run: once the state is restored (or from the start, without one), its
  /// temporary files and the frames after the checkpoint go, and stats.csv is rewritten.
  bool resumed = false;
  /// Set by a signal handler: finish the frame, write a checkpoint, throw RunInterrupted.
  const volatile std::sig_atomic_t* stop = nullptr;
};

/// Thrown by run_scene when `RunControl::stop` was set: a checkpoint of `frame` is written.
struct RunInterrupted {
  int frame;
  int signal;
};

/// Runs a scene into `out` (prepared by the caller), writing stats.csv, frames and summary.json,
/// and with `control`, DIR/checkpoint.bin. `label` prefixes the progress line (table1's "scene k
/// of n: ").
RunResult run_scene(const SceneConfig& scene, const std::string& out, const std::string& label = "",
                    const RunControl& control = {});

/// One run of `compare` or `table1` into o.out (o.mode set), resumable as `sandflow run` is:
/// run.json, a checkpoint every o.checkpoint_every frames (default 30), the stop signals. With
/// `resume` and a run.json in o.out, the run there goes on from its checkpoint (a finished one is
/// read back from its last), provided it was started as `o` asks (InputError otherwise); without,
/// o.out must be empty or new. `run_to_frame` > 0 runs it on to that frame, as `sandflow run
/// --resume DIR --frames N` does (a new one is started to end there). `scene_text` is the scene
/// file's text (nullptr: read o.scene); `resume_with` is the command the messages give to
/// continue. Returns 0, or 128 + the signal when a stop signal interrupted it (its checkpoint
/// written). `scene`: the scene it ran.
int run_part(const RunOptions& o, bool resume, const std::string* scene_text,
             const std::string& resume_with, const std::string& label, RunResult& res,
             SceneConfig& scene, int run_to_frame = 0);

/// The command that continues the run in `dir`: `sandflow run --resume DIR`.
std::string resume_command(const std::string& dir);

/// InputError when o.out holds a run (run.json) started otherwise than `o` with scene `text`
/// would start it, or, unless `run_on`, run on to another frame: run_part could not resume it as
/// that run. Returns the frame it was run on to (0: none, or no run there).
int check_resumable(const RunOptions& o, const std::string& text, bool run_on = false);

/// The most seeds per mode a comparison runs.
constexpr int kMaxSeeds = 100;

/// What a comparison runs besides one run per mode.
struct CompareOptions {
  int seeds = 3;                 ///< runs per mode, seeds s0, s0 + 1, ... (s0: the scene's)
  bool equal_stiffness = false;  ///< and one plain-DEM run at the surface run's k_n and dt
  int run_to_frame = 0;          ///< `compare --resume DIR --frames N`: every run on to N (0: not)
  bool seeds_given = false;      ///< --seeds on the command line (not the default)
  bool equal_stiffness_given = false;  ///< --equal-stiffness on the command line
  /// --dem-from DIR: an earlier comparison whose plain-DEM runs, where they were started as this
  /// comparison's would be, are copied in and read back instead of made again ("": none)
  std::string dem_from;
};

/// The runs of a scene in both modes and the figures compared (what compare.json holds).
struct Comparison {
  SceneConfig scene;                   ///< as the first surface run had it
  std::vector<std::int64_t> seeds;     ///< simulation.seed of each pair of runs
  std::vector<RunResult> surface, dem;  ///< one per seed, in the order of `seeds`
  std::optional<RunResult> dem_equal_stiffness;
  nlohmann::json json;
};

/// The folder of a comparison's run: OUT/surface and OUT/dem for the first seed, OUT/seed-S/MODE
/// for the others, OUT/dem-equal-stiffness.
std::string compare_run_dir(const std::string& out, const std::string& mode, std::size_t index,
                            std::int64_t seed);

/// The shared part of `compare` and `table1`: runs `o` in surface mode and in plain DEM (each
/// with run_part) for each seed, and the equal-stiffness run, compares the final surfaces and
/// heaps and writes OUT/compare.json. OUT is prepared here: refused when not empty unless `force`
/// (which replaces the comparison) or `resume` (which goes on with it, as OUT/compare_plan.json
/// records it); `scene_text` and `resume_with` as for run_part; `label` prefixes the progress
/// lines. Returns 0, or 128 + the signal when interrupted.
int compare_scene(const RunOptions& o, const CompareOptions& co, const std::string& out, bool force,
                  bool resume, const std::string* scene_text, const std::string& resume_with,
                  const std::string& label, Comparison& c);

/// The top of the crater site's bed as packed for the scene seed `seed` (bed_level), the level a
/// crater is measured from; NaN when the bed cannot be packed (measure_crater then finds it).
double packed_bed_level(const SceneConfig& scene, const Geometry& geometry, const CraterSite& site,
                        std::uint64_t seed);

/// The last frame file of a run folder (InputError when it has none).
std::string last_frame(const std::string& dir);

int run_command(const RunOptions& o);
/// What `sandflow measure` reads and leaves out.
struct MeasureOptions {
  std::string dir;
  int frame = 0;           ///< frames/NNNN.ply; 0: the final state
  std::string frames;      ///< a series of frames, one line each ("A:B:K", ...); "": `frame`
  double slower_than = 0;  ///< leave out grains this fast or faster [m/s]; 0: none
};

int measure_command(const MeasureOptions& o);
int compare_command(const RunOptions& o, const CompareOptions& co);
/// `command`: the command line as typed, recorded in table1.md.
int table1_command(const Table1Options& o, const std::string& command);
int render_command(const RenderOptions& o);
/// Writes DIR/report.html for a run, compare or table1 folder and returns its path.
std::string write_report(const ReportOptions& o);
int report_command(const ReportOptions& o);

}  // namespace sandflow
