// One frame of grains as plain arrays: what the World hands out (all grains, or the visible ones)
// and what frames/NNNN.ply holds, written and read back (`sandflow measure`) by io/. It sits with
// the grains, below both, so that the World needs nothing from io/ to produce it.
#pragma once

#include <cstdint>
#include <vector>

#include "core/vec3.hpp"

namespace sandflow {

struct FrameData {
  std::vector<Vec3> position;        ///< grain centres [m]
  std::vector<Real> radius;          ///< [m]
  std::vector<Vec3> velocity;        ///< [m/s]
  std::vector<std::uint32_t> id;     ///< stable grain ids
  std::vector<std::uint8_t> state;   ///< GrainState: 0 ACTIVE, 1 INTERFACE, 2 STATIC

  std::size_t size() const { return position.size(); }
};

}  // namespace sandflow
