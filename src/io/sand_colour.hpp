// The colour of each grain in the pictures and the exports: the POV-Ray frames' textures and the
// Houdini frames' Cd are the same colours, so a grain looks alike in `sandflow render` and in
// Houdini. Sand is not one colour: each grain gets one of kSandShades shades of dry quartz sand,
// chosen by a hash of its id, so a grain keeps its shade in every frame (no flicker) and
// neighbours differ.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "core/vec3.hpp"

namespace sandflow {

constexpr int kSandShades = 8;

/// The shade of grain `id`, in [0, kSandShades): a 32-bit integer hash (lowbias32) of the id.
constexpr int sand_shade(std::uint32_t id) {
  std::uint32_t x = id;
  x ^= x >> 16;
  x *= 0x7feb352dU;
  x ^= x >> 15;
  x *= 0x846ca68bU;
  x ^= x >> 16;
  return static_cast<int>(x % kSandShades);
}

/// Shade k as sRGB-encoded red, green, blue in [0, 1]: a brightness from 0.88 to 1.12 times
/// (0.76, 0.62, 0.40), with a slight warm or cool shift.
inline Vec3 sand_srgb(int shade) {
  const double light = 0.88 + 0.24 * shade / (kSandShades - 1);
  const double warm = (shade % 3 - 1) * 0.025;
  return {std::min(1.0, 0.76 * light + warm), std::min(1.0, 0.62 * light),
          std::min(1.0, 0.40 * light - warm)};
}

/// An sRGB-encoded colour as linear light (IEC 61966-2-1), what renderers and Houdini's Cd hold.
inline Vec3 srgb_to_linear(const Vec3& c) {
  const auto channel = [](double v) {
    return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4);
  };
  return {channel(c.x), channel(c.y), channel(c.z)};
}

}  // namespace sandflow
