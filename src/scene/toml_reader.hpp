// The TOML reader (internal to src/scene/): a scene's text to a toml++ table, through the guard of
// toml_guard.hpp, with toml++'s errors as InputError at "PATH:LINE:COL". read_scene_file (declared
// in scene_loader.hpp) gets the text from a file.
#pragma once

#include <toml++/toml.h>

#include <string>
#include <string_view>

namespace sandflow::loader {

/// The document `text` (at most kMaxSceneBytes), parsed with `name` as the source path of its
/// nodes. Throws InputError naming name:line:column.
toml::table parse_toml(std::string_view text, const std::string& name);

}  // namespace sandflow::loader
