// POV-Ray text of the bowl and the heightmap: the shapes the grains collide with.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "io/pov_writer.hpp"

namespace sandflow {
namespace {

std::string pov_text(const std::vector<GeometryConfig>& geometry) {
  const std::string path =
      (std::filesystem::temp_directory_path() / ("sandflow_pov_shapes_" + std::to_string(::getpid()) + ".pov"))
          .string();
  write_pov_scene(path, FrameData{}, geometry, PovOptions{});
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  std::filesystem::remove(path);
  return ss.str();
}

TEST(PovShapes, BowlIsAShellCutByTheRimPlane) {
  GeometryConfig g;
  g.type = GeometryType::Bowl;
  g.radius = 0.5;
  g.wall_thickness = 0.1;
  g.depth = 0.3;  // rim plane 0.2 below the centre
  const std::string s = pov_text({g});
  EXPECT_NE(s.find("intersection { difference { sphere { <0,0,0>, 0.6 } sphere { <0,0,0>, 0.5 } }"
                   " plane { z, -0.2 } texture { Solid }"),
            std::string::npos)
      << s;
}

TEST(PovShapes, HeightmapIsAClosedMesh) {
  GeometryConfig g;
  g.type = GeometryType::Heightmap;
  g.extent = {0, 0, 2, 1};
  g.heights = {3, 2, {0, 1, 2, 3, 4, 5}};
  const std::string s = pov_text({g});
  // 6 surface vertices and 6 under the perimeter; faces: 2 cells, 6 side quads, the bottom
  EXPECT_NE(s.find("vertex_vectors { 12,"), std::string::npos) << s;
  EXPECT_NE(s.find("face_indices { 18,"), std::string::npos) << s;
  EXPECT_NE(s.find("<2,1,5>"), std::string::npos);  // the far corner at its height
  EXPECT_NE(s.find("<0,0,-0.05>"), std::string::npos);  // the bottom, base_thickness under 0
}

}  // namespace
}  // namespace sandflow
