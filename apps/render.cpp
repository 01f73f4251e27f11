// `sandflow render`: a run's frames drawn by POV-Ray, several at once, and a movie of them.
//
// The camera and the lights of an animation belong to the run, not to the frame: they are placed
// around the bounds of the geometry and of the grains of every frame of the run, computed once
// before the first picture, so that it does not jitter and a frame rendered later matches the
// others. A still (one frame of each run) is framed on what it shows. In surface mode the static
// layer, whose grains the frames do not hold, is drawn as a surface from the run's height images. A
// comparison folder (DIR/surface and DIR/dem) is framed over both runs, so their pictures can be
// put side by side. A [camera] table in the scene file replaces the automatic camera.

#include <algorithm>
#include <atomic>
#include <cctype>
#include <charconv>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "commands.hpp"
#include "console.hpp"
#include "core/atomic_file.hpp"
#include "core/counted.hpp"
#include "core/error.hpp"
#include "core/hash.hpp"
#include "core/memory.hpp"
#include "core/memory_gate.hpp"
#include "core/process.hpp"
#include "core/read_file.hpp"
#include "core/threads.hpp"
#include "frames_spec.hpp"
#include "geometry/mesh.hpp"
#include "geometry/shapes.hpp"
#include "io/folder_lock.hpp"
#include "io/height_export.hpp"
#include "io/media_check.hpp"
#include "io/ply.hpp"
#include "io/png_gray.hpp"
#include "io/pov_writer.hpp"
#include "io/run_output.hpp"
#include "progress.hpp"
#include "scene/scene_loader.hpp"
#include "stop_signals.hpp"

namespace fs = std::filesystem;

