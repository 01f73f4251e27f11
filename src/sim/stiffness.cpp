#include "sim/stiffness.hpp"

#include <algorithm>
#include <cmath>
#include <optional>

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

  // k_impact = m_eff v^2 / (eps_i d)^2: the undamped largest overlap of an impact at v is
  // v sqrt(m_eff / k_n). A pour's grains arrive one at a time and meet a grain like them: m_eff =
  // m/2. A block or a lattice lands as a body: the grains behind keep pushing and the front
  // contact takes the strain of the compression wave, v sqrt(m / k_n) (the momentum flux (m/d) c v
  // at the wave speed c = d sqrt(k_n/m) held by one spring), m_eff = m.
  const Real mass = m.density * kPi / 6 * d * d * d;
  const Real overlap = c.impact_overlap * d;
  s.impact_mass_ratio = 0.5;
  s.impact_speed = c.impact_speed.value_or(0);
  for (const EmitterConfig& e : scene.emitters) {
    Real speed = 0;
    if (c.impact_speed) {
      speed = *c.impact_speed;
    } else {
      // the fall to the lower of the ground under the emitter and where its throw comes down (a
      // jet off a ledge lands on the floor below it)
      const Real z = e.center.z + (e.type == EmitterType::Pour ? 0 : e.size.z / 2);
      Real ground = geometry.top_below(e.center.x, e.center.y, z, z - 1e3);
      if (const std::optional<Vec3> landing = throw_landing(scene, e, geometry))
        ground = std::min(ground, landing->z);
      const Real fall = std::max(z - ground, 0.0);
      speed = std::sqrt(norm2(e.velocity) + 2 * g * fall);
    }
    const bool body = e.type == EmitterType::Block || e.type == EmitterType::Lattice;
    const Real ratio = body ? 1.0 : 0.5;
    if (ratio * speed * speed > s.impact_mass_ratio * s.impact_speed * s.impact_speed) {
      s.impact_mass_ratio = ratio;
      s.impact_speed = speed;
    }
  }
  s.k_impact = s.impact_mass_ratio * mass * s.impact_speed * s.impact_speed / (overlap * overlap);
  s.k_n = std::max(s.k_static, s.k_impact);
  return s;
}

}  // namespace sandflow
