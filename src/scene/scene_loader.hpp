// Scene files (TOML) -> SceneConfig, with every key validated. Errors are InputError whose message
// names file:line:column and the key: "scenes/floor.toml:14:3: material.restitution = 1.4 is
// outside (0, 1]". Unknown keys, wrong types and out-of-range values are all errors.
#pragma once

#include <string>
#include <vector>

#include "scene/scene_config.hpp"

namespace sandflow {

/// One --set KEY=VALUE override: KEY is a dotted path ("material.friction", "emitter.0.rate"),
/// VALUE is a TOML value ("0.5", "[0, 0, 1]", "\"disk\"").
struct Override {
  std::string key;
  std::string value;
};

/// Parses and validates a scene file, applying the overrides first (with the same validation).
SceneConfig load_scene(const std::string& path, const std::vector<Override>& overrides = {});

/// Parses and validates a scene given as text (for tests); `name` stands in for the file name.
SceneConfig load_scene_from_string(const std::string& text, const std::string& name,
                                   const std::vector<Override>& overrides = {});

/// Splits "KEY=VALUE"; throws InputError when there is no '='.
Override parse_override(const std::string& arg);

}  // namespace sandflow