namespace sandflow {
namespace {

// ---- Which frames -------------------------------------------------------------------------------

/// The frame numbers NNNN of DIR/frames/NNNN.ply, ascending.
std::vector<int> frame_numbers(const std::string& run) {
  std::vector<int> out;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(fs::path(run) / "frames", ec)) {
    if (e.path().extension() != ".ply") continue;
    const std::string stem = e.path().stem().string();
    int v = 0;
    const auto res = std::from_chars(stem.data(), stem.data() + stem.size(), v);
    if (res.ec == std::errc() && res.ptr == stem.data() + stem.size() && v > 0) out.push_back(v);
  }
  std::sort(out.begin(), out.end());
  return out;
}

/// A run folder, or the two runs of a comparison folder (surface/ and dem/).
std::vector<std::string> run_folders(const std::string& dir) {
  std::error_code ec;
  if (const std::string problem = folder_problem(dir); !problem.empty())
    throw InputError(fmt::format("{}: {}", dir, problem));
  if (fs::is_directory(fs::path(dir) / "frames", ec)) return {dir};
  std::vector<std::string> runs;
  for (const char* mode : {"surface", "dem"})
    if (fs::is_directory(fs::path(dir) / mode / "frames", ec))
      runs.push_back((fs::path(dir) / mode).string());
  if (runs.empty() && fs::exists(fs::path(dir) / "table1.csv", ec)) {
    std::vector<std::string> scenes;
    for (const auto& e : fs::directory_iterator(dir, ec))
      if (fs::is_directory(e.path() / "surface" / "frames", ec))
        scenes.push_back(e.path().string());
    std::sort(scenes.begin(), scenes.end());
    std::string list;
    for (const std::string& sc : scenes) list += (list.empty() ? "" : ", ") + sc;
    throw InputError(
        fmt::format("{}: a table1 folder: render each scene's comparison on its own ({})", dir,
                    list.empty() ? std::string("none has frames yet") : list));
  }
  if (runs.empty())
    throw InputError(fmt::format(
        "{}: no frames/NNNN.ply in this folder: expected the folder of a run (sandflow run) or of "
        "a comparison (sandflow compare, with surface/ and dem/)",
        dir));
  if (runs.size() == 1)
    print_to_stderr(
        "warning: {}: a comparison with frames in {} only: it alone is rendered, and no "
        "side-by-side movie is made\n",
        dir, runs.front());
  return runs;
}

// ---- The scene: geometry, camera, fps -------------------------------------------------------

struct RenderScene {
  std::vector<GeometryConfig> geometry;
  /// by geometry entry, nothing for other solids: the solids' own meshes (which a move of the
  /// RenderScene keeps where they are)
  std::vector<const TriangleMesh*> meshes;
  CameraConfig camera;
  std::optional<double> fps;  ///< [1/s]: the run's, else the scene file's
  std::optional<Geometry> solids;  ///< what the grains met: where the static layer has sand
  Real diameter = 0;               ///< the grains' mean diameter [m]
};

nlohmann::json read_summary(const std::string& run) {
  const std::optional<std::string> text =
      read_file_if_present((fs::path(run) / "summary.json").string(), "summary", kAnyFileSize);
  if (!text) return nlohmann::json();
  auto j = nlohmann::json::parse(*text, nullptr, false);
  return j.is_discarded() || !j.is_object() ? nlohmann::json() : j;
}

/// camera.KEY, geometry.N.render or geometry[N].render.
bool is_look_key(const std::string& key) {
  const auto word = [](std::string_view w) {
    return !w.empty() && std::all_of(w.begin(), w.end(), [](char c) {
      return std::isalnum(static_cast<unsigned char>(c)) || c == '_';
    });
  };
  const auto digits = [](std::string_view w) {
    return !w.empty() &&
           std::all_of(w.begin(), w.end(), [](char c) { return c >= '0' && c <= '9'; });
  };
  const std::string_view k = key;
  if (k.substr(0, 7) == "camera.") return word(k.substr(7));
  constexpr std::string_view kGeometry = "geometry", kRender = ".render";
  if (k.size() < kGeometry.size() + kRender.size() + 2 ||
      k.substr(0, kGeometry.size()) != kGeometry || k.substr(k.size() - kRender.size()) != kRender)
    return false;
  const std::string_view index =
      k.substr(kGeometry.size(), k.size() - kGeometry.size() - kRender.size());
  if (index.front() == '.') return digits(index.substr(1));
  return index.front() == '[' && index.back() == ']' && digits(index.substr(1, index.size() - 2));
}

/// The --set overrides of render: only what changes the picture, not what the grains met (the
/// camera and how each geometry entry is drawn).
std::vector<Override> look_overrides(const std::vector<std::string>& sets) {
  std::vector<Override> out;
  for (const std::string& s : sets) {
    Override o = parse_override(s);
    if (!is_look_key(o.key))
      throw InputError(fmt::format(
          "--set {}: render takes only camera.KEY and geometry.N.render (how the picture looks, "
          "not what the grains met)",
          s));
    out.push_back(std::move(o));
  }
  return out;
}

/// The scene the run ran (its run.json: the scene text with its --set, then `sets`), or nothing
/// when the run has no run.json. Throws InputError when its run.json cannot be read.
std::optional<SceneConfig> scene_the_run_ran(const std::string& run,
                                             const std::vector<std::string>& sets) {
  std::error_code ec;
  if (!fs::exists(fs::path(run) / "run.json", ec)) return std::nullopt;
  nlohmann::json record;
  std::string text;
  RunOptions r = read_run_record(run, record, text);
  r.sets.insert(r.sets.end(), sets.begin(), sets.end());
  return recorded_scene(r, text, record);
}

/// Whether two [[geometry]] tables make the same solid for the grains: everything but its name
/// and how it is drawn, and a heightmap's samples rather than the path of the PNG they came from.
/// `by_digest`: the run recorded its meshes' digests, which say whether a mesh file is
/// the one it ran (warn_if_meshes_differ), whatever its name.
bool same_solid(GeometryConfig a, GeometryConfig b, bool by_digest) {
  a.name = b.name;
  a.render = b.render;
  a.file = b.file;
  if (by_digest) a.mesh_file = b.mesh_file;
  return a == b;
}

/// The digests of the meshes the run's grains met, by [[geometry]] table: its summary.json's
/// mesh_digests, else its run.json's (a run not finished); nothing for a run of a sandflow before
/// them, or one whose run.json cannot be read.
std::map<int, std::string> run_mesh_digests(const nlohmann::json& summary, const std::string& run) {
  nlohmann::json digests = summary.is_object() && summary.contains("mesh_digests")
                               ? summary["mesh_digests"]
                               : nlohmann::json();
  if (!digests.is_array()) {
    std::error_code ec;
    if (!fs::exists(fs::path(run) / "run.json", ec)) return {};
    try {
      nlohmann::json record;
      std::string text;
      read_run_record(run, record, text);
      if (record.contains("mesh_digests")) digests = record["mesh_digests"];
    } catch (const InputError&) {
      return {};
    }
  }
  std::map<int, std::string> out;
  if (!digests.is_array()) return out;
  for (const nlohmann::json& d : digests)
    if (d.is_object() && d.contains("geometry") && d["geometry"].is_number_integer() &&
        d.contains("digest") && d["digest"].is_string())
      out[d["geometry"].get<int>()] = d["digest"].get<std::string>();
  return out;
}

/// A mesh drawn that is not the one the grains met: its file edited since the run, or --scene
/// naming another.
void warn_if_meshes_differ(const Geometry& solids, const std::vector<GeometryConfig>& geometry,
                           const std::map<int, std::string>& ran, const std::string& run) {
  for (const MeshObstacle& m : solids.meshes()) {
    const auto it = ran.find(m.source);
    if (it == ran.end() || it->second == fmt::format("{:016x}", mesh_digest(m.mesh))) continue;
    print_to_stderr(
        "warning: [[geometry]] table {} ('{}'): its mesh {} is not the one {} ran "
        "(its record of the meshes it ran): its file was changed since, or another was "
        "named; the geometry drawn is not what its grains met\n",
        m.source, m.name, geometry[static_cast<std::size_t>(m.source)].mesh_file, run);
  }
}

/// A --scene other than the one the run ran draws geometry the grains never met: say so when its
/// name differs from the run's record (run.json), or any solid (one moved, resized, another
/// type, one more or fewer). A run.json that cannot be read is not an error here: --scene is how
/// such a run is drawn.
void warn_if_not_the_runs_scene(const SceneConfig& given, const std::string& run,
                                bool meshes_by_digest) {
  std::optional<SceneConfig> ran;
  try {
    ran = scene_the_run_ran(run, {});
  } catch (const InputError&) {
    return;
  }
  if (!ran) return;
  if (ran->name != given.name || ran->geometry.size() != given.geometry.size()) {
    print_to_stderr(
        "warning: --scene {} is the scene '{}' with {}; {} ran '{}' with {} (its run.json): "
        "the geometry drawn is not what its grains met\n",
        given.path, given.name,
        counted(static_cast<std::int64_t>(given.geometry.size()), "[[geometry]] table"), run,
        ran->name, counted(static_cast<std::int64_t>(ran->geometry.size()), "[[geometry]] table"));
    return;
  }
  for (std::size_t k = 0; k < given.geometry.size(); ++k)
    if (!same_solid(given.geometry[k], ran->geometry[k], meshes_by_digest)) {
      print_to_stderr(
          "warning: --scene {}: [[geometry]] table {} ('{}') is not the solid {} ran "
          "(its run.json): the geometry drawn is not what its grains met\n",
          given.path, k, given.geometry[k].name, run);
      return;
    }
}

/// The scene from --scene, else the one the first run ran (its run.json: the scene text with its
/// --set, so a moved scene file or a --set of the geometry draws what the grains met), else the
/// scene file its summary.json names. Without any only the grains are drawn.
RenderScene load_render_scene(const std::string& scene_option, const std::vector<std::string>& sets,
                              const std::vector<Override>& overrides, const std::string& run) {
  RenderScene rs;
  const nlohmann::json summary = read_summary(run);
  if (summary.contains("fps") && summary["fps"].is_number()) rs.fps = summary["fps"].get<double>();
  std::string file = scene_option;
  const std::string summary_path = (fs::path(run) / "summary.json").string();
  // (`sets` change only the look: camera keys)
  const std::optional<SceneConfig> recorded =
      file.empty() ? scene_the_run_ran(run, sets) : std::nullopt;
  std::error_code ec;
  if (file.empty() && !recorded) {
    if (summary.contains("scene_file") && summary["scene_file"].is_string()) {
      file = summary["scene_file"].get<std::string>();
      if (!fs::is_regular_file(file, ec))
        throw InputError(fmt::format(
            "{}: the run's scene file {} cannot be opened (moved, or the run was started from "
            "another folder): pass it with --scene FILE",
            summary_path, file));
    } else {
      if (!overrides.empty())
        throw InputError(
            fmt::format("--set {}={}: {} is missing or names no scene file: pass "
                        "--scene FILE",
                        overrides.front().key, overrides.front().value, summary_path));
      print_to_stderr(
          "warning: {} is missing or names no scene file (an unfinished run?): drawing "
          "the grains without the geometry; pass --scene FILE to draw it\n",
          summary_path);
      return rs;
    }
  }
  const SceneConfig scene = recorded ? *recorded : load_scene(file, overrides);
  const std::map<int, std::string> mesh_digests = run_mesh_digests(summary, run);
  if (!recorded) warn_if_not_the_runs_scene(scene, run, !mesh_digests.empty());
  rs.geometry = scene.geometry;
  rs.solids = Geometry::from_config(scene.geometry, scene.material, scene.path);
  warn_if_meshes_differ(*rs.solids, scene.geometry, mesh_digests, run);
  rs.diameter = scene.material.diameter;
  rs.camera = scene.camera;
  if (!rs.fps) rs.fps = scene.output.fps;
  // the meshes drawn are those the solids placed (placing the dragon again took 1.7 s)
  rs.meshes.assign(scene.geometry.size(), nullptr);
  for (const MeshObstacle& m : rs.solids->meshes())
    if (scene.geometry[static_cast<std::size_t>(m.source)].render != RenderStyle::Hidden)
      rs.meshes[static_cast<std::size_t>(m.source)] = &m.mesh;
  for (const std::string& w : rs.solids->warnings()) print_to_stderr("warning: {}\n", w);
  return rs;
}

// ---- The static layer: the height field's h, from the run's heightfield/ files --------------

/// Frame `frame`'s static layer (heightfield/h_NNNN.png): a column holds sand where h stands a
/// quarter of a grain above the solid top under it. Empty when the run did not export it.
SandSurface static_layer(const std::string& run, int frame, const HeightImages& hi,
                         const RenderScene& scene) {
  SandSurface sf;
  if (!scene.solids) return sf;
  const std::vector<Real> h = read_height_frame(run, "h", frame, hi);
  if (h.empty()) return sf;
  sf.origin_x = hi.origin_x;
  sf.origin_y = hi.origin_y;
  sf.cell = hi.cell;
  sf.nx = hi.nx;
  sf.ny = hi.ny;
  sf.grain_diameter = scene.diameter;
  sf.z = h;
  sf.sand = static_sand_columns(h, hi, *scene.solids, scene.diameter);
  return sf;
}

// ---- Running tasks on several threads ----------------------------------------------------------

/// Calls task(i) for i in [0, n) on `jobs` threads; `task` must not throw.
void parallel_tasks(int n, int jobs, const std::function<void(int)>& task) {
  std::atomic<int> next{0};
  const auto worker = [&] {
    for (int i = next++; i < n; i = next++) task(i);
  };
  std::vector<std::thread> pool;
  for (int k = 1; k < std::min(jobs, n); ++k) pool.emplace_back(worker);
  worker();
  for (std::thread& t : pool) t.join();
}

/// Bounds of the grains (grain_core_bounds) of the frames `numbers` of each of `runs` (every frame
/// of an animation, not only those rendered: the camera is the run's), read `jobs` at a time.
ViewBounds run_bounds(const std::vector<std::string>& runs,
                      const std::vector<std::vector<int>>& numbers, int jobs) {
  std::vector<std::string> files;
  for (std::size_t k = 0; k < runs.size(); ++k)
    for (int f : numbers[k]) files.push_back(frame_path(runs[k], f));
  if (files.size() > 30)  // seconds for a large run: say what the wait is for
    print_to_stderr("framing the camera: reading the grains of {} frames\n", files.size());
  std::vector<ViewBounds> part(files.size());
  std::vector<std::string> errors(files.size());
  parallel_tasks(static_cast<int>(files.size()), jobs, [&](int i) {
    try {
      part[i] = grain_core_bounds(read_ply(files[i]));
    } catch (const std::exception& e) {
      errors[i] = e.what();
    }
  });
  ViewBounds b;
  for (std::size_t i = 0; i < files.size(); ++i) {
    if (!errors[i].empty()) throw InputError(errors[i]);
    b.add(part[i]);
  }
  return b;
}

std::string comma_list(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& x : v) s += (s.empty() ? "" : ", ") + x;
  return s;
}

