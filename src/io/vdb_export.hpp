// The OpenVDB frame (`--export vdb`): DIR/frames/NNNN.vdb, for the VDB nodes of Houdini and
// Blender. This header is light on purpose: OpenVDB's own headers (templates, TBB, Boost) are
// included by vdb_export.cpp alone, the one translation unit of the build that pays for them.
//
// A frame holds two grids:
// - "grains", a PointDataGrid of the visible grains (ACTIVE and INTERFACE) with the attributes P,
//   pscale (the radius, float), v (velocity, vec3f), id (int64, so that every uint32 id fits) and
//   state (int8: 0 ACTIVE, 1 INTERFACE). P is stored as a 16-bit offset from its voxel's centre,
//   the default of Houdini's Convert VDB Points: OpenVDB truncates it to a step of 2^-16 of a
//   voxel, 0.3 um for 1 cm grains.
//   Its voxel is 2 mean diameters: a packed heap (solid fraction 0.6) then holds 9.2 grains a
//   voxel, near the 8 points a voxel that OpenVDB's and Houdini's point conversion aim at by
//   default; a fixed size (rather than points::computeVoxelSize, frame by frame) keeps every
//   frame's quantisation the same and costs nothing.
// - "surface", a narrow-band level set (GRID_LEVEL_SET, 3 voxels each side, negative inside,
//   stored as 16-bit floats) of the whole sand: the union of the grains as spheres
//   (tools::ParticlesToLevelSet) and, in surface mode, the static layer, the region between the
//   terrain level L and the static top h of the height field. Its voxel is output.vdb_voxel_size,
//   by default a third of the smallest grain diameter, so that every grain's radius spans the 1.5
//   voxels below which OpenVDB leaves a particle out (its Nyquist limit). A coarser voxel chosen
//   by the user keeps every grain: the small ones are then drawn coarsely rather than dropped.
//   The static layer's distance is built column by column: where h and L are smooth, bilinear
//   between column centres as the height-field OBJ meshes draw them, the distance to their
//   planes, (z - h) cos(slope of h) and (L - z) cos(slope of L); across a step of the terrain (a
//   wall), where there is no sand and outside the grid, each column is a box from L to h. That is
//   exact for a plane and a box; near kinks and at the heap's rim it is an estimate whose sign,
//   the surface, is exact.
//
// Both grids carry the metadata time [s], frame, scene, units "m" and up_axis, and the file
// carries them too. With up axis y, positions, velocities and the level set are in the exported
// frame (x, z, -y) of export_formats.hpp, so that Houdini and Blender see the sand as in the other
// exports; the transforms stay axis-aligned (voxel size only).
#pragma once

#include <string>
#include <string_view>

#include "config/scene_config.hpp"
#include "dem/frame.hpp"
#include "surface/height_field.hpp"

namespace sandflow {

inline constexpr std::string_view kVdbGrainsGrid = "grains";
inline constexpr std::string_view kVdbSurfaceGrid = "surface";
/// Half width of the level set's narrow band, each side of the surface [voxels].
inline constexpr int kVdbHalfWidth = 3;

/// How a frame is written and what it says about itself.
struct VdbFrameInfo {
  std::string scene;  ///< the scene's name
  int frame = 0;      ///< frame number
  double time = 0;    ///< simulated time [s]
  UpAxis up = UpAxis::Z;
  Real points_voxel = 0.02;    ///< voxel of the "grains" grid [m]
  Real surface_voxel = 0.003;  ///< voxel of the "surface" level set [m]
};

/// The voxel of the points grid: 2 mean diameters (see above) [m].
Real vdb_points_voxel(const MaterialConfig& m);
/// The voxel of the level set: output.vdb_voxel_size, else a third of the smallest diameter [m].
Real vdb_surface_voxel(const SceneConfig& scene);

/// Writes one frame's .vdb atomically (as every export: PATH.tmp renamed over PATH): the grains of
/// `f` (velocity, id and state may be empty: 0, the index, 0) and, when `static_layer` is given,
/// its static layer in the level set. Throws OutputError naming the path.
void write_vdb(const std::string& path, const FrameData& f, const HeightField* static_layer,
               const VdbFrameInfo& info);

}  // namespace sandflow
