// libFuzzer target: the checkpoint reader of `sandflow run --resume`, then the restore into a World
// of the scene below, which checks what parsed against that world (indices, lists) before it
// touches anything. Both may refuse with an InputError naming the file; nothing else may happen.
// In the fuzz build the checksums are not checked (src/checkpoint/checkpoint.cpp), so that
// mutations reach the fields behind them.
//
// Seeds: with SANDFLOW_FUZZ_WRITE_SEEDS=DIR in the environment, the target writes checkpoints of
// its scene (surface and plain DEM, after 1, 2 and 4 frames) into DIR and exits; scripts/fuzz.sh
// does this before fuzzing, so the seeds always match this scene and the current format.
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "checkpoint/checkpoint.hpp"
#include "fuzz_common.hpp"
#include "scene/scene_loader.hpp"
#include "sim/world.hpp"

namespace {

// a small pile and a pour onto a floor: every section of a checkpoint has something in it (hot,
// interface and static grains, pairs with contact history, walls, height-field columns, emitters)
constexpr const char* kScene = R"(
[material]
diameter = 0.01
diameter_spread = 0.1
k_n = 10000.0
[simulation]
dt_fraction = 0.2
[output]
fps = 120
[[geometry]]
type = "plane"
point = [0.0, 0.0, 0.0]
normal = [0.0, 0.0, 1.0]
[[emitter]]
type = "lattice"
center = [0.0, 0.0, 0.02]
size = [0.06, 0.06, 0.03]
count = 40
[[emitter]]
type = "pour"
center = [0.0, 0.0, 0.08]
radius = 0.02
rate = 300.0
count = 20
velocity = [0.0, 0.0, -1.0]
)";

sandflow::SceneConfig scene(sandflow::Mode mode) {
  sandflow::SceneConfig s = sandflow::load_scene_from_string(kScene, "fuzz_scene.toml");
  s.simulation.mode = mode;
  return s;
}

void write_seeds(const std::string& dir) {
  std::filesystem::create_directories(dir);
  for (const sandflow::Mode mode : {sandflow::Mode::Surface, sandflow::Mode::Dem}) {
    sandflow::World world(scene(mode));
    sandflow::Checkpoint c;
    c.scene_hash = sandflow::scene_hash(world, "fuzz");
    for (int frame = 1; frame <= 4; ++frame) {
      c.frames.push_back(world.advance_frame());
      if (frame == 3) continue;
      c.world = world.save_state();
      const std::string name = std::string(mode == sandflow::Mode::Dem ? "dem" : "surface") +
                               "_frame" + std::to_string(frame) + ".ckpt";
      std::ofstream(std::filesystem::path(dir) / name, std::ios::binary)
          << sandflow::encode_checkpoint(c);
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  if (const char* dir = std::getenv("SANDFLOW_FUZZ_WRITE_SEEDS")) {
    write_seeds(dir);
    std::exit(0);
  }
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const sandflow::SceneConfig surface = scene(sandflow::Mode::Surface);
  static const sandflow::SceneConfig dem = scene(sandflow::Mode::Dem);
  static const std::uint64_t dem_hash = sandflow::scene_hash(sandflow::World(dem), "fuzz");
  sandflow_fuzz::expect_clean(
      [&] {
        sandflow::Checkpoint c =
            sandflow::parse_checkpoint(sandflow_fuzz::as_text(data, size), "fuzz.ckpt");
        // the world the checkpoint says it is of, so that both modes' seeds restore all the way
        sandflow::World world(c.scene_hash == dem_hash ? dem : surface);
        const std::uint64_t hash = sandflow::scene_hash(world, "fuzz");
        sandflow::restore_checkpoint(world, std::move(c), hash, "fuzz.ckpt");
      },
      "fuzz.ckpt");
  return 0;
}
