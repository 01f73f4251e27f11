// --set KEY=VALUE (internal to src/scene/): an override is grafted onto the parsed document before
// any table is read, so its value passes through exactly the checks a value in the file does.
// parse_override (declared in scene_loader.hpp) splits the argument.
#pragma once

#include <toml++/toml.h>

#include "scene/scene_loader.hpp"

namespace sandflow::loader {

/// Grafts one override onto the parsed document. Its value is parsed with "--set KEY" as its
/// source path, so that a message about it names where it came from. Throws InputError.
void apply_override(toml::table& root, const Override& o);

}  // namespace sandflow::loader
