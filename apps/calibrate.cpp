// `sandflow calibrate SCENE`: the angles of repose of a scene's material, measured by plain DEM
// (src/calibration), and the cache that lets surface mode use them without measuring again.
#include <omp.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <optional>
#include <string>

#include <fmt/format.h>

#include "calibration/calibration.hpp"
#include "commands.hpp"
#include "console.hpp"
#include "core/atomic_file.hpp"
#include "core/counted.hpp"
#include "core/error.hpp"
#include "core/file_kind.hpp"
#include "core/read_file.hpp"
#include "progress.hpp"
#include "scene/scene_loader.hpp"
#include "stop_signals.hpp"

namespace sandflow {

namespace fs = std::filesystem;

std::string calibration_cache_dir() {
  if (const char* d = std::getenv("SANDFLOW_CACHE_DIR"); d && *d)
    return fs::path(d) / "calibration";
  if (const char* d = std::getenv("XDG_CACHE_HOME"); d && *d)
    return fs::path(d) / "sandflow" / "calibration";
  if (const char* d = std::getenv("HOME"); d && *d)
    return fs::path(d) / ".cache" / "sandflow" / "calibration";
  return fs::path(".sandflow-cache") / "calibration";
}

std::optional<nlohmann::json> cached_calibration(const std::string& key) {
  const fs::path path = fs::path(calibration_cache_dir()) / (key + ".json");
  refuse_special_file(path.string(), "calibration cache file");
  std::string text;
  try {
    text = read_whole_file(path.string(), "calibration cache file", kAnyFileSize);
  } catch (const InputError&) {
    return std::nullopt;  // not there or unreadable: measured again, as a damaged one is
  }
  const nlohmann::json j = nlohmann::json::parse(text, nullptr, false);
  // a damaged or foreign file is measured again, not trusted
  if (j.is_discarded() || !j.is_object() || j.value("key", "") != key ||
      !j.contains("theta0_deg") || !j["theta0_deg"].is_number() || !j.contains("theta_max_deg") ||
      !j["theta_max_deg"].is_number())
    return std::nullopt;
  const double theta0 = j["theta0_deg"].get<double>(), theta_max = j["theta_max_deg"].get<double>();
  if (!(theta0 > 0 && theta0 < 90 && theta_max >= theta0 && theta_max < 90)) return std::nullopt;
  return j;
}

nlohmann::json calibration_json(const Calibration& c) {
  nlohmann::json trials = nlohmann::json::array();
  for (const CalibrationTrial& t : c.trials)
    trials.push_back(
        {{"seed", t.seed},
         {"heap_ok", t.poured.ok},
         {"reason", t.poured.ok ? "" : "too few cells on the flank"},
         {"theta0_deg", t.poured.ok ? nlohmann::json(t.theta0_deg) : nlohmann::json()},
         {"theta0_se_deg", t.poured.ok ? nlohmann::json(t.poured.se_deg) : nlohmann::json()},
         {"failed", t.failed},
         {"tilt_deg", t.tilt_deg},
         {"theta_max_deg", t.failed ? nlohmann::json(t.theta_max_deg) : nlohmann::json()},
         {"theta_stop_deg",
          t.failed && t.stop.ok ? nlohmann::json(t.theta_stop_deg) : nlohmann::json()},
         {"theta_stop_se_deg",
          t.failed && t.stop.ok ? nlohmann::json(t.stop.se_deg) : nlohmann::json()},
         {"measure_heap_deg",
          t.heap.ok ? nlohmann::json(t.heap.repose_angle_deg) : nlohmann::json()},
         {"grains_on_base", t.grains_on_base},
         {"heap_height", t.heap.height},
         {"seconds", t.seconds}});
  return {{"key", c.key},
          {"sandflow_version", SANDFLOW_VERSION},
          {"theta0_deg", c.theta0_deg},
          {"theta0_sd_deg", c.theta0_sd_deg},
          {"theta_max_deg", c.theta_max_deg},
          {"theta_max_sd_deg", c.theta_max_sd_deg},
          {"theta_stop_deg", c.theta_stop_deg},
          {"theta_stop_sd_deg", c.theta_stop_sd_deg},
          {"seconds", c.seconds},
          {"method",
           fmt::format("fixed-base heap (radius {:.3g} d) poured in plain DEM, then gravity tilted "
                       "at {:.3g} deg/s until {:.0f} % of the heap has slid off",
                       c.rig.base_diameters, c.rig.tilt_rate, 100 * kFailureLoss)},
          {"trials", trials}};
}

void store_calibration(const nlohmann::json& j) {
  if (const std::string problem = calibration_cache_problem(); !problem.empty())
    throw OutputError(problem);
  write_file_atomic(
      (fs::path(calibration_cache_dir()) / (j["key"].get<std::string>() + ".json")).string(),
      j.dump(2) + "\n");
}

std::string calibration_cache_problem() {
  const fs::path dir = calibration_cache_dir();
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec)
    return fmt::format("{}: cannot make the calibration cache folder: {}", dir.string(),
                       ec.message());
  if (access(dir.c_str(), W_OK | X_OK) != 0)
    return fmt::format("{}: cannot write in the calibration cache folder: {}", dir.string(),
                       std::strerror(errno));
  return "";
}

