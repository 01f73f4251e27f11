// The crater an impact leaves in a bed of sand, measured from the grains alone (the same for a
// plain-DEM run and a surface-mode run: every grain counts, static ones too).
//
// Method (d = mean grain diameter):
//  1. Top-surface map: square cells of side d, each holding the highest grain top, max(z + r),
//     of the grains whose centre lies in it; then a 3x3 median over the occupied neighbours, so
//     that one grain of ejecta lying in the crater, or one missing grain, is not the crater.
//  2. Reference level z_ref: the bed's undisturbed top, given by the caller (the bed's height in
//     the scene), or else the median of the smoothed map (right while the crater and its rim
//     cover less than half the bed).
//  3. Centre: the given (x, y), or else the depth-weighted centroid of the connected cells more
//     than a diameter below z_ref around the lowest smoothed cell.
//  4. Radial profile around the centre: rings of width d, each the median height of its cells.
//  5. Depth: z_ref minus the lowest profile point inside the crater (the rings before the profile
//     first rises back to z_ref, whose distance is the crater's radius). Rim: the highest profile
//     point from there out to three crater radii, above z_ref, and its distance.
// The fit is refused (ok = false, with a reason) without grains, or when no cell lies a diameter
// below z_ref (no crater to measure: the surface is within a grain of flat).
#pragma once

#include <limits>
#include <string>
#include <vector>

#include "core/vec3.hpp"

namespace sandflow {

struct CraterFit {
  double depth = 0;       ///< z_ref minus the crater's lowest profile point [m]
  double rim_height = 0;  ///< the rim's highest profile point above z_ref [m]
  double radius = 0;      ///< where the profile first rises back through z_ref [m]
  double rim_radius = 0;  ///< distance of the rim's highest point from the centre [m]
  Vec3 centre;            ///< x, y of the crater's centre; z = z_ref [m]
  bool ok = false;        ///< false: the numbers above are not a crater; see reason
  std::string reason;     ///< why ok is false (empty when ok)
};

/// Measures the crater in the grains at `pos` with radii `radius` (same length, else
/// std::invalid_argument). `z_ref` is the undisturbed top of the bed [m] and (`cx`, `cy`) the
/// crater's centre [m]; NaN: found from the grains, as above.
CraterFit measure_crater(const std::vector<Vec3>& pos, const std::vector<Real>& radius,
                         double z_ref = std::numeric_limits<double>::quiet_NaN(),
                         double cx = std::numeric_limits<double>::quiet_NaN(),
                         double cy = std::numeric_limits<double>::quiet_NaN());

}  // namespace sandflow
