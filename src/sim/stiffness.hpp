// k_n derived from the load a contact carries (docs/design.md §3), for each mode: in DEM the deepest
// grain carries the whole heap above it; in surface mode only the thin layer of grains above the
// static surface, so springs can be softer and dt larger. Impacts bound k_n in both modes.
#pragma once

#include "config/scene_config.hpp"
#include "geometry/shapes.hpp"

namespace sandflow {

struct Stiffness {
  Real k_n = 0;            ///< the stiffness used [N/m]
  bool from_load = false;  ///< false: material.k_n as given
  Real depth = 0;          ///< deepest loaded grain [m]
  Real impact_speed = 0;   ///< speed of the impact that sets k_impact [m/s]
  Real impact_mass_ratio = 0.5;  ///< its m_eff / m: 1/2 a grain of a pour, 1 a landing body
  Real k_static = 0;       ///< k_n that keeps the static overlap under stiffness.max_overlap [N/m]
  Real k_impact = 0;       ///< k_n that keeps impacts under stiffness.impact_overlap [N/m]
};

/// The stiffness of a scene run in `mode`.
Stiffness choose_stiffness(const SceneConfig& scene, Mode mode, const Geometry& geometry);

}  // namespace sandflow
