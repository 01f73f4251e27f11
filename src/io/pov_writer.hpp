// POV-Ray 3.7 scenes of a frame, and a thin wrapper that renders them with the `povray` program.
//
// The simulator's world is right-handed with z up; POV-Ray is left-handed with y up. Rather than
// transforming every coordinate, the scene keeps world coordinates and sets the camera up as
//     right -x*W/H  up y  sky z  look_at ...
// POV-Ray derives the camera's handedness from the sign of (up x direction) . right before
// look_at re-aims it; the negated right vector makes screen-right = forward x z, the right-handed
// convention, so pictures are not mirrored (tests/io/test_pov_writer.cpp checks this with a
// grain placed to the right of the camera). Rotations are written as explicit `matrix` transforms
// built with rotation_xyz_deg(), the same function the collision geometry uses, so what is drawn
// is what the grains hit.
//
// Grains are one short line each, `G(x,y,z,r,c)`, a macro that draws a sphere with one of 8 sand
// textures (c, chosen from a hash of the grain id: a small, stable colour variation that does not
// flicker between frames). Geometry: planes are drawn as infinite floors with a faint checker
// (glass planes as a thin finite slab); boxes and cylinders as solids or, for containers, as
// walls of wall_thickness around the inner size, centred on `center`, without a lid when
// open_top; spheres as spheres. RenderStyle::Glass draws clear glass, Hidden draws nothing.
// Lighting is a soft key light (a 3x3 adaptive area light), a shadowless fill light and a little
// ambient light, with a pale sky behind.
#pragma once

#include <string>
#include <vector>

#include "core/vec3.hpp"
#include "geometry/mesh.hpp"
#include "io/frame.hpp"
#include "scene/scene_config.hpp"

namespace sandflow {

struct PovOptions {
  int width = 1280;  ///< image size [pixels]
  int height = 720;
  bool auto_camera = true;  ///< frame the grains from a 3/4 view; false: use the two below
  Vec3 camera_position;     ///< [m], when auto_camera is false
  Vec3 camera_look_at;      ///< [m], when auto_camera is false
  double fov_deg = 40;      ///< horizontal field of view [deg] (POV-Ray's `angle`)
};

/// Writes a self-contained POV-Ray 3.7 scene of frame `f` with its `geometry` to `path`
/// (atomically: a temporary file renamed over `path`). Throws OutputError naming the path;
/// std::invalid_argument if f.radius (or a non-empty f.id) does not match f.position in length.
/// `meshes`, when given, holds one entry per geometry entry: the placed mesh of a mesh entry
/// (drawn as a mesh2), nullptr for the others; a mesh entry without one is not drawn.
void write_pov_scene(const std::string& path, const FrameData& f,
                     const std::vector<GeometryConfig>& geometry, const PovOptions& opt,
                     const std::vector<const TriangleMesh*>& meshes = {});

/// Full path of the `povray` executable found on PATH, or "" when there is none.
std::string find_povray();

/// Renders `pov_path` to `png_path` (width x height, antialiased, `threads` render threads; 0 or
/// less lets POV-Ray decide). POV-Ray's output goes to png_path + ".log". The PNG appears only
/// when the render succeeded. Throws OutputError with the end of the log when povray is missing,
/// fails, or leaves no image.
void render_pov(const std::string& pov_path, const std::string& png_path, int width, int height,
                int threads);

/// The grains of frame `f` exactly as write_pov_scene draws them, one `G(x,y,z,r,c)` line each:
/// the body of a frame file that #includes the rest (camera, lights, the macro G, the geometry)
/// from a scene written once by write_pov_scene with no grains (`--export pov`).
std::string pov_grain_lines(const FrameData& f);

}  // namespace sandflow
