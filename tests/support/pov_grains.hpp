// The grains of a POV-Ray scene that sandflow wrote, read back with their texture: the spheres of
// each `union {  // Sand[k]` ... `texture { Sand[k] } }` block, and a lone grain's textured
// sphere. A scan of the lines the writer makes, not a POV-Ray parser.
#pragma once

#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

namespace sandflow::test {

struct PovGrain {
  double x = 0, y = 0, z = 0, radius = 0;
  int shade = -1;  ///< the index into the scene's Sand array
};

inline std::vector<PovGrain> pov_grains(const std::string& text) {
  std::vector<PovGrain> out;
  std::istringstream in(text);
  int union_shade = -1;
  for (std::string line; std::getline(in, line);) {
    int k = -1;
    PovGrain g;
    if (std::sscanf(line.c_str(), "union {  // Sand[%d]", &k) == 1) {
      union_shade = k;
    } else if (line.rfind("texture { Sand[", 0) == 0) {
      union_shade = -1;
    } else if (std::sscanf(line.c_str(), "sphere{<%lf,%lf,%lf>,%lf texture{Sand[%d]}}", &g.x, &g.y,
                           &g.z, &g.radius, &k) == 5) {
      g.shade = k;
      out.push_back(g);
    } else if (std::sscanf(line.c_str(), "sphere{<%lf,%lf,%lf>,%lf}", &g.x, &g.y, &g.z,
                           &g.radius) == 4) {
      g.shade = union_shade;
      out.push_back(g);
    }
  }
  return out;
}

}  // namespace sandflow::test
