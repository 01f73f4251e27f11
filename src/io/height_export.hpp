// The height field of a surface-mode run as files: a 16-bit grey PNG of one height per column
// (H, the top of the sand, or h, the top of the static layer), an OBJ mesh through the column
// centres, and the sidecar JSON that says how to turn the PNG's greys back into metres.
//
// The PNG maps [z_min, z_max] linearly onto the greys 0..65535, grey = round(65535 (z - z_min) /
// (z_max - z_min)), so a height comes back as z = z_min + grey / 65535 (z_max - z_min) within half
// a level. The range is chosen once for a run (FrameExporter), so that frames are comparable and
// an animation's greys do not jump. Image row 0 is the row of columns with the highest y and
// column 0 the lowest x: the picture is a map seen from above with y up the page, the convention
// of a heightmap's PNG in a scene file, so an exported H_NNNN.png with the sidecar's z range and
// `extent` is itself a heightmap (docs/scenes.md).
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "config/scene_config.hpp"
#include "geometry/shapes.hpp"
#include "surface/height_field.hpp"

namespace sandflow {

/// The fixed z range of a run's height images [m], z_min < z_max.
struct HeightRange {
  Real z_min = 0, z_max = 1;
  /// Metres per grey level.
  Real step() const { return (z_max - z_min) / 65535.0; }
};

/// Writes `z` (one value per column of `grid`, row-major with x fastest) as a 16-bit grey PNG,
/// atomically. Values outside the range are clamped (non-finite ones written as z_min); returns
/// how many were. Throws OutputError naming the path.
std::size_t write_height_png(const std::string& path, const HeightFieldParams& grid,
                             const std::vector<Real>& z, const HeightRange& range);

/// Writes `z` as an OBJ mesh, atomically: one vertex per column centre (the vertex of column
/// (i, j) is number 1 + j nx + i), two triangles per cell between four centres, counter-clockwise
/// seen from above so that their normals point up; in the `up` frame (export_formats.hpp).
/// `comment` goes on a first `#` line. Throws OutputError naming the path.
void write_height_obj(const std::string& path, const HeightFieldParams& grid,
                      const std::vector<Real>& z, UpAxis up, const std::string& comment);

/// What heightfield.json holds: the grid (origin, cell size, nx, ny), the extent of the column
/// centres, the PNG's range and formula, and the OBJ files' up axis.
nlohmann::json height_sidecar(const HeightFieldParams& grid, const HeightRange& range, UpAxis up);

/// A run's height images as its heightfield.json describes them: the grid and the z range.
struct HeightImages {
  Real origin_x = 0, origin_y = 0, cell = 0, z_min = 0, z_max = 0;
  int nx = 0, ny = 0;
  /// The centre of column k (row-major, x fastest) [m].
  Real x_of(std::size_t k) const { return origin_x + (static_cast<Real>(k % nx) + 0.5) * cell; }
  Real y_of(std::size_t k) const { return origin_y + (static_cast<Real>(k / nx) + 0.5) * cell; }
};

/// RUN/heightfield/heightfield.json, when the run exported its height field and the file is one
/// this build writes (a grid of at least 2 x 2 columns and a z range); else nullopt.
std::optional<HeightImages> read_height_images(const std::string& run);

/// Frame `frame`'s heights from RUN/heightfield/`name`_NNNN.png (name "H" or "h"), one per column,
/// row-major with x fastest as `write_height_png` took them, within half a grey level. Empty
/// when the run did not write that frame's image; InputError naming the file when its size is not
/// the grid's.
std::vector<Real> read_height_frame(const std::string& run, const char* name, int frame,
                                    const HeightImages& grid);

/// Which columns of a frame's static top h hold static sand (1) and which are bare (0): sand where
/// h stands a quarter of a grain (`d`) above the solid under the column's centre, a mesh's
/// included. `ground`, when given, gets that solid's top per column (-infinity over none).
std::vector<std::uint8_t> static_sand_columns(const std::vector<Real>& h, const HeightImages& grid,
                                              const Geometry& solids, Real d,
                                              std::vector<Real>* ground = nullptr);

}  // namespace sandflow
