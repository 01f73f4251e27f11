// The TOML reader (toml_reader.hpp): a scene file's text, read whatever the file is, and that text
// parsed by toml++ once the guard (toml_guard.hpp) has passed it.

#include "scene/toml_reader.hpp"

#include <string>

#include "core/error.hpp"
#include "core/read_file.hpp"
#include "scene/scene_loader.hpp"
#include "scene/toml_guard.hpp"

namespace sandflow {

namespace loader {

toml::table parse_toml(std::string_view text, const std::string& name) {
  if (text.size() > kMaxSceneBytes)
    throw InputError(name + ": the scene is " + std::to_string(text.size()) +
                     " bytes, more than the limit of " + std::to_string(kMaxSceneBytes));
  if (const auto h = toml_hazard(text))
    throw InputError(name + ":" + std::to_string(h->line) + ":" + std::to_string(h->column) + ": " +
                     h->what);
  try {
    return toml::parse(text, std::string_view(name));
  } catch (const toml::parse_error& err) {
    const auto& at = err.source().begin;
    throw InputError(name + ":" + std::to_string(at.line) + ":" + std::to_string(at.column) + ": " +
                     std::string(err.description()));
  }
}

}  // namespace loader

std::string read_scene_file(const std::string& path) {
  return read_whole_file(path, "scene file", kMaxSceneBytes);
}

}  // namespace sandflow
