// libFuzzer target: the mesh readers (OBJ, PLY, OFF) behind decode_mesh, gzip included. The first
// byte picks the format ('o' OBJ, 'p' PLY, 'f' OFF, any other byte by its value modulo 3), the
// rest is the file; scripts/fuzz.sh prefixes the seed meshes accordingly.
#include <string>

#include "fuzz_common.hpp"
#include "geometry/mesh_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  static const char* const kNames[3] = {"fuzz.obj", "fuzz.ply", "fuzz.off"};
  const int format = data[0] == 'o' ? 0 : data[0] == 'p' ? 1 : data[0] == 'f' ? 2 : data[0] % 3;
  const std::string name = kNames[format];
  sandflow_fuzz::expect_clean(
      [&] { sandflow::decode_mesh(std::string(sandflow_fuzz::as_text(data + 1, size - 1)), name); },
      name);
  return 0;
}
