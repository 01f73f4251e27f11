// libFuzzer target: the scene loader (toml++ and every key's validation), with --set overrides.
// The input is a scene file; after a line "#--set" (a TOML comment, so plain scenes stay valid),
// each line is one KEY=VALUE override. A heightmap's `file` is not opened: the loader is handed an
// image reader that returns a small fixed image, so no input can make it read other files (the
// PNG reader has its own target).
#include <string>
#include <vector>

#include "fuzz_common.hpp"
#include "scene/scene_loader.hpp"

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
        sandflow::load_scene_from_string(text, "fuzz.toml", overrides, no_files);
      },
      "fuzz.toml", "--set");
  return 0;
}