/// Frame numbers in ascending order as ranges: "1-3, 5".
std::string frame_ranges(const std::vector<int>& frames) {
  std::vector<std::string> parts;
  for (std::size_t k = 0; k < frames.size();) {
    std::size_t e = k;
    while (e + 1 < frames.size() && frames[e + 1] == frames[e] + 1) ++e;
    parts.push_back(e == k ? std::to_string(frames[k])
                           : fmt::format("{}-{}", frames[k], frames[e]));
    k = e + 1;
  }
  return comma_list(parts);
}

// ---- Pictures already made -------------------------------------------------------------------

/// A picture's digest: its POV-Ray scene, size and quality, all that POV-Ray makes it from.
std::uint64_t picture_digest(const std::string& pov_text, int width, int height, bool antialias) {
  Hasher h;
  h.add_bytes(pov_text.data(), pov_text.size());
  h.add(width);
  h.add(height);
  h.add(antialias);
  return h.value();
}

/// What each picture in a run's render/ was made from: render/pictures.json, frame -> digest. A
/// picture asked for again with the same digest, and whole, is kept: an interrupted render (or the
/// same one with --movie) goes on from the pictures it made instead of making them anew.
class PictureRecord {
 public:
  explicit PictureRecord(const std::string& run)
      : path_((fs::path(run) / "render" / "pictures.json").string()) {
    try {
      if (const auto text = read_file_if_present(path_, "picture record", kMaxRecordBytes)) {
        nlohmann::json record = nlohmann::json::parse(*text);
        if (!record.is_object() || !record.contains("pictures") || !record["pictures"].is_object())
          throw InputError(path_ + ": not a record of pictures (no \"pictures\" object)");
        pictures_ = std::move(record["pictures"]);
      }
    } catch (const nlohmann::json::exception& e) {
      forget(fmt::format("{}: not a record of pictures ({})", path_, e.what()));
    } catch (const InputError& e) {  // (its message names the file)
      forget(e.what());
    }
  }

