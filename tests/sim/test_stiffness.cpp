// k_n from the load a contact carries (docs/design.md §3), per mode.
#include <gtest/gtest.h>

#include <cmath>

#include "sim/stiffness.hpp"
#include "support/test_scenes.hpp"
#include "surface/surface_params.hpp"

namespace sandflow {
namespace {

SceneConfig pour_scene(Real height, Real speed) {
  SceneConfig s;
  s.path = "stiffness";
  s.material.diameter = 0.01;
  s.material.density = 2600;
  s.geometry = {test::floor_plane()};
  EmitterConfig e;
  e.type = EmitterType::Pour;
  e.center = {0, 0, height};
  e.velocity = {0, 0, -speed};
  e.count = 100000;
  s.emitters = {e};
  s.stiffness.from_load = true;
  return s;
}

TEST(Stiffness, GivenKnWhenNotFromLoad) {
  SceneConfig s = pour_scene(0.6, 2);
  s.stiffness.from_load = false;
  s.material.k_n = 1234;
  const Geometry g = Geometry::from_config(s.geometry, s.material);
  EXPECT_EQ(choose_stiffness(s, Mode::Dem, g).k_n, 1234);
  EXPECT_EQ(choose_stiffness(s, Mode::Surface, g).k_n, 1234);
}

TEST(Stiffness, ImpactSpeedFromTheFallAndTheFormulas) {
  SceneConfig s = pour_scene(0.6, 2);
  const Geometry g = Geometry::from_config(s.geometry, s.material);
  const Stiffness dem = choose_stiffness(s, Mode::Dem, g);
  // free fall from 0.6 m starting at 2 m/s
  EXPECT_NEAR(dem.impact_speed, std::sqrt(4 + 2 * 9.81 * 0.6), 1e-6);
  const Real mass = 2600 * kPi / 6 * 1e-6;
  EXPECT_NEAR(dem.k_impact, 0.5 * mass * dem.impact_speed * dem.impact_speed / (1e-3 * 1e-3),
              1e-6 * dem.k_impact);
  EXPECT_EQ(dem.impact_mass_ratio, 0.5);  // a pour's grain meets one like it
  EXPECT_NEAR(dem.depth, largest_heap(s).height, 1e-12);
  EXPECT_NEAR(dem.k_static, 0.6 * 2600 * 9.81 * dem.depth * 0.01 / 0.01, 1e-9 * dem.k_static);
  EXPECT_EQ(dem.k_n, std::max(dem.k_static, dem.k_impact));
}

TEST(Stiffness, SurfaceModeIsSofterWhereTheStaticLoadDominates) {
  // a gentle pour (low, slow) onto what becomes a tall heap: the weight of the pile decides in
  // DEM, the thin active layer in surface mode
  SceneConfig s = pour_scene(0.02, 0.1);
  s.stiffness.impact_speed = 0.5;
  const Geometry g = Geometry::from_config(s.geometry, s.material);
  const Stiffness dem = choose_stiffness(s, Mode::Dem, g), surf = choose_stiffness(s, Mode::Surface, g);
  EXPECT_GT(dem.k_static, dem.k_impact);
  EXPECT_LT(surf.k_n, dem.k_n);
  EXPECT_NEAR(surf.depth, 0.01 + 0.005 + 0.02, 1e-12);  // R_min + T + 2 d (T = d/2)
  // impacts bound both modes alike
  SceneConfig fast = pour_scene(0.6, 2);
  const Stiffness fd = choose_stiffness(fast, Mode::Dem, g), fs = choose_stiffness(fast, Mode::Surface, g);
  EXPECT_EQ(fd.k_n, fs.k_n);
}

TEST(Stiffness, ALandingBodyIsSizedForTheGrainAgainstWhatDoesNotRecoil) {
  // A block lands as a body: the grains behind keep pushing, so its front contact takes the
  // compression wave's strain v sqrt(m/k), as a grain against a wall (m_eff = m), where a pour's
  // grain meets one of its own (m_eff = m/2): twice the k_n at the same speed.
  SceneConfig pour = pour_scene(0.6, 2);
  pour.stiffness.impact_speed = 3.0;
  SceneConfig block = pour;
  block.emitters[0].type = EmitterType::Block;
  block.emitters[0].size = {0.1, 0.1, 0.1};
  const Geometry g = Geometry::from_config(pour.geometry, pour.material);
  const Stiffness p = choose_stiffness(pour, Mode::Surface, g);
  const Stiffness b = choose_stiffness(block, Mode::Surface, g);
  const Real mass = 2600 * kPi / 6 * 1e-6;
  const Real overlap = 0.1 * 0.01;  // the default impact_overlap of a 1 cm grain
  EXPECT_EQ(b.impact_mass_ratio, 1.0);
  EXPECT_NEAR(b.k_impact, mass * 9.0 / (overlap * overlap), 1e-9 * b.k_impact);
  EXPECT_NEAR(b.k_impact, 2 * p.k_impact, 1e-9 * b.k_impact);
  block.emitters[0].type = EmitterType::Lattice;
  EXPECT_EQ(choose_stiffness(block, Mode::Surface, g).k_impact, b.k_impact);

  // a pour and a block in one scene: the impact that needs the stiffer spring decides, even
  // when the pour is the faster (m_eff v^2 / m: 2.5^2 / 2 = 3.1 for the pour, 2.44^2 = 6.0 for
  // the block)
  SceneConfig both = pour_scene(0.6, 2);
  EmitterConfig slow = both.emitters[0];
  slow.type = EmitterType::Block;
  slow.size = {0.1, 0.1, 0.1};
  slow.center = {1, 0, 0.05};  // its top 0.1 m over the floor: it falls 0.1 m
  slow.velocity = {0, 0, -2.0};
  both.emitters[0].center = {0, 0, 0};  // the pour at the floor: its own speed only
  both.emitters[0].velocity = {0, 0, -2.5};
  both.emitters.push_back(slow);
  const Stiffness s = choose_stiffness(both, Mode::Surface, g);
  EXPECT_EQ(s.impact_mass_ratio, 1.0);
  EXPECT_NEAR(s.impact_speed, std::sqrt(4 + 2 * 9.81 * 0.1), 1e-9);
}

TEST(Stiffness, AThrowOffALedgeIsSizedForItsFallToWhereItLands) {
  // a jet 0.5 m up over a shelf whose top is 0.4 m high, thrown level at 2 m/s: it clears the
  // shelf's edge (0.1 m away) before it has fallen 0.1 m and lands on the floor, 0.5 m down
  SceneConfig s = pour_scene(0.5, 0);
  s.emitters[0].velocity = {2, 0, 0};
  s.geometry.push_back(test::box_entry({0, 0, 0.2}, {0.2, 0.4, 0.4}));
  const Geometry g = Geometry::from_config(s.geometry, s.material);
  EXPECT_NEAR(choose_stiffness(s, Mode::Surface, g).impact_speed, std::sqrt(4 + 2 * 9.81 * 0.5),
              1e-9);
  // thrown slowly it comes down on the shelf: the fall under the nozzle decides
  s.emitters[0].velocity = {0.2, 0, 0};
  EXPECT_NEAR(choose_stiffness(s, Mode::Surface, g).impact_speed, std::sqrt(0.04 + 2 * 9.81 * 0.1),
              1e-9);
}

}  // namespace
}  // namespace sandflow
