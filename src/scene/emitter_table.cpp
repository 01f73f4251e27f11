// The reader of one [[emitter]] entry (scene_tables.hpp): its common keys, then only the keys of
// its type (and of a pour's shape), so that finish() refuses a key of another type.

#include <string>

#include "scene/scene_tables.hpp"
#include "sim/emitters.hpp"

namespace sandflow::loader {
namespace {

constexpr Choices<EmitterType> kEmitterTypes[] = {{"pour", EmitterType::Pour},
                                                  {"block", EmitterType::Block},
                                                  {"lattice", EmitterType::Lattice},
                                                  {"bed", EmitterType::Bed}};
constexpr Choices<PourShape> kPourShapes[] = {{"disk", PourShape::Disk}, {"rect", PourShape::Rect}};
constexpr Choices<PourFacing> kPourFacings[] = {{"up", PourFacing::Up},
                                                {"velocity", PourFacing::Velocity}};

}  // namespace

EmitterConfig read_emitter(TableReader r, std::size_t index, const MaterialConfig& material) {
  EmitterConfig e;
  e.name = "emitter " + std::to_string(index);
  r.read("type", e.type, kEmitterTypes);
  r.read_name("name", e.name);
  if (e.type == EmitterType::Bed) {
    // (its count is its packing's: scene_loader.cpp packs it once the geometry is read)
    if (r.has("count"))
      r.fail_at("count", r.name("count") +
                             " is not a key of a bed: the grains a bed holds follow from its "
                             "region (center, size, height and the geometry under it)");
    r.read("start", e.start, kNonNegative);
    r.read("center", e.center, kAny, 2);   // x, y; z is not used
    r.read("size", e.size, kPositive, 2);  // x, y extents of the footprint; z is not used
    r.require("height", "the bed's flat top, z in metres");
    r.read("height", e.height);
    r.read("relief", e.relief, kNonNegative);
    r.read("relief_wavelength", e.relief_wavelength, kPositive);
    r.read("relief_seed", e.relief_seed, kNonNegative);
    r.finish("a bed emitter");
    if (const auto problem = emitter_problem(e, material))
      r.fail_at(problem->key, r.name(problem->key) + " " + problem->what);
    return e;
  }
  r.require("count", "the number of grains to emit, an integer >= 1");
  r.read("count", e.count, closed(1, static_cast<Real>(kMaxGrains)));
  r.read("start", e.start, kNonNegative);
  r.read("velocity", e.velocity);
  r.read("jitter", e.jitter, closed(0, 1));
  r.read("spacing", e.spacing, Range{1, kInf});
  r.read("center", e.center);

  // Only the keys of this type (and pour shape) are read; finish() refuses the others.
  switch (e.type) {
    case EmitterType::Pour:
      r.read("shape", e.shape, kPourShapes);
      r.read("facing", e.facing, kPourFacings);
      if (e.facing == PourFacing::Velocity && norm(e.velocity) <= 0)
        r.fail_at("facing", r.name("facing") +
                                " = \"velocity\" lays the area across the velocity, but velocity "
                                "is zero: give the throw's velocity, or leave the area facing up");
      r.read("rate", e.rate, kPositive);
      if (e.shape == PourShape::Disk) {
        r.read("radius", e.radius, kPositive);
        r.finish("a pour with shape = \"disk\"");
      } else {
        r.read("size", e.size, kPositive, 2);  // x, y extents; z is not used
        r.finish("a pour with shape = \"rect\"");
      }
      break;
    case EmitterType::Block:
      r.read("size", e.size, kPositive);
      r.finish("a block emitter");
      break;
    case EmitterType::Lattice:
      r.read("size", e.size, kPositive);
      r.finish("a lattice emitter");
      break;
    case EmitterType::Bed:  // (read above)
      break;
  }
  // sizes that no count makes possible, refused before anything of their size is made
  if (const auto problem = emitter_problem(e, material))
    r.fail_at(problem->key, r.name(problem->key) + " " + problem->what);
  return e;
}

}  // namespace sandflow::loader
