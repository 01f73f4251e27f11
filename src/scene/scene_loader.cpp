// Scene files (TOML) -> SceneConfig: the loader's entry points and the reading of the document.
//
// The document is parsed whole (toml_reader.cpp, behind the guard of toml_guard.cpp), the --set
// overrides are grafted onto the parsed tree (overrides.cpp), and only then is the tree read into
// the structs, so an override passes through exactly the checks a value in the file does. Each
// grafted value is parsed with "--set KEY" as its source path: an error can always say where its
// value came from, "PATH:LINE:COL" or "--set KEY".
//
// Every table is read by a TableReader (table_reader.hpp), which refuses the keys its reader did
// not ask for; the readers of the tables are in settings_tables.cpp, geometry_table.cpp and
// emitter_table.cpp (scene_tables.hpp). This file reads the document's tables with them and checks
// what holds for the scene as a whole: the number of [[geometry]] entries, the heightmaps' samples,
// the grains and the pour slots of all emitters together.

#include "scene/scene_loader.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <optional>

#include "core/error.hpp"
#include "core/file_kind.hpp"
#include "geometry/bed_packing.hpp"
#include "geometry/heightmap.hpp"
#include "geometry/shapes.hpp"
#include "scene/overrides.hpp"
#include "scene/scene_tables.hpp"
#include "scene/table_reader.hpp"
#include "scene/toml_reader.hpp"
#include "sim/emitters.hpp"

namespace sandflow {
namespace loader {
namespace {

// The tables a scene has at most once, in the order "a scene file" lists its keys.
void read_settings(TableReader& doc, const Places& places, SceneConfig& c) {
  if (const auto* t = doc.table("scene")) {
    TableReader r(places, *t, "scene");
    r.read_name("name", c.name);
    // (the name makes the default output folder, out/NAME-MODE)
    if (!is_plain_folder_name(c.name))
      r.fail_at("name", "scene.name = \"" + c.name +
                            "\": expected a name that can make a folder's (not empty, no / or \\, "
                            "not . or ..)");
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
  if (const auto* t = doc.table("output"))
    read_output({places, *t, "output"}, c.output, c.material);
  if (const auto* t = doc.table("camera")) read_camera({places, *t, "camera"}, c.camera);
}

// The [[geometry]] entries: at most kMaxGeometryEntries; each heightmap is bounded by its sides,
// all of them together by one of the largest.
void read_geometries(TableReader& doc, const Places& places, const ImageReader& read_image,
                     SceneConfig& c) {
  const auto* a = doc.array_of_tables("geometry");
  if (!a) return;
  std::size_t heightmap_samples = 0;
  for (std::size_t i = 0; i < a->size(); ++i) {
    const std::string prefix = "geometry[" + std::to_string(i) + "]";
    const TableReader r(places, *a->get(i)->as_table(), prefix);
    if (i == kMaxGeometryEntries)
      r.fail_at("type", prefix + ": the scene has " + std::to_string(a->size()) +
                            " [[geometry]] entries, more than the limit of " +
                            std::to_string(kMaxGeometryEntries) +
                            " (every grain and height-field column asks each of them): put "
                            "many solids into one mesh");
    c.geometry.push_back(read_geometry(r, i, c.path, read_image));
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

// The [[emitter]] entries: at least one; at most kMaxGrains grains and kMaxPourSlots pour slots
// all together.
void read_emitters(TableReader& doc, const Places& places, SceneConfig& c) {
  const auto* emitters = doc.array_of_tables("emitter");
  if (!emitters || emitters->empty())
    doc.fail_at("emitter", "emitter: a scene needs at least one [[emitter]] table, found none");
  std::int64_t total = 0;
  Real slots = 0;
  std::optional<Geometry> geometry;  // built for the first bed
  for (std::size_t i = 0; i < emitters->size(); ++i) {
    const std::string prefix = "emitter[" + std::to_string(i) + "]";
    const TableReader r(places, *emitters->get(i)->as_table(), prefix);
    c.emitters.push_back(read_emitter(r, i, c.material));
    EmitterConfig& e = c.emitters.back();
    if (e.type == EmitterType::Bed) {
      // a bed holds what its region holds: packed now, on the geometry, for its count (the World
      // packs it again, the same, from the same seed), at most what the scene has room for
      if (!geometry) {
        try {
          geometry.emplace(Geometry::from_config(c.geometry, c.material, c.path));
        } catch (const InputError& err) {
          r.fail_at("type", prefix + ": its floor is the scene's geometry, which cannot be made: " +
                                err.what());
        }
      }
      BedPacking bed;
      const Real room = std::min(kMaxBedGrains, static_cast<Real>(kMaxGrains - total));
      if (const auto problem =
              pack_bed_emitter(e, c.material, *geometry, bed_seed(c.simulation.seed, i), bed, room,
                               c.simulation.threads))
        r.fail_at(problem->key, r.name(problem->key) + " " + problem->what +
                                    (room < kMaxBedGrains && std::string(problem->key) == "size"
                                         ? " (the scene's room left for grains)"
                                         : ""));
      set_bed_extent(e, bed);
    }
    total += e.count;  // each at most kMaxGrains: the sum cannot overflow here
    if (total > kMaxGrains)
      r.fail_at(e.type == EmitterType::Bed ? "size" : "count",
                r.name(e.type == EmitterType::Bed ? "size" : "count") + " = " +
                    std::to_string(e.count) + " brings the scene to " + std::to_string(total) +
                    " grains, more than the limit of " + std::to_string(kMaxGrains) + " in all");
    slots += pour_slots(c.emitters.back(), c.material);  // each at most kMaxPourSlots
    if (slots > kMaxPourSlots) {
      const char* key = c.emitters.back().shape == PourShape::Disk ? "radius" : "size";
      r.fail_at(key, r.name(key) + " brings the scene's pours to about " +
                         format_real(std::round(slots)) +
                         " slots together, more than the limit of " + format_real(kMaxPourSlots));
    }
  }
}

SceneConfig read_scene(const toml::table& root, const std::string& path,
                       const ImageReader& read_image) {
  SceneConfig c;
  const Places places(path, &c);
  c.path = path;
  c.name = std::filesystem::path(path).stem().string();

  TableReader doc(places, root, "");
  read_settings(doc, places, c);
  read_geometries(doc, places, read_image, c);
  read_emitters(doc, places, c);
  doc.finish("a scene file");
  return c;
}

}  // namespace
}  // namespace loader

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