  /// Whether the picture of `frame` was made from `digest` (and is still there, whole).
  bool has(int frame, std::uint64_t digest, const std::string& png) const {
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      const auto it = pictures_.find(std::to_string(frame));
      if (it == pictures_.end() || *it != fmt::format("{:016x}", digest)) return false;
    }
    return png_problem(png).empty();  // (read outside the lock: the other jobs' records go on)
  }

  /// Records the picture of `frame`, just made from `digest` (the record written at once: a
  /// render killed later keeps it). A record that cannot be written is warned of, once.
  void made(int frame, std::uint64_t digest) {
    const std::lock_guard<std::mutex> lock(mutex_);
    pictures_[std::to_string(frame)] = fmt::format("{:016x}", digest);
    try {
      write_file_atomic(path_, nlohmann::json{{"pictures", pictures_}}.dump(1) + "\n");
    } catch (const OutputError& e) {
      if (!warned_)
        print_to_stderr("warning: {}: the next render makes these pictures again\n", e.what());
      warned_ = true;
    }
  }

 private:
  /// Starts with no picture recorded, saying why: only time is lost, the pictures made again.
  void forget(const std::string& why) {
    print_to_stderr("warning: {}: every picture is made again\n", why);
    pictures_ = nlohmann::json::object();
  }

  static constexpr std::size_t kMaxRecordBytes = std::size_t{64} << 20;
  std::string path_;
  nlohmann::json pictures_ = nlohmann::json::object();
  mutable std::mutex mutex_;
  bool warned_ = false;
};

}  // namespace

