// The `sandflow` command: argument parsing, printing and exit codes. The simulation itself is in
// the library (src/); this file only drives it.
//
// Exit status: 0 done, 1 unexpected failure, 2 bad input (scene, option, file),
// 3 the simulation blew up, 4 an output could not be written, 128 + N stopped by signal N.
#include <omp.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <csignal>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <string>
#include <system_error>
#include <vector>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <CLI/CLI.hpp>

#include "commands.hpp"
#include "console.hpp"
#include "core/error.hpp"
#include "core/threads.hpp"
#include "sim/world.hpp"

using namespace sandflow;

namespace {

/// The command line as typed, quoted where a shell would need it.
std::string command_line(int argc, char** argv) {
  std::string s;
  for (int k = 0; k < argc; ++k) {
    std::string a = argv[k];
    if (a.empty() || a.find_first_of(" \t'\"$\\*?;&|<>()") != std::string::npos) {
      std::string q = "'";
      for (char ch : a) q += ch == '\'' ? std::string("'\\''") : std::string(1, ch);
      a = q + "'";
    }
    s += (k ? " " : "") + a;
  }
  return s;
}

/// Reads all of `v` into `x` (a leading + allowed, as CLI11 reads it): from_chars' error, and
/// invalid_argument also for nothing or for characters left over.
template <class T>
std::errc read_all(const std::string& v, T& x) {
  const char* end = v.data() + v.size();
  const char* begin = v.data() + (v.size() > 1 && v[0] == '+');
  const auto [p, ec] = std::from_chars(begin, end, x);
  return v.empty() || p != end ? std::errc::invalid_argument : ec;
}

/// A count from lo to hi, written as a whole number: CLI11's Range alone calls "2e2" or "1.0"
/// out of range, which sends the user looking for the wrong mistake.
CLI::Validator whole(std::int64_t lo, std::int64_t hi) {
  return CLI::Validator(
      [lo, hi](std::string& v) {
        std::int64_t n = 0;
        const std::errc ec = read_all(v, n);
        if (ec == std::errc::invalid_argument)
          return fmt::format("{} is not a whole number", v.empty() ? "''" : v);
        if (ec == std::errc::result_out_of_range || n < lo || n > hi)
          return fmt::format("{} is not in range {} to {}", v, lo, hi);
        return std::string();
      },
      fmt::format("INT in [{} - {}]", lo, hi));
}

/// A number from lo to hi. CLI11's Range lets "nan" through (no comparison with it is true), and
/// calls "abc" out of range rather than no number.
CLI::Validator real_in(double lo, double hi) {
  return CLI::Validator(
      [lo, hi](std::string& v) {
        double x = 0;
        const std::errc ec = read_all(v, x);
        if (ec == std::errc::invalid_argument)
          return fmt::format("{} is not a number", v.empty() ? "''" : v);
        if (ec == std::errc::result_out_of_range || !std::isfinite(x) || x < lo || x > hi)
          return fmt::format("{} is not in range {:g} to {:g}", v, lo, hi);
        return std::string();
      },
      fmt::format("NUMBER in [{:g} - {:g}]", lo, hi));
}

/// CLI11's own words, said as sandflow says its errors: with the command, what was meant, and
/// where to read what it takes. CLI11 words an option given twice as a count of values
/// ("--grains: At Most 1 required but received 2"), an option without its value as "1 required
/// INT missing", a missing argument by its variable ("dir is required"), and lists words it did
/// not expect last first ("not expected: dem --mode" for `compare --mode dem`).
std::string failure_message(const CLI::App* app, const CLI::Error& e) {
  std::string what = e.what();
  std::vector<std::string> names;
  if (app)
    for (const CLI::App* c : app->get_subcommands([](const CLI::App*) { return true; }))
      names.push_back(c->get_name());
  const CLI::App* command =
      app && !app->get_subcommands().empty() ? app->get_subcommands().front() : nullptr;
  if (!command) {
    const bool word = app && !app->remaining().empty();
    const std::string given = word ? app->remaining().front() : "";
    return fmt::format("{}; its commands: {}\nRun sandflow --help for what each does.\n",
                       !word ? std::string("sandflow: give a command")
                       : given.rfind("-", 0) == 0
                           ? fmt::format("sandflow takes no option {} before its command", given)
                           : fmt::format("{}: sandflow has no such command", given),
                       fmt::join(names, ", "));
  }
  const std::string name = "sandflow " + command->get_name();
  const std::string repeated = ": At Most 1 required but received ";
  const std::string needs_value = ": 1 required ";
  if (const std::size_t at = what.find(repeated); at != std::string::npos) {
    what = fmt::format("{} is given {} times: give it once", what.substr(0, at),
                       what.substr(at + repeated.size()));
  } else if (const std::size_t v = what.find(needs_value);
             v != std::string::npos && what.size() > 8 &&
             what.compare(what.size() - 8, 8, " missing") == 0) {
    what =
        fmt::format("{} needs a value ({})", what.substr(0, v),
                    what.substr(v + needs_value.size(), what.size() - 8 - v - needs_value.size()));
  } else if (dynamic_cast<const CLI::RequiredError*>(&e)) {
    for (const CLI::Option* o : command->get_options())
      if (o->get_positional() && what == o->get_name() + " is required") {
        std::string var = o->get_name();
        for (char& c : var) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
        what = fmt::format("`{}` needs its {}: {}", name, var, o->get_description());
      }
  } else if (dynamic_cast<const CLI::ExtrasError*>(&e)) {
    const std::vector<std::string> extra = command->remaining();
    if (extra.empty() && !app->remaining().empty())  // (before the command)
      what = fmt::format(
          "sandflow takes no option {} before its command; options go after it, "
          "as `{} --help` lists them",
          app->remaining().front(), name);
    else if (!extra.empty())
      what = fmt::format(
          "`{}` takes no {} {}{}", name, extra.front().rfind("-", 0) == 0 ? "option" : "argument",
          extra.front(),
          extra.size() > 1 ? fmt::format(" (given: {})", fmt::join(extra, " ")) : std::string());
  }
  return fmt::format("{}\nRun {} --help for what it takes.\n", what, name);
}

// frame counts and numbers: 1 to the most frames a run may have (sim/world.hpp)
const CLI::Validator kFrameRange = whole(1, static_cast<std::int64_t>(kMaxFrames));

// an output folder given as '' would fall back to the default one, unasked
const CLI::Validator kNonEmptyPath(
    [](const std::string& s) { return s.empty() ? std::string("an empty folder name") : ""; }, "");

/// The options of the commands that run a scene: the file, where to write, and how to scale it.
void add_scene_options(CLI::App* cmd, RunOptions& o, const std::string& out_help,
                       const std::string& set_help) {
  cmd->add_option("scene", o.scene, "scene file (TOML)")->required();
  cmd->add_option("--out", o.out, out_help)->check(kNonEmptyPath);
  cmd->add_option("--frames", o.frames, "number of frames (default: from the scene)")
      ->check(kFrameRange);
  cmd->add_option("--grains", o.grains, "scale the emitters to N grains in total")
      ->check(whole(1, 2000000000));
  cmd->add_option("--threads", o.threads,
                  "OpenMP threads (default: OMP_NUM_THREADS when set, else all cores)")
      ->check(whole(1, kMaxThreads));
  cmd->add_option("--set", o.sets, set_help);
  cmd->add_option("--export", o.exports,
                  "files written each frame, comma-separated: ply, vtk, geo, geo_gz, pov, csv, "
                  "height, height_obj, vdb, or none (default: the scene's output.export, else "
                  "ply, and height in surface mode; the files: docs/scenes.md, Exports)");
  cmd->add_option("--up-axis", o.up_axis,
                  "up axis of exported PLY, VTK, geo, CSV, OBJ and VDB files: z (the scene's) or y "
                  "(the scene's z becomes y); POV-Ray files are unaffected (default: the scene's "
                  "output.up_axis, else z)")
      ->check(CLI::IsMember({"z", "y"}));
}

// The OpenMP runtimes read OMP_NUM_THREADS as the program loads, before main: LLVM's (a clang
// build) stops the program on an empty one. One that is not a count leaves the environment before
// any library starts (an entry of .preinit_array runs first), kept for main's warning. (Plain
// arrays, and the environment from the loader's `env`: no constructor has run yet, not even
// the C library's, so getenv and std::string cannot be used.)
char bad_omp_num_threads[64];
bool bad_omp_num_threads_cut = false;

void drop_bad_omp_num_threads(int, char**, char** env) {
  constexpr char kName[] = "OMP_NUM_THREADS=";
  for (char** e = env; e && *e; ++e) {
    if (std::strncmp(*e, kName, sizeof kName - 1) != 0) continue;
    const char* text = *e + sizeof kName - 1;
    if (omp_thread_count(text)) return;
    const std::size_t n = std::strlen(text), kept = std::min(n, sizeof bad_omp_num_threads - 1);
    std::memcpy(bad_omp_num_threads, text, kept);
    bad_omp_num_threads[kept] = '\0';
    bad_omp_num_threads_cut = kept < n;
    for (char** f = e; *f; ++f) *f = *(f + 1);  // (the rest of the environment moves up one)
    return;
  }
}

[[gnu::used, gnu::section(".preinit_array")]] void (*const drop_bad_omp_num_threads_early)(
    int, char**, char**) = &drop_bad_omp_num_threads;

}  // namespace

