// The parameters of the height field and the interface, with the defaults of docs/scenes.md
// derived from the grain size and the material where the scene leaves them unset.
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "config/scene_config.hpp"
#include "geometry/shapes.hpp"
#include "surface/height_field.hpp"
#include "surface/interface_layer.hpp"

namespace sandflow {

/// The most columns a height field may have (16 M: 1.7 GiB per field); the scene loader refuses a
/// surface.extent that needs more, surface_params() a domain from the geometry that does.
constexpr std::size_t kMaxHeightFieldColumns = 16u << 20;

/// Random packing fraction of a heap, for the volume the grains of a scene take.
constexpr Real kHeapPacking = 0.6;

struct SurfaceParams {
  HeightFieldParams grid;
  InterfaceParams interface;
  int update_steps = 1;      ///< DEM steps between height-field updates
  Real update_interval = 0;  ///< update_steps * dt [s]
  Real z_top = 1, z_floor = -1;  ///< vertical span searched for the terrain [m]
};

/// R_min [m], R_min under a flowing layer [m] and T [m] of a scene (defaults: d, 4 d and d/2).
Real rolling_min(const SceneConfig& scene);
Real flowing_min(const SceneConfig& scene);
Real interface_thickness(const SceneConfig& scene);

/// Height [m] and base radius [m] of the cone that holds every grain of the scene at theta_0
/// (packing fraction 0.6): the scale of the largest heap the scene can make. A bed's grains lie
/// in its footprint, not in the cone: they add the highest bed's top (above z = 0) to the height.
struct HeapSize {
  Real height, radius;
};
HeapSize largest_heap(const SceneConfig& scene);

/// Where an emitter's throw comes down on the ground (a jet, a pour or a block thrown sideways):
/// from its centre, on the free fall of its velocity, to the solid top below where it lands.
/// Nothing for a bed, for a throw straight up or down, under gravity not along -z, or where no
/// ground lies below.
std::optional<Vec3> throw_landing(const SceneConfig& scene, const EmitterConfig& e,
                                  const Geometry& geometry);

/// Every parameter, resolved for a run with time step dt.
SurfaceParams surface_params(const SceneConfig& scene, const Geometry& geometry, Real dt);

/// Most questions (a solid's stretches along a line) tracing a height field's columns may ask:
/// 2^33, reached in 35 s by 31 stacked container boxes (186 slabs) over the largest field (16.8
/// million columns); 64 planes over it ask 1.1e9 in 7 s, one floor 1.7e7. More means many solids
/// under a fine, wide field.
constexpr std::uint64_t kMaxTerrainQueries = std::uint64_t{1} << 33;

/// Most vertical lines looked down on an edge between two column centres for a wall standing
/// between them (a container wall thinner than a column): a solid thinner than 1/32 of a column
/// may fall between them.
constexpr int kMaxWallLines = 63;

/// The solids under each column centre (a solid at z_floor where there is none), and the walls
/// between columns. InputError when tracing them asks the solids more than `budget` times.
TerrainColumns terrain_columns(const SurfaceParams& p, const Geometry& geometry,
                               std::uint64_t budget = kMaxTerrainQueries);

}  // namespace sandflow