/// What to do about a cache folder that cannot be written (the variables that move it).
constexpr const char* kCacheAdvice =
    "set SANDFLOW_CACHE_DIR (or XDG_CACHE_HOME) to a folder that can be written";

nlohmann::json measure_calibration(const SceneConfig& scene, int trials, const RigSettings& rig,
                                   bool keep) {
  // on a terminal one line redrawn; in a log, a line per phase of each trial
  const bool tty = isatty(STDERR_FILENO) != 0;
  std::string last;
  CoreShareWarning core_share(omp_get_max_threads());
  const StopSignals signals;
  const Calibration c = calibrate(
      scene, trials,
      [&](int trial, const char* phase, double t) {
        if (g_stop_signal != 0) {
          if (tty) print_to_stderr("\n");
          throw CalibrationInterrupted{g_stop_signal};
        }
        if (const std::optional<std::string> warning = core_share.poll())
          print_to_stderr("{}{}\n", tty ? "\r\033[K" : "", *warning);
        const std::string now =
            fmt::format("calibrating: trial {} of {}, {}", trial + 1, trials, phase);
        if (tty)
          print_to_stderr("\r{} (t = {:.2f} s)\033[K", now, t);
        else if (now != last)
          print_to_stderr("{}\n", now);
        last = now;
      },
      rig);
  if (tty) print_to_stderr("\n");
  nlohmann::json j = calibration_json(c);
  j["threads"] = omp_get_max_threads();  // (what `seconds` took; the angles do not depend on it)
  if (keep) {
    try {
      store_calibration(j);
    } catch (const OutputError& e) {
      // minutes of measuring: the angles are said, so that a scene can take them by hand
      throw OutputError(fmt::format(
          "{}\n  the angles measured are not kept: theta0 {:.2f} deg, theta_max {:.2f} deg (a "
          "scene takes them as [surface] repose_angle and max_angle)",
          e.what(), j["theta0_deg"].get<double>(), j["theta_max_deg"].get<double>()));
    }
  }
  return j;
}

bool calibration_disabled() {
  const char* v = std::getenv("SANDFLOW_NO_CALIBRATION");
  return v && *v && std::string(v) != "0";
}

bool needs_calibration(const SceneConfig& scene) {
  const SurfaceConfig& s = scene.surface;
  return scene.simulation.mode == Mode::Surface && (!s.repose_angle_given || !s.max_angle);
}

nlohmann::json resolve_surface_angles(SceneConfig& scene) {
  SurfaceConfig& s = scene.surface;
  if (!needs_calibration(scene)) {
    s.angles_source = "scene";
  } else if (calibration_disabled()) {
    s.angles_source = fmt::format(
        "{} (SANDFLOW_NO_CALIBRATION is set)",
        s.repose_angle_given ? "scene, and the built-in max_angle" : "built-in defaults");
  } else {
    const std::string key = calibration_key(scene);
    std::optional<nlohmann::json> j = cached_calibration(key);
    const bool cached = j.has_value();
    if (!cached) {
      print_to_stderr(
          "{}: surface.repose_angle or max_angle unset: measuring the material's angles "
          "(sandflow calibrate, once for this material: about a minute)\n",
          scene.path);
      // a folder that cannot be written costs this run nothing, the next one the measurement
      const std::string problem = calibration_cache_problem();
      if (!problem.empty())
        warn_once(fmt::format("{}: the angles measured now serve this run and are not kept; {}",
                              problem, kCacheAdvice));
      omp_set_num_threads(thread_count(scene));  // the run's --threads: its share of the cores
      j = measure_calibration(scene, kDefaultCalibrationTrials, {}, false);
      if (problem.empty()) {
        try {
          store_calibration(*j);
        } catch (const OutputError& e) {  // (a disk that filled while it measured)
          warn_once(fmt::format("{}: the angles measured now serve this run and are not kept; {}",
                                e.what(), kCacheAdvice));
        }
      }
    }
    const Real theta0 = deg_to_rad((*j)["theta0_deg"].get<double>());
    const Real theta_max = deg_to_rad((*j)["theta_max_deg"].get<double>());
    if (!s.repose_angle_given) s.repose_angle = theta0;
    if (!s.max_angle) s.max_angle = std::max(theta_max, s.repose_angle);
    if (*s.max_angle < s.repose_angle)
      throw InputError(fmt::format(
          "{}: surface.max_angle = {:.4g} is less than the material's calibrated repose angle "
          "{:.4g} (degrees): set both, or neither",
          scene.path, rad_to_deg(*s.max_angle), rad_to_deg(s.repose_angle)));
    s.angles_source = fmt::format("{}calibration {} ({})", s.repose_angle_given ? "scene and " : "",
                                  key, cached ? "cached" : "measured for this run");
  }
  // radians as the run holds them: a resumed run must get the same bits, not a round trip
  const Real max_angle = s.max_angle.value_or(s.repose_angle + deg_to_rad(6.0));
  return {{"repose_angle_deg", rad_to_deg(s.repose_angle)},
          {"max_angle_deg", rad_to_deg(max_angle)},
          {"repose_angle_rad", s.repose_angle},
          {"max_angle_rad", max_angle},
          {"source", s.angles_source}};
}