int main(int argc, char** argv) {
  open_missing_standard_streams();
  // A file past the size limit (ulimit -f) then fails to write with EFBIG, reported as an
  // OutputError like a full disk, instead of the signal killing the process mid-write; a log
  // whose reader went away (`| head`) loses its lines, not the run.
  std::signal(SIGXFSZ, SIG_IGN);
  std::signal(SIGPIPE, SIG_IGN);
  // libgomp takes OMP_NUM_THREADS as it stands for every parallel region until told otherwise,
  // and one it cannot start crashes it (100,000 on this machine: a segmentation fault while the
  // World was built): every region gets the count sandflow takes, at most kMaxThreads. (One that
  // is not a count has left the environment already: drop_bad_omp_num_threads.)
  if (bad_omp_num_threads[0] != '\0')  // (an empty one is dropped without a word, as before)
    print_to_stderr(
        "warning: OMP_NUM_THREADS={}{} is not a count of threads from 1 to {}: ignored, "
        "{} (one per core) unless --threads or simulation.threads says\n",
        bad_omp_num_threads, bad_omp_num_threads_cut ? "..." : "", kMaxThreads,
        omp_get_num_procs());
  omp_set_num_threads(default_thread_count());
  if (const std::vector<long> cpus = absent_affinity_cpus(); !cpus.empty())
    print_to_stderr(
        "warning: GOMP_CPU_AFFINITY={} names {} this process cannot run on ({}{}): OpenMP "
        "stops the program (\"Thread creation failed\") if it binds a thread to one; unset it or "
        "name only CPUs of {}\n",
        std::getenv("GOMP_CPU_AFFINITY"), cpus.size() == 1 ? "a CPU" : "CPUs",
        fmt::join(cpus.begin(), cpus.begin() + std::min<std::size_t>(cpus.size(), 8), ", "),
        cpus.size() > 8 ? ", ..." : "", usable_cpus());
  // a region gets the threads the job says it runs on (OMP_DYNAMIC=true let libgomp give fewer)
  omp_set_dynamic(0);
  CLI::App app{
      "sandflow: sand animated as a surface flow (Zhu & Yang 2010), with plain DEM beside it"};
  app.require_subcommand(1);
  app.set_version_flag("--version", SANDFLOW_VERSION);
  app.failure_message(failure_message);

  RunOptions ro;
  auto* run = app.add_subcommand("run", "simulate a scene and write its frames and statistics");
  add_scene_options(run, ro, "output folder (default out/SCENE-MODE)",
                    "override a scene key: --set material.friction=0.5");
  run->add_option("--mode", ro.mode, "surface (height field + DEM) or dem (plain DEM)")
      ->check(CLI::IsMember({"surface", "dem"}));
  run->add_flag("--check", ro.check, "validate the scene and print its plan, then stop");
  run->add_flag("--force", ro.force, "replace the run in a non-empty output folder");
  run->add_flag("--profile", ro.profile, "print the seconds spent in each stage");
  run->get_option("scene")->required(false);  // (not with --resume)
  run->add_option("--resume", ro.resume,
                  "continue the run in DIR from its last checkpoint, exactly as it was started "
                  "(no scene; --threads and --checkpoint-every may change, and --frames N runs "
                  "it on to frame N, a finished run too)");
  run->add_option("--checkpoint-every", ro.checkpoint_every,
                  "write DIR/checkpoint.bin every N frames and after the last (default 30; 0: "
                  "only on SIGINT/SIGTERM)")
      ->check(whole(0, static_cast<std::int64_t>(kMaxFrames)));
  run->footer(
      "A run writes DIR/run.json (how it was started) and, every N frames, DIR/checkpoint.bin.\n"
      "SIGINT (Ctrl-C) or SIGTERM finishes the current frame, writes a checkpoint and exits;\n"
      "a second one stops at once. `sandflow run --resume DIR` continues a run that was\n"
      "interrupted, killed or stopped by an error, and ends with the same state as a run that\n"
      "never stopped (docs/checkpoints.md); `--resume DIR --frames N` runs it on to frame N\n"
      "(more settling after a finished run), as if it had been started with --frames N.\n"
      "Exit status: 0 done, 2 bad input, 3 the simulation blew up (the message names the step,\n"
      "the grain and the command that reproduces it), 4 an output could not be written,\n"
      "130 interrupted by SIGINT, 143 by SIGTERM.");

  RunOptions cao;
  int calibration_trials = 3;
  bool calibrate_again = false;
  auto* calibrate = app.add_subcommand(
      "calibrate",
      "measure the angles of repose (theta0, theta_max) of a scene's material in plain DEM");
  calibrate->add_option("scene", cao.scene, "scene file (TOML)")->required();
  calibrate->add_option("--set", cao.sets, "override a scene key: --set material.friction=0.4");
  calibrate
      ->add_option("--threads", cao.threads,
                   "OpenMP threads (default: OMP_NUM_THREADS when set, else all cores)")
      ->check(whole(1, kMaxThreads));
  calibrate->add_option("--trials", calibration_trials, "seeds measured (default 3)")
      ->check(whole(1, 100));
  calibrate->add_flag("--again", calibrate_again, "measure even when the cache holds the result");
  RigSettings rig;
  calibrate
      ->add_option("--base", rig.base_diameters,
                   "radius of the rig's base in grain diameters (default 10; what surface "
                   "runs use. A smaller base reads the angles low, a larger one costs more)")
      ->check(real_in(4.0, 40.0));
  calibrate
      ->add_option("--tilt-rate", rig.tilt_rate,
                   "how fast gravity tilts, deg/s (default 2: what surface runs use)")
      ->check(real_in(0.1, 30.0));
  calibrate->footer(
      "A heap is poured onto a rough disk 10 grain diameters in radius until it overflows; its\n"
      "flank gives theta0 (where a flow stops). Gravity is then tilted slowly until the heap\n"
      "fails: theta_max = theta0 + the tilt. The result is cached by a hash of the material\n"
      "(calibration_cache_dir: $SANDFLOW_CACHE_DIR, $XDG_CACHE_HOME/sandflow or\n"
      "~/.cache/sandflow), and surface mode uses it where the scene sets no angle.");

  MeasureOptions mo;
  auto* measure = app.add_subcommand(
      "measure",
      "print the angle of repose of a run's final state, or its crater in a scene with a bed");
  measure->add_option("dir", mo.dir, "run folder")->required();
  auto* measure_frame =
      measure
          ->add_option("--frame", mo.frame,
                       "measure frames/NNNN.ply instead of the final state (a surface run's with "
                       "its static top, heightfield/h_NNNN.png, for the sand asleep under them)")
          ->check(whole(1, 10000000));
  measure
      ->add_option("--frames", mo.frames,
                   "measure a series of frames, one line each and their mean: A:B (inclusive), "
                   "A:B:K (every K-th from A), A:, :B or all")
      ->excludes(measure_frame);
  measure
      ->add_option("--slower-than", mo.slower_than,
                   "leave out the grains as fast as this or faster [m/s]: a stream still "
                   "falling onto the heap, a flow")
      ->check(real_in(1e-9, 1e9));

  RunOptions co;
  auto* compare = app.add_subcommand(
      "compare", "run a scene in both modes and compare speed, grains simulated and the heaps");
  add_scene_options(compare, co, "output folder (default out/SCENE-compare)",
                    "override a scene key in both runs");
  compare->add_flag("--force", co.force, "replace a comparison in a non-empty output folder");
  compare->get_option("scene")->required(false);  // (not with --resume)
  compare->add_option("--resume", co.resume,
                      "go on with the comparison in DIR, stopped, killed or finished, from its "
                      "runs' last checkpoints, as it was started (no scene; --threads may change, "
                      "--frames N runs all its runs on to frame N, --seeds K adds seeds up to K "
                      "and --equal-stiffness adds that run)");
  CompareOptions cmp;
  compare
      ->add_option("--seeds", cmp.seeds,
                   "runs per mode, with seeds S, S+1, ... (S: the scene's simulation.seed); the "
                   "spread of the plain-DEM runs is the noise floor of the comparison (default 3)")
      ->check(whole(1, kMaxSeeds));
  compare->add_option(
      "--dem-from", cmp.dem_from,
      "an earlier comparison whose plain-DEM runs stand for this one's: each run there started "
      "as this one's would be (the same scene text, --set, --grains, --frames, --export, "
      "--up-axis) is copied into DIR and read back, not made again; the others are made. For a "
      "changed surface flow against plain DEM that did not change; the speed-ups pair wall times "
      "measured at different times");
  compare->add_flag("--equal-stiffness", cmp.equal_stiffness,
                    "also run plain DEM at the surface run's k_n and dt (DIR/dem-equal-stiffness): "
                    "the speed-up without the softer springs");
  compare->footer(
      "For each seed, runs the scene in surface mode, then in plain DEM: DIR/surface and DIR/dem\n"
      "for the first seed, DIR/seed-S/surface and DIR/seed-S/dem for the others; each with\n"
      "run.json and a checkpoint every 30 frames as `sandflow run` writes them. SIGINT or\n"
      "SIGTERM finishes the frame, writes a checkpoint and exits (130/143), and\n"
      "`sandflow compare --resume DIR` goes on. Wall times are summed over the frames of each run,\n"
      "so a resumed comparison reports the time of every frame once. DIR/compare.json holds the\n"
      "means over the seeds, the spread of the plain-DEM seeds and the distances between the\n"
      "final sand surfaces (docs/physics.md, Sameness).");

  Table1Options to;
  auto* table1 = app.add_subcommand(
      "table1",
      "the paper's Table 1: run its scenes in both modes (as compare does) and tabulate them");
  table1->add_option("--scale", to.scale,
                     "grains per scene: round(F x the paper's count), F in (0, 100] (default 1)");
  table1->add_option("--frames", to.frames, "number of frames per run (default: each scene's)")
      ->check(kFrameRange);
  table1->add_option("--out", to.out, "output folder (default out/table1)")->check(kNonEmptyPath);
  table1
      ->add_option("--scenes", to.scenes,
                   "comma-separated subset of floor,terrain,bowl,dragon,armadillo (default: all "
                   "five)")
      ->delimiter(',');
  table1->add_option("--scene-dir", to.scene_dir,
                     "folder of the scene files NAME.toml (default: ./scenes if there is one, "
                     "else the source tree's scenes/)");
  table1
      ->add_option("--threads", to.threads,
                   "OpenMP threads (default: OMP_NUM_THREADS when set, else all cores)")
      ->check(whole(1, kMaxThreads));
  table1->add_flag("--force", to.force,
                   "write into a non-empty output folder, replacing its table and the folders of "
                   "the scenes run");
  table1
      ->add_option("--seeds", to.seeds,
                   "runs per mode of each scene, as compare --seeds (default 1)")
      ->check(whole(1, kMaxSeeds));
  table1->add_flag("--resume", to.resume,
                   "go on with the table in a non-empty output folder, given the same options: "
                   "finished runs are read back from their last checkpoints, stopped ones go on "
                   "from theirs");
  table1->footer(
      "Writes DIR/table1.csv (one row per scene that ran), DIR/table1.md (every scene, the\n"
      "command, date, cores and threads, and the paper's figures) and DIR/SCENE/ (compare.json,\n"
      "dem/, surface/), rewriting both tables after each scene. A scene whose file SCENE.toml is\n"
      "missing is skipped: listed as missing, and the others still run. A scene that fails is\n"
      "listed as failed with its error, and the others still run.\n"
      "Exit status: 0 when every scene whose file was found ran; otherwise that of the first\n"
      "scene that failed (2 bad input, 3 blow-up, 4 output, 1 other); 2 when no scene file was\n"
      "found at all (the tables list every scene as missing) or an option is bad (then nothing\n"
      "is written).");

  RenderOptions rdo;
  auto* render = app.add_subcommand(
      "render", "render a run's frames with POV-Ray to DIR/render/NNNN.png, and a movie of them");
  render->add_option("dir", rdo.dir, "run folder, or a comparison's folder (surface/ and dem/)")
      ->required();
  render->add_option("--width", rdo.width, "image width [pixels] (default 1280)")
      ->check(whole(16, 16384));
  render->add_option("--height", rdo.height, "image height [pixels] (default 720)")
      ->check(whole(16, 16384));
  auto* frame_opt =
      render->add_option("--frame", rdo.frame, "one frame (default: the last; all with --movie)")
          ->check(kFrameRange);
  render
      ->add_option("--frames", rdo.frames,
                   "frames to render, from 1: N, A:B (inclusive), A:, :B, or all (default: the "
                   "last; all with --movie)")
      ->excludes(frame_opt)
      ->check(CLI::Validator(
          [](std::string& v) {
            return v.empty() ? std::string("expected N, A:B, A:, :B or all, got nothing")
                             : std::string();
          },
          "FRAMES"));
  render
      ->add_option("--quality", rdo.quality,
                   "final (antialiased, soft light; the default) or draft (fast previews)")
      ->check(CLI::IsMember({"draft", "final"}));
  render
      ->add_option("--jobs", rdo.jobs,
                   "frames rendered at once (default: one per core, or OMP_NUM_THREADS)")
      ->check(whole(1, kMaxThreads));
  render->add_flag("--movie", rdo.movie,
                   "also encode the frames to DIR/render/movie.mp4 (H.264) with ffmpeg");
  render->add_flag("--keep-pov", rdo.keep_pov,
                   "keep each picture's POV-Ray scene (NNNN.pov) and the logs of POV-Ray "
                   "(NNNN.png.log) and ffmpeg (movie.mp4.log)");
  render->add_flag("--again", rdo.again,
                   "make every picture anew (default: a picture made earlier from the same scene, "
                   "size and quality is kept)");
  render->add_option("--scene", rdo.scene,
                     "scene file for the geometry and [camera] (default: the one the run ran, "
                     "recorded in its run.json with its --set)");
  render->add_option("--set", rdo.sets,
                     "change the look: --set camera.fov=30, --set geometry.1.render=glass "
                     "(camera.KEY and geometry.N.render only)");
  render->footer(
      "Every frame of a run gets the same camera and light: the scene file's [camera], or an\n"
      "automatic one framing the geometry and the grains of all the run's frames. A comparison\n"
      "folder renders both runs with one camera, into surface/render and dem/render (--movie\n"
      "adds DIR/render/side_by_side.mp4: surface flow left, plain DEM right). Frames\n"
      "render in parallel (--jobs); each povray gets cores/jobs threads. A frame that fails is\n"
      "named with the end of POV-Ray's log, and the others are still rendered. A picture made\n"
      "earlier from the same scene, size and quality is kept (DIR/render/pictures.json), so an\n"
      "interrupted render goes on where it stopped. The movie runs\n"
      "at the run's fps; without ffmpeg the frames are rendered and the exit status is 2.\n"
      "Prints the path of each picture (and movie) on stdout.\n"
      "Exit status: 0 done, 2 bad option or folder, povray or ffmpeg missing, 4 a frame failed\n"
      "or an output could not be written.\n");

  ReportOptions rpo;
  auto* report = app.add_subcommand(
      "report", "write DIR/report.html: summary, plots, contact sheet (both modes for compare)");
  report->add_option("dir", rpo.dir, "run, compare or table1 folder")->required();
  report
      ->add_option("--contact-sheet", rpo.contact_sheet,
                   "frames on the contact sheet, evenly spaced, ending with the last (default "
                   "6; 0: none)")
      ->check(whole(0, 100));
  bool no_render = false;
  report->add_flag("--no-render", no_render,
                   "do not run POV-Ray: show only the frames already in DIR/render/");
  report->footer(
      "Writes DIR/report.html, one self-contained page (inline CSS and SVG plots, pictures\n"
      "embedded; no network, no JavaScript). A run folder: the summary, plots per frame (grains\n"
      "simulated, interface and static; seconds per frame; dt; transitions) and a contact sheet.\n"
      "A compare folder: both modes on shared axes, the speed-up and the two final frames side by\n"
      "side (and each run's own page). A table1 folder: each scene's page and an index.\n"
      "Frames without a picture in DIR/render/ are rendered with POV-Ray: 480x270 for the\n"
      "contact sheet; the final frames of a comparison at 640x360, or at the size of the one\n"
      "already rendered. `run` and `compare` write the page without pictures.");

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? 0 : 2;
  }
  const int status = [&] {
    try {
      if (*run) return run_command(ro);
      if (*compare) {
        cmp.seeds_given = compare->count("--seeds") > 0;
        cmp.equal_stiffness_given = compare->count("--equal-stiffness") > 0;
        return compare_command(co, cmp);
      }
      if (*table1) return table1_command(to, command_line(argc, argv));
      if (*measure) return measure_command(mo);
      if (*calibrate) return calibrate_command(cao, calibration_trials, calibrate_again, rig);
      if (*render) return render_command(rdo);
      if (*report) {
        rpo.render = !no_render;
        return report_command(rpo);
      }
    } catch (const InputError& e) {
      print_to_stderr("error: {}\n", e.what());
      return 2;
    } catch (const SimulationError& e) {
      print_to_stderr("\nsimulation stopped: {}\n", e.what());
      return 3;
    } catch (const OutputError& e) {
      print_to_stderr("\noutput error: {}\n", e.what());
      return 4;
    } catch (const std::exception& e) {
      print_to_stderr("\nerror: {}\n", e.what());
      return 1;
    }
    return 0;
  }();
  // stdout is buffered in a pipe or a file: what did not reach it is known only now (a full disk,
  // a reader gone), and a command whose summary is lost has not done what it was asked
  const bool flushed = std::fflush(stdout) == 0;
  const int flush_error = errno;
  if (!flushed || std::ferror(stdout) != 0) {
    print_to_stderr(
        "\noutput error: the standard output could not be written{}: the command's printed "
        "summary is lost{}\n",
        flushed ? "" : fmt::format(" ({})", std::strerror(flush_error)),
        *run || *compare || *table1 ? "; its files are written" : "");
    return status != 0 ? status : 4;
  }
  return status;
}
