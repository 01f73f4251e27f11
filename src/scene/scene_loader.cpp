// Scene files (TOML) -> SceneConfig: the loader's entry points and the reading of the document.
//
// The document is parsed whole (toml_reader.cpp, behind the guard of toml_guard.cpp), the --set
// overrides are grafted onto the parsed tree, and only then is the tree read into the structs, so
// an override passes through exactly the checks a value in the file does. Each grafted value is
// parsed with "--set KEY" as its source path: an error can always say where its value came from,
// "PATH:LINE:COL" or "--set KEY".
//
// Every table is read by a TableReader (table_reader.hpp), which refuses the keys its reader did
// not ask for; the readers of the tables are in settings_tables.cpp, geometry_table.cpp and
// emitter_table.cpp (scene_tables.hpp). This file reads the document's tables with them and checks
// what holds for the scene as a whole: the number of [[geometry]] entries, the heightmaps' samples,
// the grains and the pour slots of all emitters together.

#include "scene/scene_loader.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "geometry/heightmap.hpp"
#include "scene/scene_tables.hpp"
#include "scene/table_reader.hpp"
#include "scene/toml_guard.hpp"
#include "scene/toml_reader.hpp"
#include "sim/emitters.hpp"

namespace sandflow {
namespace loader {
namespace {

// The tables a scene has at most once, in the order "a scene file" lists its keys.
void read_settings(TableReader& doc, const Places& places, SceneConfig& c) {
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
}

SceneConfig read_scene(const toml::table& root, const std::string& path,
                       const ImageReader& read_image) {
  const Places places(path);
  SceneConfig c;
  c.path = path;
  c.name = std::filesystem::path(path).stem().string();

  TableReader doc(places, root, "");
  read_settings(doc, places, c);
  read_geometries(doc, places, read_image, c);
  read_emitters(doc, places, c);
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
