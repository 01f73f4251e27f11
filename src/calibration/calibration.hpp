// The angles of repose of a scene's material, measured by plain DEM (`sandflow calibrate`).
//
// The rig: the fixed-base heap of the powder tests (ISO 4324, a cone on a disk): grains poured
// gently onto the top of a solid cylinder of radius R_b = 10 d (the scene's walls: its wall
// friction), until the heap overflows its rim. The base fixes the heap's size, so the heap does not
// depend on how much was poured or how fast it spread; what overflows falls off and leaves.
//  1. θ0, the angle at which a flow stops: the heap's flank once the pour has stopped and the
//     grains have settled, the last flow over it having stopped there (a cone fitted to the top
//     surface about the base's axis: cone_fit in calibration.cpp).
//  2. θ_max, the angle at which a static slope fails: gravity is then tilted (about x, at
//     kTiltRate) so that the downhill flank steepens by the tilt φ. The heap fails when it has
//     lost kFailureLoss of its grains since the tilt began; θ_max = θ0 + φ at that moment.
//  3. For the record, θ_stop: the tilt is held for kStopTime while the avalanche runs out, and the
//     flank facing downhill, seen in gravity's frame, is fitted. It is a wedge of a small heap,
//     and scatters by several degrees between seeds (docs/physics.md), so θ0 is the poured flank.
// Each trial is one seed; the result is the mean and the standard deviation over the trials.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "analysis/heap.hpp"
#include "config/scene_config.hpp"

namespace sandflow {

/// Radius of the rig's base, in mean diameters: 10 d makes a heap of about 1,000 grains.
constexpr Real kCalibrationBaseDiameters = 10;
/// How fast gravity tilts [deg/s]: a degree per 30 grain times sqrt(d / g) for 1 cm grains.
constexpr Real kTiltRate = 2.0;
/// Fraction of the heap's grains lost since the tilt began that marks its failure.
constexpr Real kFailureLoss = 0.03;
/// The tilt stops here [deg] (a heap that still stands has no θ_max below θ0 + this).
constexpr Real kMaxTilt = 30;
/// How long the avalanche is left to run out before θ_stop is measured [s].
constexpr Real kStopTime = 1.0;

/// The rig's size and pace: the defaults are what `sandflow calibrate` measures with (and what the
/// cache key stands for); tests shrink them.
struct RigSettings {
  Real base_diameters = kCalibrationBaseDiameters;
  Real tilt_rate = kTiltRate;  ///< [deg/s]
};

/// A cone fitted on the base's axis (calibration.cpp: cone_fit).
struct ConeFit {
  bool ok = false;
  double angle_deg = 0, se_deg = 0;  ///< the angle and its standard error from the fit [deg]
  int cells = 0;                     ///< surface cells fitted
};

struct CalibrationTrial {
  std::uint64_t seed = 0;
  HeapFit heap;                     ///< the settled heap on the base, as `measure` sees it
  ConeFit poured;                   ///< its flank about the base's axis (ok: θ0 measured)
  double theta0_deg = 0;            ///< the flank's angle after the pour [deg]
  double tilt_deg = 0;              ///< gravity's tilt at failure [deg]
  double theta_max_deg = 0;         ///< θ0 + tilt at failure [deg]
  ConeFit stop;                     ///< the downhill flank after the avalanche (in gravity's frame)
  double theta_stop_deg = 0;        ///< its angle [deg]
  bool failed = false;              ///< the heap failed within kMaxTilt
  std::int64_t grains_on_base = 0;  ///< grains on the base when the tilt began
  double seconds = 0;               ///< wall time of the trial [s]
};

struct Calibration {
  std::vector<CalibrationTrial> trials;
  double theta0_deg = 0, theta0_sd_deg = 0;          ///< θ0: mean, standard deviation [deg]
  double theta_max_deg = 0, theta_max_sd_deg = 0;    ///< the same for θ_max
  double theta_stop_deg = 0, theta_stop_sd_deg = 0;  ///< the same for θ_stop (0: none measured)
  double seconds = 0;
  std::string key;  ///< what the angles depend on, hashed (calibration_key)
  RigSettings rig;  ///< the rig it was measured with
};

/// How long the fingerprint's probe runs, in the grain's time scale sqrt(d / g).
constexpr int kFingerprintFrames = 6;

/// The state hash of a small DEM probe of the scene's material (a block of 40 grains thrown onto
/// a small base for kFingerprintFrames times sqrt(d / g), a few milliseconds): any change of the
/// code that changes the DEM's results changes it, so a cached calibration never outlives the code
/// that measured it (and no one has to remember to bump a version).
std::uint64_t dem_fingerprint(const SceneConfig& scene);

/// The hex hash of what the angles depend on: the material (sizes, density, contact law,
/// friction with the walls), gravity's magnitude, the stiffness rule, the rig and its version,
/// and the DEM's fingerprint (the code that measures them).
std::string calibration_key(const SceneConfig& scene, const RigSettings& rig = {});
/// The same with the fingerprint given.
std::string calibration_key(const SceneConfig& scene, const RigSettings& rig,
                            std::uint64_t fingerprint);

/// The rig of one trial for `scene`'s material, with seed `seed`, in plain DEM.
SceneConfig calibration_rig(const SceneConfig& scene, std::uint64_t seed,
                            const RigSettings& rig = {});

/// Progress of a trial: its index, the phase ("pour" or "tilt"), the simulated time [s].
using CalibrationProgress = std::function<void(int trial, const char* phase, double t)>;

/// Runs `trials` seeds (the scene's seed, + 1, ...) and gathers them. InputError when the scene's
/// material cannot make a rig (as for any scene); the trials whose heap cannot be fitted are kept
/// with heap.ok false and left out of the means (none left: InputError saying why).
Calibration calibrate(const SceneConfig& scene, int trials,
                      const CalibrationProgress& progress = {}, const RigSettings& rig = {});

}  // namespace sandflow
