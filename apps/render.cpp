// `sandflow render`: a run's frame drawn by POV-Ray.
#include <omp.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "commands.hpp"
#include "core/error.hpp"
#include "io/ply.hpp"
#include "io/pov_writer.hpp"
#include "io/run_output.hpp"
#include "scene/scene_loader.hpp"

namespace fs = std::filesystem;

namespace sandflow {

int render_command(const RenderOptions& o) {
  const std::string& dir = o.dir;
  const int width = o.width, height = o.height, frame = o.frame;
  const std::string ply = frame > 0 ? frame_path(dir, frame) : last_frame(dir);
  const FrameData f = read_ply(ply);
  // the geometry comes from the scene file the run recorded
  std::vector<GeometryConfig> geometry;
  Geometry placed;  // its meshes, placed
  std::vector<const TriangleMesh*> meshes;
  std::ifstream in(fs::path(dir) / "summary.json");
  if (in) {
    const auto summary = nlohmann::json::parse(in, nullptr, false);
    if (!summary.is_discarded() && summary.contains("scene_file")) {
      const SceneConfig scene = load_scene(summary["scene_file"].get<std::string>());
      geometry = scene.geometry;
      placed = Geometry::from_config(geometry, scene.material, scene.path);
      std::size_t next = 0;
      for (const GeometryConfig& g : geometry)
        meshes.push_back(g.type == GeometryType::Mesh ? &placed.meshes()[next++].mesh : nullptr);
    }
  }
  if (find_povray().empty())
    throw InputError("povray is not installed: sudo apt-get install povray");
  fs::create_directories(fs::path(dir) / "render");
  const std::string stem = (fs::path(dir) / "render" / fs::path(ply).stem()).string();
  PovOptions opt;
  opt.width = width;
  opt.height = height;
  write_pov_scene(stem + ".pov", f, geometry, opt, meshes);
  render_pov(stem + ".pov", stem + ".png", width, height, omp_get_num_procs());
  fmt::print("{}\n", stem + ".png");
  return 0;
}

}  // namespace sandflow