int render_command(const RenderOptions& o) {
  // Options first: nothing is read or written when one is bad.
  if (o.quality != "draft" && o.quality != "final")
    throw InputError(fmt::format("--quality {}: expected draft or final", o.quality));
  FramesSpec spec;
  std::string frames_option;
  if (!o.frames.empty()) {
    spec = parse_frames(o.frames);
    frames_option = "--frames " + o.frames;
  } else if (o.frame > 0) {
    spec = {o.frame, o.frame};
    frames_option = fmt::format("--frame {}", o.frame);
  }
  const std::vector<Override> overrides = look_overrides(o.sets);
  const bool movie_tool = !o.movie || !find_program("ffmpeg").empty();

  // The frames of each run (a comparison's two runs have the same)
  const std::vector<std::string> runs = run_folders(o.dir);
  struct Task {
    std::string run;
    int frame;
  };
  std::vector<Task> tasks;
  struct Span {
    int first, last;
  };
  std::vector<Span> spans;
  // (a movie of the last frame alone is no movie: --movie alone takes them all)
  const bool last_only = o.frames.empty() && o.frame <= 0 && !o.movie;
  for (const std::string& run : runs) {
    const std::vector<int> have = frame_numbers(run);
    if (have.empty()) throw InputError(fmt::format("{}: no frames/NNNN.ply in this folder", run));
    const int first = last_only ? have.back() : spec.first.value_or(have.front());
    const int last = last_only ? have.back() : spec.last.value_or(have.back());
    if (std::max(first, last) > have.back())
      throw InputError(fmt::format(
          "{}: frame {} is beyond the last frame of {}, {} ({}): expected frames up to {}",
          frames_option, std::max(first, last), run, have.back(), frame_path(run, have.back()),
          have.back()));
    if (first > last)
      throw InputError(fmt::format("{}: {} has no frames in that range (its first is {})",
                                   frames_option, run, have.front()));
    for (int f = first; f <= last; ++f) {
      if (!std::binary_search(have.begin(), have.end(), f))
        throw InputError(fmt::format("{}: {} is missing", frames_option, frame_path(run, f)));
      tasks.push_back({run, f});
    }
    spans.push_back({first, last});
  }

  if (runs.size() > 1 && (spans[0].first != spans[1].first || spans[0].last != spans[1].last))
    print_to_stderr(
        "warning: {}: its runs' frames differ ({} {}-{}, {} {}-{}: frames were deleted, or "
        "a run was run on alone): each is rendered on its own{}\n",
        o.dir, runs[0], spans[0].first, spans[0].last, runs[1], spans[1].first, spans[1].last,
        o.movie ? ", and no side-by-side movie is made" : "");
  if (find_povray().empty())
    throw InputError("povray is not installed: sudo apt-get install povray");
  if (!movie_tool)
    print_to_stderr(
        "warning: ffmpeg is not installed: the frames will be rendered, but no movie made "
        "(sudo apt-get install ffmpeg)\n");

  const RenderScene scene = load_render_scene(o.scene, o.sets, overrides, runs.front());
  const int cores = std::max(1, default_thread_count());  // the cores this job may take
  const int jobs = std::min(o.jobs > 0 ? o.jobs : cores, static_cast<int>(tasks.size()));
  // the cores shared out: each povray gets its share of them as render threads
  const int threads_each = std::max(1, cores / std::max(jobs, 1));

  PovOptions opt;
  opt.width = o.width;
  opt.height = o.height;
  opt.fov_deg = scene.camera.fov_deg;
  opt.soft_light = o.quality == "final";
  if (scene.camera.position) {
    opt.auto_camera = false;
    opt.camera_position = *scene.camera.position;
    opt.camera_look_at = *scene.camera.look_at;
    opt.camera_up = scene.camera.up.value_or(Vec3{0, 0, 1});
  }
  // Lights and floor are placed around the same bounds for every frame, the camera too: those of
  // every frame of the run for an animation, so that it does not jitter; a still is framed on
  // what it shows. Either way the static layer's sand and the geometry are in.
  const bool still =
      std::all_of(spans.begin(), spans.end(), [](const Span& sp) { return sp.first == sp.last; });
  std::vector<std::vector<int>> framed;
  for (std::size_t k = 0; k < runs.size(); ++k)
    framed.push_back(still ? std::vector<int>{spans[k].first} : frame_numbers(runs[k]));
  opt.bounds = run_bounds(runs, framed, cores);
  opt.bounds.add(geometry_bounds(scene.geometry, scene.meshes));
  std::vector<std::optional<HeightImages>> heights;
  for (std::size_t k = 0; k < runs.size(); ++k) {
    heights.push_back(read_height_images(runs[k]));
    const nlohmann::json summary = read_summary(runs[k]);
    const auto field = [&](const char* key) {
      return summary.is_object() && summary.contains(key) ? summary.at(key) : nlohmann::json();
    };
    const nlohmann::json statics = field("n_static_final");
    if (!heights.back() && field("mode") == "surface" && statics.is_number_integer() &&
        statics.get<std::int64_t>() > 0)
      print_to_stderr(
          "warning: {}: its static layer ({} at the end) is not drawn: "
          "heightfield/heightfield.json is missing or not one sandflow wrote (a run "
          "exports it with --export height)\n",
          runs[k], counted(statics.get<std::int64_t>(), "grain"));
    if (!heights.back() || !still) continue;  // (in an animation the grains cover it)
    for (int f : framed[k]) {
      const SandSurface sf = static_layer(runs[k], f, *heights.back(), scene);
      for (std::size_t c = 0; c < sf.sand.size(); ++c)
        if (sf.sand[c])
          opt.bounds.add({sf.origin_x + (static_cast<Real>(c % sf.nx) + 0.5) * sf.cell,
                          sf.origin_y + (static_cast<Real>(c / sf.nx) + 0.5) * sf.cell, sf.z[c]},
                         0.5 * sf.cell);
    }
  }

  // one render at a time in a folder: two wrote the same scene, log and partial picture names
  // and removed each other's (the second failed every frame with an empty log)
  std::vector<std::unique_ptr<FolderLock>> locks;
  for (const std::string& run : runs)
    if (!o.folder_held)
      locks.push_back(std::make_unique<FolderLock>(
          (fs::path(run) / "render").string(),
          FolderUse{"render", "wait for it to end or stop it, then render again"}));

  // Render: failures are collected, the other frames go on.
  const int n = static_cast<int>(tasks.size());
  std::vector<std::string> errors(tasks.size());
  std::mutex progress_mutex;
  int done = 0;
  auto progress_label = [&](int at_once) {
    return fmt::format("render {} ({}, {} at once)", o.dir, o.quality, at_once);
  };
  Progress progress(progress_label(jobs), n);
  // SIGINT or SIGTERM: the pictures being made are stopped and their files removed, no new one
  // starts, and what is done stays
  const StopSignals signals;
  const StopChildren stop_children;
  std::vector<char> rendered(tasks.size(), 0), kept(tasks.size(), 0);
  std::vector<std::unique_ptr<PictureRecord>> records;
  for (const std::string& run : runs) records.push_back(std::make_unique<PictureRecord>(run));
  // POV-Rays at once: no more than the memory free now holds, by what each picture took
  const std::int64_t free_memory = available_memory_bytes();
  MemoryGate gate(free_memory / 10 * 9, jobs, std::min(jobs, cores));
  bool memory_said = false;
  parallel_tasks(n, jobs, [&](int i) {
    if (!gate.enter([] { return g_stop_signal != 0; })) return;
    std::int64_t peak = 0;  // what this picture held: POV-Ray's peak and the scene's text
    const Task& t = tasks[i];
    const std::string stem = (fs::path(t.run) / "render" / fmt::format("{:04d}", t.frame)).string();
    std::size_t grains = 0;
    try {
      const FrameData f = read_ply(frame_path(t.run, t.frame));
      grains = f.size();
      const auto k =
          static_cast<std::size_t>(std::find(runs.begin(), runs.end(), t.run) - runs.begin());
      const SandSurface sf =
          heights[k] ? static_layer(t.run, t.frame, *heights[k], scene) : SandSurface{};
      PovOptions frame_opt = opt;
      frame_opt.time = t.frame / scene.fps.value_or(30.0);  // (a removed solid is not drawn)
      const std::string text = pov_scene_text(f, scene.geometry, frame_opt, scene.meshes, &sf);
      const bool antialias = o.quality == "final";
      const std::uint64_t digest = picture_digest(text, o.width, o.height, antialias);
      const bool up_to_date = !o.again && records[k]->has(t.frame, digest, stem + ".png");
      if (!up_to_date || o.keep_pov) write_file_atomic(stem + ".pov", text, Sync::Later);
      if (up_to_date) {
        kept[static_cast<std::size_t>(i)] = 1;
      } else {
        peak =
            render_pov(stem + ".pov", stem + ".png", o.width, o.height, threads_each, antialias) +
            static_cast<std::int64_t>(text.size());
        records[k]->made(t.frame, digest);
      }
      rendered[static_cast<std::size_t>(i)] = 1;
      if (!o.keep_pov) {
        std::error_code ec;
        fs::remove(stem + ".pov", ec);
        fs::remove(stem + ".png.log", ec);
      }
    } catch (const std::exception& e) {
      errors[i] = e.what();
      if (g_stop_signal != 0 && !o.keep_pov) {  // (stopped, not failed: nothing to look into)
        std::error_code ec;
        fs::remove(stem + ".pov", ec);
        fs::remove(stem + ".png.log", ec);
      }
    }
    gate.leave(peak);
    const std::lock_guard<std::mutex> lock(progress_mutex);
    if (gate.allowed() < jobs) {
      if (!memory_said)
        progress.note(fmt::format(
            "render: a picture takes up to {:.0f} MB (POV-Ray and its scene) and {:.0f} MB were "
            "free: {} at once, not {}",
            static_cast<double>(gate.largest_peak()) / 1e6, static_cast<double>(free_memory) / 1e6,
            gate.allowed(), jobs));
      memory_said = true;
      progress.relabel(progress_label(gate.allowed()));  // (the line says what runs)
    }
    if (kept[static_cast<std::size_t>(i)]) progress.skip();  // (its speed is POV-Ray's)
    progress.update(++done, static_cast<std::int64_t>(grains));
  });

  if (g_stop_signal != 0) {
    std::vector<int> done_frames;
    for (int i = 0; i < n; ++i)
      if (rendered[static_cast<std::size_t>(i)]) done_frames.push_back(tasks[i].frame);
    for (int i = 0; i < n; ++i)
      if (rendered[static_cast<std::size_t>(i)])
        fmt::print("{}\n",
                   (fs::path(tasks[i].run) / "render" / fmt::format("{:04d}.png", tasks[i].frame))
                       .string());
    if (signals.outermost())
      print_to_stderr(
          "\ninterrupted: {} of {} pictures made (in place){}; the others are not "
          "made{}. The same command goes on from them\n",
          done_frames.size(), n,
          done_frames.empty() || runs.size() > 1
              ? std::string()
              : fmt::format(", frames {}", frame_ranges(done_frames)),
          o.movie ? ", nor the movie" : "");
    return 128 + g_stop_signal;
  }

  if (const auto same = std::count(kept.begin(), kept.end(), 1); same > 0)
    print_to_stderr(
        "render: {} of {} kept, made earlier from the same scene, size and quality "
        "(render/pictures.json; --again makes them anew)\n",
        same, counted(n, "picture"));

  // What was made, on stdout; what failed, in the error.
  std::vector<int> failed;
  for (int i = 0; i < n; ++i) {
    const std::string stem =
        (fs::path(tasks[i].run) / "render" / fmt::format("{:04d}", tasks[i].frame)).string();
    if (errors[i].empty())
      fmt::print("{}.png\n", stem);
    else
      failed.push_back(i);
  }
  std::fflush(stdout);
  if (!failed.empty()) {
    std::vector<std::string> names;
    for (std::size_t k = 0; k < failed.size() && k < 10; ++k) {
      const Task& t = tasks[failed[k]];
      names.push_back(runs.size() > 1
                          ? fmt::format("{} frame {}", fs::path(t.run).filename().string(), t.frame)
                          : fmt::format("frame {}", t.frame));
    }
    if (failed.size() > names.size())
      names.push_back(fmt::format("and {} more", failed.size() - names.size()));
    throw OutputError(fmt::format(
        "{} of {} frames failed to render ({}); the other pictures are in place{}. The first "
        "failure: {}",
        failed.size(), n, comma_list(names), o.movie ? ", and no movie was made" : "",
        errors[failed.front()]));
  }

  if (!o.movie) return 0;
  const double fps = scene.fps.value_or(30.0);
  if (!scene.fps)
    print_to_stderr("warning: the run's fps is unknown (no summary.json): the movie is at {}\n",
                    fps);
  // each run's movie, and a comparison's two runs side by side (surface left, DEM right)
  struct Movie {
    std::vector<std::string> folders;
    Span span;
    std::string mp4;
  };
  std::vector<Movie> movies;
  for (std::size_t k = 0; k < runs.size(); ++k) {
    const std::string folder = (fs::path(runs[k]) / "render").string();
    movies.push_back({{folder}, spans[k], (fs::path(folder) / "movie.mp4").string()});
  }
  const bool side_by_side =
      runs.size() > 1 && spans[0].first == spans[1].first && spans[0].last == spans[1].last;
  if (side_by_side) {
    const fs::path folder = fs::path(o.dir) / "render";
    std::error_code ec;
    fs::create_directories(folder, ec);
    if (ec) throw OutputError(fmt::format("{}: cannot create: {}", folder.string(), ec.message()));
    movies.push_back({{movies[0].folders[0], movies[1].folders[0]},
                      spans[0],
                      (folder / "side_by_side.mp4").string()});
  }
  if (!movie_tool) {
    const Movie& m = movies.front();
    throw InputError(fmt::format(
        "ffmpeg is not installed, so no movie was made (the pictures are in {}). Install it "
        "with: sudo apt-get install ffmpeg; then encode them with: ffmpeg -framerate {} "
        "-start_number {} -i {}/%04d.png -frames:v {}{} -c:v libx264 -pix_fmt yuv420p {}",
        comma_list(runs.size() > 1
                       ? std::vector<std::string>{movies[0].folders[0], movies[1].folders[0]}
                       : m.folders),
        fps, m.span.first, m.folders[0], m.span.last - m.span.first + 1,
        o.width % 2 || o.height % 2 ? " -vf 'pad=ceil(iw/2)*2:ceil(ih/2)*2'" : "", m.mp4));
  }
  for (const Movie& m : movies) {
    try {
      encode_movie(m.folders, m.span.first, m.span.last - m.span.first + 1, fps, m.mp4);
    } catch (const OutputError&) {
      if (g_stop_signal == 0) throw;
      print_to_stderr(
          "\ninterrupted while {} was encoded: it is not made (the pictures are in "
          "place)\n",
          m.mp4);
      return 128 + g_stop_signal;
    }
    if (!o.keep_pov) {
      std::error_code ec;
      fs::remove(m.mp4 + ".log", ec);
    }
    fmt::print("{}\n", m.mp4);
  }
  return 0;
}

}  // namespace sandflow
