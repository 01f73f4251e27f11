// Scene files (TOML) -> SceneConfig.
//
// The document is parsed whole (toml_reader.cpp, behind the guard of toml_guard.cpp), the --set
// overrides are grafted onto the parsed tree, and only then is the tree read into the structs, so
// an override passes through exactly the checks a value in the file does. Each grafted value is
// parsed with "--set KEY" as its source path: an error can always say where its value came from,
// "PATH:LINE:COL" or "--set KEY".
//
// Every table is read by a TableReader (table_reader.hpp), which refuses the keys its reader did
// not ask for.

#include "scene/scene_loader.hpp"

#include <toml++/toml.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <concepts>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <optional>
#include <sstream>
#include <string_view>
#include <utility>

#include "core/error.hpp"
#include "geometry/heightmap.hpp"
#include "io/export_formats.hpp"
#include "io/png_gray.hpp"
#include "scene/table_reader.hpp"
#include "scene/toml_guard.hpp"
#include "scene/toml_reader.hpp"
#include "sim/emitters.hpp"
#include "surface/surface_params.hpp"

namespace sandflow {
namespace loader {
namespace {

// The most grains a scene may make, in one emitter or in all: far above any scene we run, below
// 2^31 (grain ids are 32-bit) and what `--grains` accepts.
constexpr std::int64_t kMaxGrains = 2'000'000'000;

constexpr Choices<Mode> kModes[] = {{"surface", Mode::Surface}, {"dem", Mode::Dem}};
constexpr Choices<OnLeave> kOnLeave[] = {{"stop", OnLeave::Stop}, {"count", OnLeave::Count}};
constexpr Choices<GeometryType> kGeometryTypes[] = {{"plane", GeometryType::Plane},
                                                    {"box", GeometryType::Box},
                                                    {"cylinder", GeometryType::Cylinder},
                                                    {"sphere", GeometryType::Sphere},
                                                    {"bowl", GeometryType::Bowl},
                                                    {"heightmap", GeometryType::Heightmap},
                                                    {"mesh", GeometryType::Mesh}};
constexpr Choices<RenderStyle> kRenderStyles[] = {
    {"solid", RenderStyle::Solid}, {"glass", RenderStyle::Glass}, {"hidden", RenderStyle::Hidden}};
constexpr Choices<EmitterType> kEmitterTypes[] = {
    {"pour", EmitterType::Pour}, {"block", EmitterType::Block}, {"lattice", EmitterType::Lattice}};
constexpr Choices<PourShape> kPourShapes[] = {{"disk", PourShape::Disk}, {"rect", PourShape::Rect}};
constexpr Choices<UpAxis> kUpAxes[] = {{"z", UpAxis::Z}, {"y", UpAxis::Y}};

// ---- The tables of a scene ----------------------------------------------------------------------

void read_material(TableReader r, MaterialConfig& m) {
  r.read("density", m.density, kPositive);
  r.read("diameter", m.diameter, kPositive);
  r.read("diameter_spread", m.diameter_spread, closed(0, 0.5));
  r.read("k_n", m.k_n, kPositive);
  r.read("k_t_ratio", m.k_t_ratio, closed(0, 1));
  r.read("restitution", m.restitution, open_closed(0, 1));
  r.read("tangential_damping_ratio", m.tangential_damping_ratio, closed(0, 1));
  r.read("friction", m.friction, kNonNegative);
  r.read("rolling_friction", m.rolling_friction, kNonNegative);
  r.read("rolling_stiffness_ratio", m.rolling_stiffness_ratio, kNonNegative);
  r.read("rolling_damping_ratio", m.rolling_damping_ratio, kNonNegative);
  r.read("wall_friction", m.wall_friction, kNonNegative);
  r.read("wall_rolling_friction", m.wall_rolling_friction, kNonNegative);
  r.finish("[material]");
}

void read_simulation(TableReader r, SimulationConfig& s) {
  r.read("mode", s.mode, kModes);
  r.read("gravity", s.gravity);
  r.read("dt", s.dt, kPositive);
  r.read("dt_fraction", s.dt_fraction, open_closed(0, 0.2));
  r.read("skin", s.skin, open_closed(0, 2));
  r.read("skin_steps", s.skin_steps, closed(0, 1000));  // 0: one skin for all grains
  r.read("skin_max", s.skin_max, closed(0, 2));
  r.read("sort_every", s.sort_every, kNonNegative);  // 0: never re-sort
  r.read("seed", s.seed, kNonNegative);
  r.read("threads", s.threads, closed(0, 4096));
  r.read("max_overlap_stop", s.max_overlap_stop, open_closed(0, 1));
  r.read("domain", s.domain);
  r.read("on_leave", s.on_leave, kOnLeave);
  r.finish("[simulation]");
  if (s.domain) {
    const auto& d = *s.domain;
    if (!(d[3] > d[0]) || !(d[4] > d[1]) || !(d[5] > d[2]))
      r.fail_at("domain", r.name("domain") + " = [" + format_real(d[0]) + ", " +
                              format_real(d[1]) + ", " + format_real(d[2]) + ", " +
                              format_real(d[3]) + ", " + format_real(d[4]) + ", " +
                              format_real(d[5]) +
                              "]: expected [x0, y0, z0, x1, y1, z1] with x1 > x0, y1 > y0, z1 > z0");
  }
}

void read_stiffness(TableReader r, StiffnessConfig& k) {
  r.read("from_load", k.from_load);
  r.read("max_overlap", k.max_overlap, open_closed(0, 0.5));
  r.read("impact_overlap", k.impact_overlap, open_closed(0, 0.5));
  r.read("impact_speed", k.impact_speed, kNonNegative);
  r.read("dem_depth", k.dem_depth, kPositive);
  r.read("surface_depth", k.surface_depth, kPositive);
  r.finish("[stiffness]");
}

// Angles are written in degrees and stored in radians. `diameter` is the default cell size.
void read_surface(TableReader r, SurfaceConfig& s, Real diameter) {
  r.read("cell_size", s.cell_size, kPositive);
  r.read("exchange_rate", s.exchange_rate, kPositive);
  std::optional<Real> repose_deg;
  std::optional<Real> max_deg;
  r.read("repose_angle", repose_deg, open(0, 90));
  r.read("max_angle", max_deg, open(0, 90));
  r.read("rolling_min", s.rolling_min, kNonNegative);
  r.read("flowing_min", s.flowing_min, kNonNegative);
  r.read("interface_thickness", s.interface_thickness, kPositive);
  r.read("update_interval", s.update_interval, kPositive);
  r.read("trap_speed", s.trap_speed, kNonNegative);
  r.read("flow_speed", s.flow_speed, kNonNegative);
  r.read("extent", s.extent);
  r.finish("[surface]");

  if (repose_deg) {
    s.repose_angle = deg_to_rad(*repose_deg);
    s.repose_angle_given = true;
  }
  if (max_deg) {
    s.max_angle = deg_to_rad(*max_deg);
    if (*s.max_angle < s.repose_angle) {
      // The default repose angle is printed in degrees, rounded off its round trip via radians.
      const std::string repose_text =
          repose_deg
              ? format_real(*repose_deg)
              : format_real(std::round(rad_to_deg(s.repose_angle) * 1e9) / 1e9) + " (the default)";
      r.fail_at("max_angle", r.name("max_angle") + " = " + format_real(*max_deg) +
                                 " is less than " + r.name("repose_angle") + " = " + repose_text +
                                 " (degrees): expected max_angle >= repose_angle");
    }
  }
  if (s.extent) {
    const auto& [x0, y0, x1, y1] = *s.extent;
    if (!(x1 > x0) || !(y1 > y0))
      r.fail_at("extent", r.name("extent") + " = [" + format_real(x0) + ", " + format_real(y0) +
                              ", " + format_real(x1) + ", " + format_real(y1) +
                              "]: expected [x0, y0, x1, y1] with x1 > x0 and y1 > y0");
    // the grid the extent makes, refused here with its place when too large (without an extent,
    // surface_params() refuses it once the geometry gives the domain)
    const Real cell = s.cell_size.value_or(diameter);
    const Real nx = std::ceil((x1 - x0) / cell), ny = std::ceil((y1 - y0) / cell);
    if (!(nx * ny <= static_cast<Real>(kMaxHeightFieldColumns)))
      r.fail_at(s.cell_size ? "cell_size" : "extent",
                r.name("extent") + " at " +
                    (s.cell_size ? r.name("cell_size") + " = " + format_real(cell) + " m"
                                 : "a cell size of " + format_real(cell) +
                                       " m (the grain diameter: cell_size unset)") +
                    " makes a height field of " + format_count(nx) + " x " + format_count(ny) +
                    " columns, more than the limit of " + std::to_string(kMaxHeightFieldColumns) +
                    ": set a larger cell_size or a smaller extent");
  }
}

void read_output(TableReader r, OutputConfig& o) {
  r.read("fps", o.fps, kPositive);
  r.read("duration", o.duration, kPositive);
  r.read("settle_time", o.settle_time, kNonNegative);
  std::optional<std::vector<TableReader::Word>> exports;
  r.read("export", exports);
  r.read("up_axis", o.up_axis, kUpAxes);
  r.finish("[output]");
  if (exports) {
    o.exports.emplace();
    for (const auto& w : *exports) {
      const auto f = export_format(w.text);
      if (!f)
        fail(w.place, w.name + " = " + in_quotes(w.text) + " is not an export: expected one of " +
                          export_names() + " (an empty array [] writes no per-frame files)");
      if (!has_export(*o.exports, *f)) o.exports->push_back(*f);
    }
  }
}

// The render camera: a fixed one (position and look_at together, up optional) or only a field of
// view for the automatic one.
void read_camera(TableReader r, CameraConfig& c) {
  const auto vector = [&r](std::string_view key, std::optional<Vec3>& out) {
    const bool present = r.has(key);
    Vec3 v{0, 0, 0};
    r.read(key, v);  // also makes `key` one the table accepts
    if (present) out = v;
  };
  vector("position", c.position);
  vector("look_at", c.look_at);
  vector("up", c.up);
  r.read("fov", c.fov_deg, open(0, 180));
  r.finish("[camera]");

  if (c.position && !c.look_at)
    r.require("look_at", "[x, y, z], the point the camera at camera.position looks at");
  if (c.look_at && !c.position)
    r.require("position", "[x, y, z], where the camera looking at camera.look_at stands");
  if (c.up && !c.position)
    r.fail_at("up", r.name("up") +
                        " is set without camera.position and camera.look_at: the automatic camera "
                        "keeps z up; set all three or leave up out");
  if (!c.position) return;
  const Vec3 view = *c.look_at - *c.position;
  if (norm(view) == 0)
    r.fail_at("look_at", r.name("look_at") + " is camera.position: expected a point the camera "
                                             "looks at, away from where it stands");
  if (c.up) {
    const Real n = norm(*c.up);
    if (n == 0) r.fail_at("up", r.name("up") + " = [0, 0, 0]: expected a direction");
    // the picture's up must not point along the view, or it cannot be set upright
    if (norm(cross(*c.up / n, view / norm(view))) < 1e-3)
      r.fail_at("up", r.name("up") +
                          " is parallel to the view direction (look_at - position): expected a "
                          "direction across it");
  }
}

// A heightmap's samples: inline `heights`, a grey PNG `file` or procedural `noise`, exactly one.
void read_heightmap(TableReader& r, GeometryConfig& g, const std::string& scene_path,
                    const ImageReader& read_image) {
  std::optional<std::array<Real, 4>> extent;
  r.require("extent", "[x0, y0, x1, y1], the rectangle the terrain covers");
  r.read("extent", extent);
  const auto& [x0, y0, x1, y1] = *extent;
  if (!(x1 > x0) || !(y1 > y0))
    r.fail_at("extent", r.name("extent") + " = [" + format_real(x0) + ", " + format_real(y0) +
                            ", " + format_real(x1) + ", " + format_real(y1) +
                            "]: expected [x0, y0, x1, y1] with x1 > x0 and y1 > y0");
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
  const auto read_range = [&] {
    r.read("z_min", g.z_min);
    r.read("z_max", g.z_max);
    if (!(g.z_max > g.z_min))
      r.fail_at("z_max", r.name("z_max") + " = " + format_real(g.z_max) + " is not above " +
                             r.name("z_min") + " = " + format_real(g.z_min) +
                             ": expected z_max > z_min");
  };
  if (given[0] == "heights") {
    g.height_source = HeightSource::Inline;
    r.read("heights", g.heights, kMaxHeightmapSide);
    r.finish("a heightmap with heights");
  } else if (given[0] == "noise") {
    g.height_source = HeightSource::Noise;
    const toml::table* t = r.table("noise");
    TableReader n = r.nested("noise", *t);
    n.read("wavelength", g.noise_wavelength, kPositive);
    n.read("seed", g.noise_seed, kNonNegative);
    n.finish("a heightmap's noise");
    read_range();
    r.finish("a heightmap with noise");
    g.heights = noise_heights(g.extent, g.noise_wavelength, g.noise_seed, g.z_min, g.z_max);
  } else {
    g.height_source = HeightSource::File;
    std::string file;
    r.read("file", file);
    read_range();
    r.finish("a heightmap with file");
    // relative to the scene file; image row 0 (the top) is the far edge, y = y1
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
                            std::to_string(img.height) +
                            " pixels: a heightmap needs at least 2 x 2");
    g.heights.nx = img.width;
    g.heights.ny = img.height;
    g.heights.z.resize(img.value.size());
    for (int j = 0; j < img.height; ++j)
      for (int i = 0; i < img.width; ++i)
        g.heights.z[static_cast<std::size_t>(j) * img.width + i] =
            g.z_min + (g.z_max - g.z_min) *
                          img.value[static_cast<std::size_t>(img.height - 1 - j) * img.width + i];
  }
}

GeometryConfig read_geometry(TableReader r, std::size_t index, const std::string& scene_path,
                             const ImageReader& read_image) {
  GeometryConfig g;
  g.name = "geometry " + std::to_string(index);
  r.read("type", g.type, kGeometryTypes);
  r.read("name", g.name);
  r.read("render", g.render, kRenderStyles);
  r.read("friction", g.friction, kNonNegative);
  r.read("remove_at", g.remove_at, kNonNegative);
  if (g.remove_at && g.type == GeometryType::Mesh)
    r.fail_at(
        "remove_at",
        r.name("remove_at") + ": a mesh cannot be removed yet (its boundary particles would stay)");

  // Only the keys of this type are read; finish() refuses the others.
  const auto read_container = [&] {
    r.read("container", g.container);
    r.read("open_top", g.open_top);
    r.read("wall_thickness", g.wall_thickness, kPositive);
  };
  switch (g.type) {
    case GeometryType::Plane: {
      r.read("point", g.point);
      r.read("normal", g.normal);
      // Scale by the largest component first so that huge components cannot overflow the norm.
      const Real big = std::max({std::abs(g.normal.x), std::abs(g.normal.y), std::abs(g.normal.z)});
      if (big == 0)
        r.fail_at("normal", r.name("normal") + " = [0, 0, 0]: expected a non-zero normal vector");
      g.normal = g.normal / big;
      g.normal = g.normal / norm(g.normal);
      r.finish("a plane");
      break;
    }
    case GeometryType::Box:
      r.read("center", g.center);
      r.read("size", g.size, kPositive);
      r.read("rotation", g.rotation_deg);
      read_container();
      r.finish("a box");
      break;
    case GeometryType::Cylinder:
      r.read("center", g.center);
      r.read("rotation", g.rotation_deg);
      r.read("radius", g.radius, kPositive);
      r.read("height", g.height, kPositive);
      read_container();
      r.finish("a cylinder");
      break;
    case GeometryType::Sphere:
      r.read("center", g.center);
      r.read("radius", g.radius, kPositive);
      r.finish("a sphere");
      break;
    case GeometryType::Bowl:
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
      break;
    case GeometryType::Heightmap:
      read_heightmap(r, g, scene_path, read_image);
      break;
    case GeometryType::Mesh: {
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
        r.fail_at("fallback", r.name("fallback") + " = \"" + fallback +
                                  "\": expected \"none\" or \"box\"");
      g.fallback_box = fallback == "box";
      r.read("fallback_size", g.fallback_size, kPositive);
      r.read("particle_radius", g.particle_radius, kPositive);
      r.finish("a mesh");
      break;
    }
  }
  return g;
}

EmitterConfig read_emitter(TableReader r, std::size_t index, const MaterialConfig& material) {
  EmitterConfig e;
  e.name = "emitter " + std::to_string(index);
  r.read("type", e.type, kEmitterTypes);
  r.read("name", e.name);
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
  }
  // sizes that no count makes possible, refused before anything of their size is made
  if (const auto problem = emitter_problem(e, material))
    r.fail_at(problem->key, r.name(problem->key) + " " + problem->what);
  return e;
}

SceneConfig read_scene(const toml::table& root, const std::string& path,
                       const ImageReader& read_image) {
  const Places places(path);
  SceneConfig c;
  c.path = path;
  c.name = std::filesystem::path(path).stem().string();

  TableReader doc(places, root, "");
  if (const auto* t = doc.table("scene")) {
    TableReader r(places, *t, "scene");
    r.read("name", c.name);
    r.read("description", c.description);
    r.finish("[scene]");
  }
  if (const auto* t = doc.table("material")) read_material({places, *t, "material"}, c.material);
  if (const auto* t = doc.table("simulation"))
    read_simulation({places, *t, "simulation"}, c.simulation);
  if (const auto* t = doc.table("stiffness"))
    read_stiffness({places, *t, "stiffness"}, c.stiffness);
  if (const auto* t = doc.table("surface"))
    read_surface({places, *t, "surface"}, c.surface, c.material.diameter);
  if (const auto* t = doc.table("output")) read_output({places, *t, "output"}, c.output);
  if (const auto* t = doc.table("camera")) read_camera({places, *t, "camera"}, c.camera);

  std::size_t heightmap_samples = 0;
  if (const auto* a = doc.array_of_tables("geometry")) {
    for (std::size_t i = 0; i < a->size(); ++i) {
      const std::string prefix = "geometry[" + std::to_string(i) + "]";
      const TableReader r(places, *a->get(i)->as_table(), prefix);
      if (i == kMaxGeometryEntries)
        r.fail_at("type", prefix + ": the scene has " + std::to_string(a->size()) +
                              " [[geometry]] entries, more than the limit of " +
                              std::to_string(kMaxGeometryEntries) +
                              " (every grain and height-field column asks each of them): put "
                              "many solids into one mesh");
      c.geometry.push_back(read_geometry(r, i, path, read_image));
      // each heightmap is bounded by its sides; all of them together by one of the largest
      const HeightGrid& h = c.geometry.back().heights;
      heightmap_samples += static_cast<std::size_t>(h.nx) * static_cast<std::size_t>(h.ny);
      if (heightmap_samples > kMaxHeightmapSamples) {
        const char* key = c.geometry.back().height_source == HeightSource::File    ? "file"
                          : c.geometry.back().height_source == HeightSource::Noise ? "noise"
                                                                                   : "heights";
        r.fail_at(key, r.name(key) + " brings the scene's heightmaps to " +
                           std::to_string(heightmap_samples) +
                           " samples together, more than the limit of " +
                           std::to_string(kMaxHeightmapSamples) + " (one of 4096 x 4096)");
      }
    }
  }
  const auto* emitters = doc.array_of_tables("emitter");
  if (!emitters || emitters->empty())
    doc.fail_at("emitter", "emitter: a scene needs at least one [[emitter]] table, found none");
  std::int64_t total = 0;
  Real slots = 0;
  for (std::size_t i = 0; i < emitters->size(); ++i) {
    const std::string prefix = "emitter[" + std::to_string(i) + "]";
    const TableReader r(places, *emitters->get(i)->as_table(), prefix);
    c.emitters.push_back(read_emitter(r, i, c.material));
    total += c.emitters.back().count;  // each at most kMaxGrains: the sum cannot overflow here
    if (total > kMaxGrains)
      r.fail_at("count", r.name("count") + " = " + std::to_string(c.emitters.back().count) +
                             " brings the scene to " + std::to_string(total) +
                             " grains, more than the limit of " + std::to_string(kMaxGrains) +
                             " in all");
    slots += pour_slots(c.emitters.back(), c.material);  // each at most kMaxPourSlots
    if (slots > kMaxPourSlots) {
      const char* key = c.emitters.back().shape == PourShape::Disk ? "radius" : "size";
      r.fail_at(key, r.name(key) + " brings the scene's pours to about " +
                         format_real(std::round(slots)) +
                         " slots together, more than the limit of " + format_real(kMaxPourSlots));
    }
  }

  doc.finish("a scene file");
  return c;
}

// ---- Overrides ----------------------------------------------------------------------------------

// "emitter[0].rate" or "emitter.0.rate" -> {"emitter", "0", "rate"}.
std::vector<std::string> split_key(const std::string& key, const std::string& where) {
  const auto malformed = [&] {
    fail(where, "malformed key " + in_quotes(key) +
                    ": expected a dotted path such as material.friction or emitter[0].rate");
  };
  std::string dotted;
  for (std::size_t i = 0; i < key.size(); ++i) {
    if (key[i] == '[') {
      const std::size_t close = key.find(']', i);
      if (close == std::string::npos || close == i + 1) malformed();
      const std::string index = key.substr(i + 1, close - i - 1);
      if (!std::all_of(index.begin(), index.end(), [](char ch) { return ch >= '0' && ch <= '9'; }))
        malformed();
      dotted += "." + index;
      i = close;
      if (i + 1 < key.size() && key[i + 1] != '.' && key[i + 1] != '[') malformed();
    } else if (key[i] == ']') {
      malformed();
    } else {
      dotted += key[i];
    }
  }
  std::vector<std::string> segments;
  std::size_t begin = 0;
  while (true) {
    const std::size_t dot = dotted.find('.', begin);
    segments.push_back(dotted.substr(begin, dot == std::string::npos ? dot : dot - begin));
    if (segments.back().empty()) malformed();
    if (dot == std::string::npos) break;
    begin = dot + 1;
  }
  return segments;
}

std::optional<std::size_t> parse_index(const std::string& s) {
  std::size_t i = 0;
  const auto res = std::from_chars(s.data(), s.data() + s.size(), i);
  if (res.ec != std::errc() || res.ptr != s.data() + s.size()) return std::nullopt;
  return i;
}

// The override's value as a one-key document {v = VALUE}, parsed with "--set KEY" as its source
// path. Text that is not a TOML value is taken as a bare string, so --set simulation.mode=dem
// works.
toml::table parse_override_value(const Override& o, const std::string& where) {
  const std::string doc = "v = " + o.value;
  try {
    if (!toml_hazard(doc)) {  // else a string (toml++ could not parse it safely)
      toml::table t = toml::parse(doc, std::string_view(where));
      if (t.size() == 1 && t.contains("v")) return t;  // not "1\nw = 2" smuggling in more keys
    }
  } catch (const toml::parse_error&) {
  }
  std::ostringstream quoted;
  quoted << toml::value<std::string>(o.value);
  const std::string as_string = "v = " + quoted.str();
  if (const auto h = toml_hazard(as_string))
    fail(where, "cannot read the value " + in_quotes(o.value) + ": " + h->what);
  try {
    return toml::parse(as_string, std::string_view(where));
  } catch (const toml::parse_error& err) {
    fail(where,
         "cannot read the value " + in_quotes(o.value) + ": " + std::string(err.description()));
  }
}

// Grafts one override onto the parsed document. Tables on the way must exist (an index past the
// last [[emitter]] is an error), except the plain top-level tables, which a file may leave out.
void apply_override(toml::table& root, const Override& o) {
  const std::string where = "--set " + o.key;
  const std::vector<std::string> segments = split_key(o.key, where);

  toml::node* at = &root;
  std::string walked;  // the path so far, named as in messages: emitter[0]
  for (std::size_t s = 0; s + 1 < segments.size(); ++s) {
    const std::string& seg = segments[s];
    if (auto* t = at->as_table()) {
      toml::node* child = t->get(seg);
      if (!child) {
        const bool plain = seg == "scene" || seg == "material" || seg == "simulation" ||
                           seg == "stiffness" || seg == "surface" || seg == "output" ||
                           seg == "camera";
        if (t != &root || !plain)
          fail(where, "the scene has no table " + (walked.empty() ? seg : walked + "." + seg));
        child = &t->insert_or_assign(seg, toml::table{}).first->second;
      }
      walked = walked.empty() ? seg : walked + "." + seg;
      at = child;
    } else if (auto* a = at->as_array()) {
      const auto i = parse_index(seg);
      if (!i) fail(where, walked + " is an array: index it with a number, as in " + walked + ".0");
      if (*i >= a->size())
        fail(where, "the scene has no " + walked + "[" + seg + "] (it has " +
                        std::to_string(a->size()) + ")");
      walked += "[" + seg + "]";
      at = a->get(*i);
    } else {
      fail(where, walked + " is " + type_name(*at) + ", not a table");
    }
  }

  auto* target = at->as_table();
  if (!target) {
    if (at->is_array())
      fail(where, "cannot set one element of " + walked + "; set the whole array instead");
    fail(where, walked + " is " + type_name(*at) + ", not a table");
  }
  toml::table parsed = parse_override_value(o, where);
  // Moving (not copying) the node keeps its source region, hence its "--set KEY" place.
  parsed.get("v")->visit(
      [&](auto& node) { target->insert_or_assign(segments.back(), std::move(node)); });
}

}  // namespace
}  // namespace loader

