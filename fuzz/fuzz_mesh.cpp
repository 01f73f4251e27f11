// libFuzzer target: the mesh readers behind decode_mesh (OBJ, PLY, OFF; STL, glTF and GLB through
// assimp), gzip included, then a World built on what they read. The first byte says how, the rest
// is the file: 'o', 'p', 'f', 's', 'g', 'b' pick OBJ, PLY, OFF, STL, glTF, GLB, placed at the
// file's own scale (as `scale = 1`, so that huge or tiny coordinates reach the placement and the
// sampling) in surface mode; any other byte picks the format by its value modulo 6 (in that
// order), fits the mesh to 0.2 m when its bit 7 is set and runs plain DEM when its bit 6 is.
// scripts/fuzz.sh prefixes each seed mesh with its letter and with its fitted-surface byte (0x80
// + the format's place in the order). Assimp's library is not instrumented: its crashes, hangs
// and allocations count, its coverage does not guide.
//
// A mesh that reads is written to a file of this process's own and named by a small scene, which
// is built into a World as `run --check` does: placement, the inside test, the boundary particles
// and, in surface mode, the height field over them. Its grains are 5 cm, so that a seed mesh a
// metre across gives thousands of particles, not hundreds of thousands: the fuzzer then tries
// many more inputs (the inputs' own scale still reaches the limits). A glTF that names other files
// looks for them beside that file, where there are none.
#include <fstream>
#include <string>
#include <string_view>

#include <fmt/format.h>

#include "fuzz_common.hpp"
#include "geometry/mesh_io.hpp"
#include "scene/scene_loader.hpp"
#include "sim/world.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  static const char* const kNames[6] = {"fuzz.obj", "fuzz.ply",  "fuzz.off",
                                        "fuzz.stl", "fuzz.gltf", "fuzz.glb"};
  static constexpr std::string_view kLetters = "opfsgb";
  const std::uint8_t how = data[0];
  const std::size_t letter_at = kLetters.find(static_cast<char>(how));
  const bool letter = letter_at != std::string_view::npos;
  const std::size_t format = letter ? letter_at : how % 6;
  const bool fitted = !letter && (how & 0x80), dem = !letter && (how & 0x40);
  const std::string name = kNames[format];
  const std::string bytes(sandflow_fuzz::as_text(data + 1, size - 1));
  bool read = false;
  sandflow_fuzz::expect_clean(
      [&] {
        sandflow::decode_mesh(bytes, name);
        read = true;
      },
      name);
  if (!read) return 0;

  const std::string file = (sandflow_fuzz::own_folder() / name).string();
  std::ofstream(file, std::ios::binary) << bytes;
  const std::string scene_text =
      fmt::format(R"(
[material]
diameter = 0.05
[simulation]
mode = "{}"
[[geometry]]
type = "plane"
[[geometry]]
type = "mesh"
file = "{}"
{}
[[emitter]]
type = "pour"
center = [0.0, 0.0, 0.5]
radius = 0.15
count = 100
)",
                  dem ? "dem" : "surface", file, fitted ? "size = 0.2" : "");
  sandflow_fuzz::expect_clean(
      [&] {
        const sandflow::World world(sandflow::load_scene_from_string(scene_text, "fuzz_mesh.toml"));
      },
      "fuzz_mesh.toml", file);
  return 0;
}
