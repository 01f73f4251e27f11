// Scenes that tests build in code: a grain material on a floor, and a pour above it. Each test
// then changes only what it studies, so what differs between two tests is what they test.
#pragma once

#include <cstdint>
#include <string>

#include "config/scene_config.hpp"

namespace sandflow::test {

/// A horizontal plane at height z: the floor.
inline GeometryConfig floor_plane(Real z = 0) {
  GeometryConfig g;
  g.type = GeometryType::Plane;
  g.point = {0, 0, z};
  return g;
}

inline GeometryConfig box_entry(const Vec3& center, const Vec3& size) {
  GeometryConfig g;
  g.type = GeometryType::Box;
  g.center = center;
  g.size = size;
  return g;
}

/// `count` grains poured at `rate` per second from a disk of `radius` at `center`, at `velocity`.
inline EmitterConfig disk_pour(const Vec3& center, Real radius, Real rate, std::int64_t count,
                               const Vec3& velocity) {
  EmitterConfig e;
  e.type = EmitterType::Pour;
  e.center = center;
  e.radius = radius;
  e.rate = rate;
  e.count = count;
  e.velocity = velocity;
  return e;
}

/// Grains of `diameter` (10 % spread, k_n = 1e4 N/m, the default friction) on a floor, 30 fps,
/// no emitter yet.
inline SceneConfig grains_on_floor(const std::string& name, Mode mode, Real diameter) {
  SceneConfig s;
  s.path = "test";
  s.name = name;
  s.simulation.mode = mode;
  s.material.diameter = diameter;
  s.material.diameter_spread = 0.1;
  s.material.k_n = 1e4;
  s.output.fps = 30;
  s.geometry = {floor_plane()};
  return s;
}

}  // namespace sandflow::test
