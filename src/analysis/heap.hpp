// The angle of repose of a heap of grains, measured from the grains alone.
//
// Method (d = mean grain diameter, all heights measured from the floor):
//  1. Top-surface map. The plane is cut into square cells of side d. A cell's height is the
//     highest grain top, max(z + r), over the grains whose centre lies in it, minus the floor
//     height (floor_z, or by default the lowest grain bottom, min(z - r)). Cells holding no grain
//     have no height and are skipped everywhere below.
//  2. Apex. Each cell's height is replaced by the median of the occupied cells of its 3x3
//     neighbourhood, so that one stray grain on top does not count as the summit. The apex is the
//     highest smoothed cell; its x, y are refined to the centroid of the occupied cells connected
//     to it whose smoothed height is within half a diameter of that maximum (a flat or rounded top
//     then gives its centre rather than the first cell of a tie). Its z is the floor plus that
//     maximum.
//  3. Radial profile. The cells are grouped into rings of width d around the apex. Each ring gives
//     one profile point: the median distance and the median height of its cells. Medians keep
//     the staircase of single grains and the occasional loose grain from biasing the profile.
//  4. Height. Hh = the largest profile height.
//  5. Flank. Walking outwards from the ring of Hh, the profile is cut at the first ring lower than
//     band_low * Hh (the toe, where the heap meets the floor, and everything beyond it). Of the
//     rings before the cut, those with band_low * Hh <= height <= band_high * Hh (defaults 25 %
//     and 75 %) are the flank: this leaves out the rounded top and the toe.
//  6. Fit. A least-squares line height = a + b * distance through the flank points gives the
//     angle of repose atan(-b) in degrees, the RMS of the residuals, and the base radius, where
//     the line meets the floor (-a / b).
// The fit is refused (ok = false, with a reason) when there are no usable grains, when the flank
// band spans less than 2 diameters of height (4 diameters of heap with the default band: below
// that the profile is the staircase of single grains), when fewer than 4 flank points remain, or
// when the flank does not descend. The angle's standard error comes from the fit's scatter. Then
// repose_angle_deg is NaN and base_radius is the outermost profile distance.
#pragma once

#include <limits>
#include <string>
#include <vector>

#include "core/vec3.hpp"

namespace sandflow {

/// Why a run or a comparison of a scene with a bed gives no angle of repose.
inline constexpr const char* kNoHeapInABed =
    "not measured in a scene with a bed: the heap fit would take the bed's flat top, its walls and "
    "the crater's rim for a heap";

struct HeapFit {
  double repose_angle_deg = std::numeric_limits<double>::quiet_NaN();  ///< [deg]
  double height = 0;       ///< Hh: highest point of the radial profile above the floor [m]
  double base_radius = 0;  ///< where the fitted flank meets the floor [m]
  Vec3 apex;               ///< summit: refined x, y and the floor plus the smoothed maximum [m]
  int points_used = 0;     ///< profile points in the flank fit
  double fit_rms = 0;      ///< RMS residual of the flank fit [m]
  double repose_angle_se_deg = 0;  ///< standard error of the angle from the fit's scatter [deg]
  bool ok = false;         ///< false: the numbers above are not an angle of repose; see reason
  std::string reason;      ///< why ok is false (empty when ok)
};

/// Measures the heap formed by grains at `pos` with radii `radius` (same length, else
/// std::invalid_argument). `floor_z` is the height the heap stands on [m]; NaN means the lowest
/// grain bottom. The flank is the part of the radial profile between band_low and band_high of
/// the heap height (fractions, 0 <= band_low < band_high <= 1).
HeapFit measure_heap(const std::vector<Vec3>& pos, const std::vector<Real>& radius,
                     double floor_z = std::numeric_limits<double>::quiet_NaN(),
                     double band_low = 0.25, double band_high = 0.75);

}  // namespace sandflow