void apply_surface_angles(SceneConfig& scene, const nlohmann::json& angles) {
  SurfaceConfig& s = scene.surface;
  s.repose_angle = angles.at("repose_angle_rad").get<double>();
  s.max_angle = angles.at("max_angle_rad").get<double>();
  s.angles_source = angles.at("source").get<std::string>();
}

namespace {

// What `calibrate` prints of a calibration record; nlohmann::json::exception when the record
// lacks a field (a cache file written by hand, or by another version).
std::string describe(const nlohmann::json& j) {
  std::string out;
  for (const auto& t : j.at("trials")) {
    if (!t.at("heap_ok").get<bool>()) {
      out += fmt::format("trial (seed {})   no heap: {}\n", t.at("seed").get<std::uint64_t>(),
                         t.at("reason").get<std::string>());
      continue;
    }
    const bool failed = t.at("failed").get<bool>();
    out += fmt::format(
        "trial (seed {})   theta0 {:.2f} deg (fit +- {:.2f}), {}{}, {} grains, {:.0f} s\n",
        t.at("seed").get<std::uint64_t>(), t.at("theta0_deg").get<double>(),
        t.at("theta0_se_deg").get<double>(),
        failed ? fmt::format("failed at a tilt of {:.1f} deg: theta_max {:.2f} deg",
                             t.at("tilt_deg").get<double>(), t.at("theta_max_deg").get<double>())
               : fmt::format("still standing at a tilt of {:.0f} deg", kMaxTilt),
        failed && t.at("theta_stop_deg").is_number()
            ? fmt::format(", stopped at {:.2f} deg", t.at("theta_stop_deg").get<double>())
            : "",
        t.at("grains_on_base").get<std::int64_t>(), t.at("seconds").get<double>());
  }
  out += fmt::format(
      "theta0           {:.2f} +- {:.2f} deg (the poured heap's flank; mean and standard "
      "deviation of the trials)\n",
      j.at("theta0_deg").get<double>(), j.at("theta0_sd_deg").get<double>());
  out += fmt::format("theta_max        {:.2f} +- {:.2f} deg\n", j.at("theta_max_deg").get<double>(),
                     j.at("theta_max_sd_deg").get<double>());
  out += fmt::format(
      "theta_stop       {:.2f} +- {:.2f} deg (downhill after the avalanche; not used)\n",
      j.at("theta_stop_deg").get<double>(), j.at("theta_stop_sd_deg").get<double>());
  out += fmt::format("method           {}\n", j.at("method").get<std::string>());
  return out;
}

}  // namespace

int calibrate_command(const RunOptions& o, int trials, bool again, const RigSettings& rig) {
  const SceneConfig scene = load_for_run(o);
  omp_set_num_threads(thread_count(scene));
  const std::string key = calibration_key(scene, rig);
  std::optional<nlohmann::json> j = again ? std::nullopt : cached_calibration(key);
  std::string text;
  if (j) {
    try {
      text = describe(*j);
    } catch (const nlohmann::json::exception&) {
      j.reset();  // an incomplete record: measured again
    }
  }
  const bool cached = j.has_value();
  if (!j) {
    // (before the minutes of measuring, not after them)
    if (const std::string problem = calibration_cache_problem(); !problem.empty())
      throw OutputError(fmt::format("{}; {}", problem, kCacheAdvice));
    try {
      j = measure_calibration(scene, trials, rig);
    } catch (const CalibrationInterrupted& e) {
      print_to_stderr("\ninterrupted: nothing measured was kept\n");
      return 128 + e.signal;
    }
    text = describe(*j);
  }
  fmt::print("scene            {} ({})\n", scene.name, scene.path);
  fmt::print("material key     {}\n", key);
  fmt::print("{}", text);
  fmt::print("{}        {}\n", cached ? "cached" : "stored",
             (fs::path(calibration_cache_dir()) / (key + ".json")).string());
  if (!cached)
    fmt::print("time             {:.0f} s on {}\n", j->at("seconds").get<double>(),
               counted(j->value("threads", 0), "thread"));
  // A smaller base holds a lower heap whose flank stands lower (the floor's sand, seeds 1 and 2:
  // base 4 gave 9.6-16.3 deg, 6: 23.2-25.5, 7: 27.4-28.7, 10: 31.2-34.9, 14: 35.0-35.3;
  // docs/performance.md, forty-seventh); surface runs use the default rig's key, never these.
  if (rig.base_diameters < RigSettings{}.base_diameters)
    print_to_stderr(
        "warning: a base of {:g} diameters measures the angles low (the floor's sand: "
        "theta0 9.6-16.3 deg at 4, 27.4-28.7 at 7, 31.2-34.9 at 10); surface runs use the "
        "default rig's, not these\n",
        rig.base_diameters);
  return 0;
}

}  // namespace sandflow
