// POV-Ray 3.7 scenes of a frame, and a thin wrapper that renders them with the `povray` program.
//
// The simulator's world is right-handed with z up; POV-Ray is left-handed with y up. Rather than
// transforming every coordinate, the scene keeps world coordinates and sets the camera up as
//     right -x*W/H  up y  sky z  look_at ...     (sky: the [camera] table's up, z by default)
// POV-Ray derives the camera's handedness from the sign of (up x direction) . right before
// look_at re-aims it; the negated right vector makes screen-right = forward x z, the right-handed
// convention, so pictures are not mirrored (tests/io/test_pov_writer.cpp checks this with a
// grain placed to the right of the camera). Rotations are written as explicit `matrix` transforms
// built with rotation_xyz_deg(), the same function the collision geometry uses, so what is drawn
// is what the grains hit.
//
// Grains are spheres gathered in one union per sand texture (8 shades; a grain's shade comes
// from a hash of its id: a small, stable colour variation that does not flicker between frames),
// which POV-Ray reads faster and holds in less memory than a texture a sphere. Geometry: planes are
// drawn as infinite floors with a faint checker (glass planes as a thin finite slab); boxes and
// cylinders as solids or, for containers, as walls of wall_thickness around the inner size, centred
// on `center`, without a lid when open_top; spheres as spheres; a bowl as its shell below the rim;
// heightmaps and meshes as mesh2 triangles; a surface-mode frame's static layer (SandSurface) as a
// smooth mesh2 in a sand texture with a grain-sized grain. RenderStyle::Glass draws clear glass,
// Hidden draws nothing. A scene without a solid plane gets a floor under its lowest point, for
// looks only (unless the camera is below it). Lighting: for the final look a soft key light (a 3x3
// adaptive area light), a shadowless fill light and a little ambient light, with a pale sky behind;
// the draft look replaces the area light by a point light (faster, hard shadows).
//
// An animation must not jitter: everything sized from the scene's extent (the automatic camera,
// the lights, the floor's squares, a glass plane's slab) is sized from PovOptions::bounds when it
// is given. `sandflow render` passes the bounds of the whole run, so every frame of a run has the
// same camera and light.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "config/scene_config.hpp"
#include "core/vec3.hpp"
#include "dem/frame.hpp"
#include "geometry/mesh.hpp"

