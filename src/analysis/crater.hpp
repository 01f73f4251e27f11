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
//
// A scene's crater (crater_site, used by `sandflow compare`): made in the scene's bed (a bed
// emitter), the centre where its thrown sand lands, z_ref the bed's top as packed (bed_level),
// and only the grains whose centres lie over the bed's footprint counted (ejecta thrown out of
// its container are not the bed's surface).
#pragma once

#include <cstddef>
#include <limits>
#include <string>
#include <vector>

#include "config/scene_config.hpp"
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

/// The top of a flat bed as the map of step 1 sees it: the median of its smoothed cells [m]; NaN
/// without grains. A packed bed's grains stop short of its `height` (by about a third of a
/// diameter for the drop-and-roll packing of geometry/bed_packing.hpp, 1 cm grains): measured on
/// the bed as it was packed, this is the undisturbed level a crater is measured from. From the
/// height instead, a rim lower than that third would not count as one.
double bed_level(const std::vector<Vec3>& pos, const std::vector<Real>& radius);

/// Where a scene's crater is sought.
struct CraterSite {
  bool bed = false;           ///< false: the scene has no bed emitter, so no crater is sought
  std::size_t bed_index = 0;  ///< the bed's index among the scene's emitters
  double height = std::numeric_limits<double>::quiet_NaN();  ///< the bed's `height` [m]
  double x0 = 0, y0 = 0, x1 = 0, y1 = 0;                     ///< the bed's footprint [m]
  double cx = std::numeric_limits<double>::quiet_NaN();  ///< the centre [m]; NaN: found from the
  double cy = std::numeric_limits<double>::quiet_NaN();  ///< grains (measure_crater)
  std::string centre_from;  ///< how the centre was chosen, for messages
};

/// The crater site of a scene. The bed: the one the thrown sand comes down on, else the scene's
/// first. The centre: with exactly one emitter besides the beds (a block, a pour, a lattice),
/// where its sand comes down to the bed's `height` on a ballistic path from its start (the bottom
/// of a block's or a lattice's box, a pour's disk) at its velocity under the scene's gravity: the
/// same centre for every run of the scene, whatever its seed and mode. Otherwise (none, several,
/// or one that never comes down over a bed) NaN: measure_crater finds it from the grains.
CraterSite crater_site(const SceneConfig& scene);

/// The crater at `site`, measured from the level `z_ref` [m] (NaN: found from the grains), in the
/// grains whose centres lie over its bed's footprint; a site without a bed gives a fit that is
/// not ok.
CraterFit measure_crater(const CraterSite& site, double z_ref, const std::vector<Vec3>& pos,
                         const std::vector<Real>& radius);

}  // namespace sandflow