// ---- Public entry points ------------------------------------------------------------------------

Override parse_override(const std::string& arg) {
  const auto trim = [](std::string s) {
    const auto first = s.find_first_not_of(" \t");
    const auto last = s.find_last_not_of(" \t");
    return first == std::string::npos ? std::string() : s.substr(first, last - first + 1);
  };
  const std::size_t eq = arg.find('=');
  if (eq == std::string::npos)
    throw InputError("--set " + arg + ": expected KEY=VALUE, as in --set material.friction=0.5");
  Override o{trim(arg.substr(0, eq)), trim(arg.substr(eq + 1))};
  if (o.key.empty())
    throw InputError("--set " + arg +
                     ": the key is empty; expected KEY=VALUE, as in --set material.friction=0.5");
  return o;
}

SceneConfig load_scene_from_string(const std::string& text, const std::string& name,
                                   const std::vector<Override>& overrides,
                                   const ImageReader& read_image) {
  toml::table root = loader::parse_toml(text, name);
  for (const auto& o : overrides) loader::apply_override(root, o);
  return loader::read_scene(root, name, read_image);
}

SceneConfig load_scene(const std::string& path, const std::vector<Override>& overrides) {
  return load_scene_from_string(read_scene_file(path), path, overrides);
}

}  // namespace sandflow
