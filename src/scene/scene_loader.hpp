// Scene files (TOML) -> SceneConfig, with every key validated. Errors are InputError whose message
// names file:line:column and the key: "scenes/floor.toml:14:3: material.restitution = 1.4 is
// outside (0, 1]". Unknown keys, wrong types and out-of-range values are all errors.
#pragma once

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

#include "config/scene_config.hpp"
#include "io/png_gray.hpp"

namespace sandflow {

/// One --set KEY=VALUE override: KEY is a dotted path ("material.friction", "emitter.0.rate"),
/// VALUE is a TOML value ("0.5", "[0, 0, 1]", "\"disk\"").
struct Override {
  std::string key;
  std::string value;
};

/// Largest scene file [bytes]. toml++ takes about 35 times the text in memory at worst (a long
/// array of "0,"), so this bounds the parse to about 1 GB; a large terrain belongs in a PNG.
inline constexpr std::size_t kMaxSceneBytes = std::size_t{32} << 20;

/// Most [[geometry]] entries a scene may have. Every entry is asked for its distance by every
/// grain near it each step and by every height-field column when the field is built (256 planes
/// over the largest field took 226 s to check); a scene of many solids is one mesh.
inline constexpr std::size_t kMaxGeometryEntries = 64;

/// How the loader reads a heightmap's image file (path, largest side); read_gray_png by default.
using ImageReader = std::function<GrayImage(const std::string& path, int max_side)>;

/// Parses and validates a scene file, applying the overrides first (with the same validation).
/// The text of a scene file, read in pieces up to kMaxSceneBytes (a pipe has no size to check
/// first); a folder, FIFO or device is refused by its type. Throws InputError.
std::string read_scene_file(const std::string& path);
SceneConfig load_scene(const std::string& path, const std::vector<Override>& overrides = {});

/// Parses and validates a scene given as text (for tests); `name` stands in for the file name.
/// A heightmap's `file` is read by `read_image`: the fuzzer passes one that opens nothing.
SceneConfig load_scene_from_string(const std::string& text, const std::string& name,
                                   const std::vector<Override>& overrides = {},
                                   const ImageReader& read_image = read_gray_png);

/// Splits "KEY=VALUE"; throws InputError when there is no '='.
Override parse_override(const std::string& arg);

}  // namespace sandflow
