// One frame of visible grains, as written to frames/NNNN.ply and read back by `sandflow measure`.
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
