// The reader of one [[geometry]] entry (scene_tables.hpp): its common keys, then only the keys of
// its type, so that finish() refuses a key of another type; a heightmap's samples come inline,
// from a grey PNG or from procedural noise.

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "geometry/heightmap.hpp"
#include "io/png_gray.hpp"
#include "scene/scene_tables.hpp"

namespace sandflow::loader {
namespace {

constexpr Choices<GeometryType> kGeometryTypes[] = {
    {"plane", GeometryType::Plane},       {"box", GeometryType::Box},
    {"cylinder", GeometryType::Cylinder}, {"sphere", GeometryType::Sphere},
    {"bowl", GeometryType::Bowl},         {"heightmap", GeometryType::Heightmap},
    {"mesh", GeometryType::Mesh}};
constexpr Choices<RenderStyle> kRenderStyles[] = {
    {"solid", RenderStyle::Solid}, {"glass", RenderStyle::Glass}, {"hidden", RenderStyle::Hidden}};

// ---- Heightmaps ---------------------------------------------------------------------------------

// The range the samples of `file` or `noise` are scaled to.
void read_z_range(TableReader& r, GeometryConfig& g) {
  r.read("z_min", g.z_min);
  r.read("z_max", g.z_max);
  if (!(g.z_max > g.z_min))
    r.fail_at("z_max", r.name("z_max") + " = " + format_real(g.z_max) + " is not above " +
                           r.name("z_min") + " = " + format_real(g.z_min) +
                           ": expected z_max > z_min");
}

void read_noise_heights(TableReader& r, GeometryConfig& g) {
  g.height_source = HeightSource::Noise;
  const toml::table* t = r.table("noise");
  TableReader n = r.nested("noise", *t);
  n.read("wavelength", g.noise_wavelength, kPositive);
  n.read("seed", g.noise_seed, kNonNegative);
  n.finish("a heightmap's noise");
  read_z_range(r, g);
  r.finish("a heightmap with noise");
  g.heights = noise_heights(g.extent, g.noise_wavelength, g.noise_seed, g.z_min, g.z_max);
}

// A grey PNG, relative to the scene file; image row 0 (the top) is the far edge, y = y1.
void read_file_heights(TableReader& r, GeometryConfig& g, const std::string& scene_path,
                       const ImageReader& read_image) {
  g.height_source = HeightSource::File;
  std::string file;
  r.read("file", file);
  read_z_range(r, g);
  r.finish("a heightmap with file");
  const std::filesystem::path p(file);
  g.file = p.is_absolute() ? file : (std::filesystem::path(scene_path).parent_path() / p).string();
  const std::string what = r.name("file") + " = " + in_quotes(file) + ": ";
  GrayImage img;
  try {
    img = read_image(g.file, kMaxHeightmapSide);
  } catch (const InputError& e) {
    r.fail_at("file", what + e.what());
  }
  if (img.width < 2 || img.height < 2)
    r.fail_at("file", what + g.file + " is " + std::to_string(img.width) + " x " +
                          std::to_string(img.height) + " pixels: a heightmap needs at least 2 x 2");
  g.heights.nx = img.width;
  g.heights.ny = img.height;
  g.heights.z.resize(img.value.size());
  for (int j = 0; j < img.height; ++j)
    for (int i = 0; i < img.width; ++i)
      g.heights.z[static_cast<std::size_t>(j) * img.width + i] =
          g.z_min + (g.z_max - g.z_min) *
                        img.value[static_cast<std::size_t>(img.height - 1 - j) * img.width + i];
}

// A heightmap's samples: inline `heights`, a grey PNG `file` or procedural `noise`, exactly one.
void read_heightmap(TableReader& r, GeometryConfig& g, const std::string& scene_path,
                    const ImageReader& read_image) {
  std::optional<std::array<Real, 4>> extent;
  r.require("extent", "[x0, y0, x1, y1], the rectangle the terrain covers");
  r.read("extent", extent);
  check_extent(r, *extent);
  g.extent = *extent;
  r.read("base_thickness", g.base_thickness, kPositive);

  const char* sources[] = {"heights", "file", "noise"};
  std::vector<std::string> given;
  for (const char* k : sources)
    if (r.has(k)) given.emplace_back(k);
  if (given.size() != 1)
    r.fail_at(given.empty() ? "extent" : given[1],
              r.name(given.empty() ? "heights" : given[1]) +
                  ": a heightmap takes exactly one of heights, file, noise" +
                  (given.empty() ? ", found none" : " (found " + join(given, " and ") + ")"));
  if (given[0] == "heights") {
    g.height_source = HeightSource::Inline;
    r.read("heights", g.heights, kMaxHeightmapSide);
    r.finish("a heightmap with heights");
  } else if (given[0] == "noise") {
    read_noise_heights(r, g);
  } else {
    read_file_heights(r, g, scene_path, read_image);
  }
}

// ---- The other shapes ---------------------------------------------------------------------------

void read_plane(TableReader& r, GeometryConfig& g) {
  r.read("point", g.point);
  r.read("normal", g.normal);
  // Scale by the largest component first so that huge components cannot overflow the norm.
  const Real big = std::max({std::abs(g.normal.x), std::abs(g.normal.y), std::abs(g.normal.z)});
  if (big == 0)
    r.fail_at("normal", r.name("normal") + " = [0, 0, 0]: expected a non-zero normal vector");
  g.normal = g.normal / big;
  g.normal = g.normal / norm(g.normal);
  r.finish("a plane");
}

// The keys of a box or cylinder that may be a container (walls around the inner size).
void read_container(TableReader& r, GeometryConfig& g) {
  r.read("container", g.container);
  r.read("open_top", g.open_top);
  r.read("wall_thickness", g.wall_thickness, kPositive);
  for (const char* key : {"open_top", "wall_thickness"})
    if (r.has(key) && !g.container)
      r.fail_at(key, r.name(key) + " belongs to a container: set " + r.name("container") +
                         " = true, or leave it out");
}

void read_bowl(TableReader& r, GeometryConfig& g) {
  r.read("center", g.center);
  r.read("rotation", g.rotation_deg);
  r.read("radius", g.radius, kPositive);
  r.read("wall_thickness", g.wall_thickness, kPositive);
  r.read("depth", g.depth, kPositive);
  r.finish("a bowl");
  if (g.depth && !(*g.depth < 2 * g.radius))
    r.fail_at("depth", r.name("depth") + " = " + format_real(*g.depth) +
                           " is not below 2 * radius = " + format_real(2 * g.radius) +
                           ": expected depth in (0, 2 radius), 2 radius being a closed sphere");
}

void read_mesh(TableReader& r, GeometryConfig& g) {
  r.read("file", g.mesh_file);
  if (g.mesh_file.empty()) r.fail_at("type", r.name("file") + ": a mesh needs its file");
  r.read("scale", g.scale, kPositive);
  r.read("size", g.mesh_size, kPositive);
  if (g.scale && g.mesh_size)
    r.fail_at("size", r.name("size") + ": give either scale or size, not both");
  r.read("rotation", g.rotation_deg);
  r.read("position", g.position);
  std::string fallback = "none";
  r.read("fallback", fallback);
  if (fallback != "none" && fallback != "box")
    r.fail_at("fallback",
              r.name("fallback") + " = \"" + fallback + "\": expected \"none\" or \"box\"");
  g.fallback_box = fallback == "box";
  r.read("fallback_size", g.fallback_size, kPositive);
  r.read("particle_radius", g.particle_radius, kPositive);
  r.finish("a mesh");
}

// The keys of g.type; finish() refuses the others.
void read_shape(TableReader& r, GeometryConfig& g, const std::string& scene_path,
                const ImageReader& read_image) {
  switch (g.type) {
    case GeometryType::Plane:
      read_plane(r, g);
      break;
    case GeometryType::Box:
      r.read("center", g.center);
      r.read("size", g.size, kPositive);
      r.read("rotation", g.rotation_deg);
      read_container(r, g);
      r.finish("a box");
      break;
    case GeometryType::Cylinder:
      r.read("center", g.center);
      r.read("rotation", g.rotation_deg);
      r.read("radius", g.radius, kPositive);
      r.read("height", g.height, kPositive);
      read_container(r, g);
      r.finish("a cylinder");
      break;
    case GeometryType::Sphere:
      r.read("center", g.center);
      r.read("radius", g.radius, kPositive);
      r.finish("a sphere");
      break;
    case GeometryType::Bowl:
      read_bowl(r, g);
      break;
    case GeometryType::Heightmap:
      read_heightmap(r, g, scene_path, read_image);
      break;
    case GeometryType::Mesh:
      read_mesh(r, g);
      break;
  }
}

}  // namespace

GeometryConfig read_geometry(TableReader r, std::size_t index, const std::string& scene_path,
                             const ImageReader& read_image) {
  GeometryConfig g;
  g.name = "geometry " + std::to_string(index);
  r.read("type", g.type, kGeometryTypes);
  r.read_name("name", g.name);
  r.read("render", g.render, kRenderStyles);
  r.read("friction", g.friction, kNonNegative);
  r.read("remove_at", g.remove_at, kNonNegative);
  if (g.remove_at && g.type == GeometryType::Mesh)
    r.fail_at(
        "remove_at",
        r.name("remove_at") + ": a mesh cannot be removed yet (its boundary particles would stay)");
  read_shape(r, g, scene_path, read_image);
  return g;
}

}  // namespace sandflow::loader
