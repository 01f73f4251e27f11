// The TOML reader (toml_reader.hpp): a scene file's text, read whatever the file is, and that text
// parsed by toml++ once the guard (toml_guard.hpp) has passed it.

#include "scene/toml_reader.hpp"

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "core/file_kind.hpp"
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
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    throw InputError(path + ": cannot open scene file (it is a directory)");
  refuse_special_file(path, "scene file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot open scene file");
  // read in pieces up to the limit: a pipe or a device has no size to check first
  std::string text;
  std::vector<char> buf(1 << 16);  // (not on the stack: the command's whole stack may be 64 KiB)
  while (in.read(buf.data(), static_cast<std::streamsize>(buf.size())) || in.gcount() > 0) {
    if (text.size() + static_cast<std::size_t>(in.gcount()) > kMaxSceneBytes)
      throw InputError(path + ": the scene file is larger than the limit of " +
                       std::to_string(kMaxSceneBytes) + " bytes");
    text.append(buf.data(), static_cast<std::size_t>(in.gcount()));
  }
  if (in.bad()) throw InputError(path + ": cannot read scene file");
  return text;
}

}  // namespace sandflow
