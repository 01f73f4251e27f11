// Where an emitter's region lies: a pour's area (level, or across its velocity for a nozzle) and
// the box around any emitter's region, for the layers that frame, grid or bound what an emitter
// makes. Worked out from the EmitterConfig alone, so every layer above sees the same region.
#pragma once

#include <algorithm>
#include <cmath>

#include "config/scene_config.hpp"

namespace sandflow {

/// The directions a pour's area spans: `along` carries its first extent (a disk's, or a
/// rectangle's size.x), `across` its second (size.y). A level area spans x and y; one facing its
/// velocity n spans the horizontal direction n x z and, upwards across n, (n x z) x n (x and y
/// again for a pour thrown straight down).
struct PourAxes {
  Vec3 along{1, 0, 0}, across{0, 1, 0};
};

inline PourAxes pour_axes(const EmitterConfig& e) {
  const Real speed = norm(e.velocity);
  if (e.type != EmitterType::Pour || e.facing == PourFacing::Up || speed <= 0) return {};
  const Vec3 n = e.velocity / speed;
  const Vec3 side = cross(n, Vec3{0, 0, 1});
  const Real side_len = norm(side);
  // (thrown along z, n x z vanishes: the level axes then)
  if (side_len < 1e-12) return {{1, 0, 0}, cross(Vec3{1, 0, 0}, n) * (n.z < 0 ? 1.0 : -1.0)};
  const Vec3 along = side / side_len;
  return {along, cross(along, n)};
}

/// Half extents of the axis-aligned box around an emitter's region (about its center): a pour's
/// area, one layer of slots (no depth), a block's, lattice's or bed's box (a bed: its footprint,
/// z from its packing).
inline Vec3 emitter_half_extent(const EmitterConfig& e) {
  if (e.type != EmitterType::Pour) return e.size * 0.5;
  const bool disk = e.shape == PourShape::Disk;
  const Real a = disk ? e.radius : e.size.x / 2, b = disk ? e.radius : e.size.y / 2;
  const PourAxes axes = pour_axes(e);
  if (disk) {  // a circle's extent along a unit axis k: r sqrt(1 - n_k^2), n its normal
    const Vec3 n = cross(axes.along, axes.across);
    return {a * std::sqrt(std::max(0.0, 1 - n.x * n.x)),
            a * std::sqrt(std::max(0.0, 1 - n.y * n.y)),
            a * std::sqrt(std::max(0.0, 1 - n.z * n.z))};
  }
  return {a * std::abs(axes.along.x) + b * std::abs(axes.across.x),
          a * std::abs(axes.along.y) + b * std::abs(axes.across.y),
          a * std::abs(axes.along.z) + b * std::abs(axes.across.z)};
}

}  // namespace sandflow