namespace sandflow {

/// An axis-aligned box around what a picture shows [m]; spheres widen it by their radius.
struct ViewBounds {
  Vec3 lo{0, 0, 0}, hi{0, 0, 0};
  bool empty = true;
  void add(const Vec3& p, Real r);
  void add(const ViewBounds& b);
  Vec3 centre() const { return (lo + hi) * 0.5; }
  Real radius() const;  ///< half the diagonal, at least 1e-6 [m]
};

/// The grains of a frame (non-finite positions skipped).
ViewBounds grain_bounds(const FrameData& f);
/// The box of a frame's grains without its strays: on each axis from the 0.5th to the 99.5th
/// percentile of the centres (all of them under 1,000 grains), widened by the largest radius. A
/// grain thrown far from the heap would otherwise set the camera's distance, and the heap come out
/// small in the picture.
ViewBounds grain_core_bounds(const FrameData& f);
/// The finite, visible geometry: meshes (as in write_pov_scene), spheres, boxes, cylinders,
/// bowls, heightmaps; planes are infinite and hidden geometry is not drawn, so neither counts.
ViewBounds geometry_bounds(const std::vector<GeometryConfig>& geometry,
                           const std::vector<const TriangleMesh*>& meshes = {});

struct PovOptions {
  int width = 1280;  ///< image size [pixels]
  int height = 720;
  bool auto_camera = true;  ///< frame the bounds from a 3/4 view; false: use the three below
  Vec3 camera_position;     ///< [m], when auto_camera is false
  Vec3 camera_look_at;      ///< [m], when auto_camera is false
  Vec3 camera_up{0, 0, 1};  ///< the picture's up direction (POV-Ray's `sky`), when not auto
  double fov_deg = 40;      ///< horizontal field of view [deg] (POV-Ray's `angle`)
  /// What the camera frames and the lights are placed around; unset: this frame's grains and
  /// the geometry. An empty box is taken as unset.
  ViewBounds bounds;
  bool soft_light = true;  ///< an area light (soft shadows); false: a point light (draft)
  bool floor = true;       ///< draw a floor under the scene when its geometry has no plane (and the
                           ///< camera is above it)
  /// The frame's time [s]: a solid removed before it (`remove_at`) is not drawn. The scene
  /// declares it as SandflowTime unless the file that includes it already has.
  double time = 0;
};

/// The automatic camera's position and look-at point for `bounds` (what write_pov_scene uses
/// when opt.auto_camera): from above at 35 degrees, a 3/4 view, just far enough for the whole
/// box to fit opt.fov_deg at opt.width x opt.height with a 10 % border.
std::pair<Vec3, Vec3> auto_camera(const ViewBounds& bounds, const PovOptions& opt);

/// Writes a self-contained POV-Ray 3.7 scene of frame `f` with its `geometry` to `path`
/// (atomically: a temporary file renamed over `path`). Throws OutputError naming the path;
/// std::invalid_argument if f.radius (or a non-empty f.id) does not match f.position in length.
/// `meshes`, when given, holds one entry per geometry entry: the placed mesh of a mesh entry
/// (drawn as a mesh2), nullptr for the others; a mesh entry without one is not drawn.
/// The static layer of a surface-mode frame, drawn as a smooth surface under the grains (its
/// grains are not in the frame): the top h of each column, row-major with x fastest, column (i, j)
/// centred at origin + ((i + 1/2) cell, (j + 1/2) cell), and whether the column holds sand. A cell
/// between four column centres is drawn when one of them holds sand, so the surface runs down to
/// the ground at the heap's edge.
struct SandSurface {
  Real origin_x = 0, origin_y = 0, cell = 0;
  int nx = 0, ny = 0;
  std::vector<Real> z;             ///< h per column [m]
  std::vector<std::uint8_t> sand;  ///< 1 where the column holds sand
  Real grain_diameter = 0;         ///< the scale of the texture's grain [m]
  bool empty() const { return nx < 2 || ny < 2; }
};

void write_pov_scene(const std::string& path, const FrameData& f,
                     const std::vector<GeometryConfig>& geometry, const PovOptions& opt,
                     const std::vector<const TriangleMesh*>& meshes = {},
                     const SandSurface* static_layer = nullptr);

/// The text write_pov_scene writes.
std::string pov_scene_text(const FrameData& f, const std::vector<GeometryConfig>& geometry,
                           const PovOptions& opt,
                           const std::vector<const TriangleMesh*>& meshes = {},
                           const SandSurface* static_layer = nullptr);

/// find_program("povray") (core/process.hpp).
std::string find_povray();

/// Renders `pov_path` to `png_path` (width x height, antialiased unless `antialias` is false,
/// `threads` render threads; 0 or less lets POV-Ray decide). POV-Ray's output goes to
/// png_path + ".log". The PNG appears only when the render succeeded and the picture is whole
/// (io/media_check.hpp). Throws OutputError with the end of the log when povray is missing, fails,
/// or leaves no whole picture, and with what the disk holds when it is full. Returns the most
/// memory POV-Ray held [bytes] (0 if unknown).
std::int64_t render_pov(const std::string& pov_path, const std::string& png_path, int width,
                        int height, int threads, bool antialias = true);

/// Encodes the images FOLDER/NNNN.png, frames first .. first + count - 1 (the names frame_path
/// gives), into the H.264 MP4 `mp4_path` (yuv420p, odd sizes padded to even) at `fps` frames per
/// second, with ffmpeg. Several folders (pictures of the same size) are put side by side, left
/// to right. ffmpeg's output goes to mp4_path + ".log"; the movie appears only when the encoding
/// succeeded and the movie is whole, `count` frames (io/media_check.hpp: ffmpeg can exit with
/// status 0 on a full disk). Throws OutputError naming the path (with the end of the log, and
/// what the disk holds when it is full) when ffmpeg is missing or fails.
void encode_movie(const std::vector<std::string>& folders, int first, int count, double fps,
                  const std::string& mp4_path);

/// The grains of frame `f` exactly as write_pov_scene draws them, one `G(x,y,z,r,c)` line each:
/// the body of a frame file that #includes the rest (camera, lights, the macro G, the geometry)
/// from a scene written once by write_pov_scene with no grains (`--export pov`).
std::string pov_grain_lines(const FrameData& f);

}  // namespace sandflow
