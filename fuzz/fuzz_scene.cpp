// libFuzzer target: the scene loader (toml++ and every key's validation), with --set overrides.
// The input is a scene file; after a line "#--set" (a TOML comment, so plain scenes stay valid),
// each line is one KEY=VALUE override. A heightmap's `file` is not opened: the loader is handed an
// image reader that returns a small fixed image, so no input can make it read other files (the
// PNG reader has its own target).
//
// A scene that loads is then built into a World, as `run --check` does (geometry, boundary
// particles, emitters, height field, time step), so that what the loader lets through is checked
// past it, with at most 1,000 grains. Every mesh entry's `file` is replaced by one small
// tetrahedron this target writes, so no input can make it read other files; its scale, size,
// rotation and position stay the input's (the mesh target fuzzes the files themselves, and builds a
// World from each too).
#include <fstream>
#include <string>
#include <vector>

#include "fuzz_common.hpp"
#include "scene/scene_loader.hpp"
#include "sim/world.hpp"

namespace {

std::string tetrahedron_file() {
  static const std::string path = [] {
    const std::string p = (sandflow_fuzz::own_folder() / "tetrahedron.obj").string();
    std::ofstream(p) << "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";
    return p;
  }();
  return path;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view input = sandflow_fuzz::as_text(data, size);
  const std::string_view marker = "\n#--set\n";
  const std::size_t split = input.find(marker);
  const std::string text(input.substr(0, split));

  const sandflow::ImageReader no_files = [](const std::string&, int) {
    sandflow::GrayImage img;
    img.width = 3;
    img.height = 2;
    img.value = {0, 0.5, 1, 0.25, 0.75, 0.125};
    return img;
  };
  sandflow_fuzz::expect_clean(
      [&] {
        std::vector<sandflow::Override> overrides;
        if (split != std::string_view::npos) {
          std::string_view rest = input.substr(split + marker.size());
          while (!rest.empty()) {
            const std::size_t nl = rest.find('\n');
            const std::string line(rest.substr(0, nl));
            rest = nl == std::string_view::npos ? std::string_view() : rest.substr(nl + 1);
            if (!line.empty()) overrides.push_back(sandflow::parse_override(line));
          }
        }
        sandflow::SceneConfig scene =
            sandflow::load_scene_from_string(text, "fuzz.toml", overrides, no_files);
        for (sandflow::GeometryConfig& g : scene.geometry)
          if (g.type == sandflow::GeometryType::Mesh) g.mesh_file = tetrahedron_file();
        // at most 1,000 grains, as `--grains 1000` would: the emitters' places and sizes stay
        // the input's, and the World is built 5 to 50 times faster (the seeds are full scale)
        if (scene.total_grains() > 1000) sandflow::scale_grain_count(scene, 1000);
        const sandflow::World world(scene);
      },
      "fuzz.toml", "--set", tetrahedron_file());
  return 0;
}
