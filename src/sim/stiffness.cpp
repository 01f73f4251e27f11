#include "sim/stiffness.hpp"

#include <algorithm>
#include <cmath>

#include "surface/surface_params.hpp"

namespace sandflow {

Stiffness choose_stiffness(const SceneConfig& scene, Mode mode, const Geometry& geometry) {
  Stiffness s;
  s.k_n = scene.material.k_n;
  const StiffnessConfig& c = scene.stiffness;
  if (!c.from_load) return s;
  s.from_load = true;
  const MaterialConfig& m = scene.material;
  const Real d = m.diameter;
  const Real g = norm(scene.simulation.gravity);

  s.depth = mode == Mode::Dem
                ? c.dem_depth.value_or(largest_heap(scene).height)
                : c.surface_depth.value_or(rolling_min(scene) + interface_thickness(scene) + 2 * d);
  // one contact carries the weight of the column of cross-section d^2 above it
  s.k_static = kHeapPacking * m.density * g * s.depth * d / c.max_overlap;

  if (c.impact_speed) {
    s.impact_speed = *c.impact_speed;
  } else {
    for (const EmitterConfig& e : scene.emitters) {
      const Real z = e.center.z + (e.type == EmitterType::Pour ? 0 : e.size.z / 2);
      const Real fall = std::max(z - geometry.top_below(e.center.x, e.center.y, z, z - 1e3), 0.0);
      s.impact_speed = std::max(s.impact_speed, std::sqrt(norm2(e.velocity) + 2 * g * fall));
    }
  }
  // head-on impact of two mean grains: largest overlap v sqrt(m_eff / k_n)
  const Real mass = m.density * kPi / 6 * d * d * d;
  const Real overlap = c.impact_overlap * d;
  s.k_impact = 0.5 * mass * s.impact_speed * s.impact_speed / (overlap * overlap);
  s.k_n = std::max(s.k_static, s.k_impact);
  return s;
}

}  // namespace sandflow
