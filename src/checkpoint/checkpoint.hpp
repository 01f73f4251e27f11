// Checkpoints: the whole state of a run at a frame boundary, so that a resumed run ends with
// exactly the state hash of the same run uninterrupted (docs/checkpoints.md).
//
// A checkpoint is a little-endian binary file:
//
//   header   "SANDCKPT", format version (u32), header length (u32), the sandflow version that
//            wrote it, the hash of the resolved scene, frame and step, then the table of sections
//            (tag, byte size), the CRC-32 of the payload and the CRC-32 of the header itself;
//   payload  the sections in a fixed order: RUN (the statistics of every frame so far), WRLD
//            (counters, random state, emitters' progress, stage timings), GRNS (hot grains in
//            their storage order), STAT (static grains as their store packs them, slot for slot),
//            DEM (neighbour, wall and boundary lists with their contact history, reference
//            positions, allowances, rebuild counters) and SURF (height-field columns and the
//            interface's memory).
//
// Every value is named and written field by field (no raw structs, no padding). The reader takes
// bytes and trusts none of them: every count is checked against the bytes left in its section
// before anything is allocated, every real must be finite, and a checkpoint that parses is then
// checked against the World it is restored into (indices in range, lists well formed) before
// anything is touched, so that truncated, corrupt or hostile input gives an InputError, never a
// crash. Adding a field to FrameStats or to a class's saved state means adding it here and
// raising kCheckpointFormat.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "sim/world.hpp"

namespace sandflow {

/// 4: the stage timings are those of the eight stages of World::step (core/timer.hpp), not five.
/// 5: STAT holds the static store's compact form (12 bytes a grain), not doubles; the height
///    field keeps each column's time at rest (closed columns).
/// 6: SURF holds the blows under way and the grains they counted (surface.blows).
/// 7: the height field keeps how much longer each column holds a stopped flow's layer
///    (surface.flowing_hold).
/// 8: each emitter's progress counts the grains a block, lattice or bed left out (their places
///    were taken).
constexpr std::uint32_t kCheckpointFormat = 8;

struct Checkpoint {
  std::uint32_t format = kCheckpointFormat;
  std::string sandflow_version = SANDFLOW_VERSION;
  std::uint64_t scene_hash = 0;    ///< scene_hash() of the run that wrote it
  WorldState world;                ///< world.frame and world.step are in the header
  std::vector<FrameStats> frames;  ///< statistics of frames 1..world.frame, as the run wrote them
};

/// The bytes of a checkpoint. Throws SimulationError when the state holds a non-finite value
/// (the guards stop a run before that; such a checkpoint could not be read back).
std::string encode_checkpoint(const Checkpoint& c);

/// Parses checkpoint bytes; `name` (the file) prefixes every message. Checks the magic, the format
/// version, both checksums, the section table and every count; it does not check the state
/// against a scene (restore_checkpoint does). Throws InputError.
Checkpoint parse_checkpoint(std::string_view bytes, const std::string& name);

/// Hash of the resolved scene of a run: `start_record` (how the run was started: the scene text,
/// its overrides and options) and what the World made of it (time step, stiffness, boundary
/// particles, heightmaps, the height field's grid), so that a mesh or image file that changed
/// since is caught too.
std::uint64_t scene_hash(const World& world, std::string_view start_record);

/// Restores `c` into `world`, a World freshly built from the same scene. Refuses (InputError
/// naming `name`) a checkpoint written by another sandflow version, of another scene (hash other
/// than `expected_hash`), or whose state does not fit this world; `world` is untouched then.
void restore_checkpoint(World& world, Checkpoint c, std::uint64_t expected_hash,
                        const std::string& name);

/// Reads and parses a checkpoint file (InputError when it cannot be read or is malformed).
Checkpoint read_checkpoint(const std::string& path);

}  // namespace sandflow
