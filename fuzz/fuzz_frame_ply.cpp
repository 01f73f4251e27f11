// libFuzzer target: the frame reader of `sandflow measure` and `render` (PLY point clouds).
#include "fuzz_common.hpp"
#include "io/ply.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  sandflow_fuzz::expect_clean(
      [&] { sandflow::parse_frame_ply(sandflow_fuzz::as_text(data, size), "fuzz.ply"); },
      "fuzz.ply");
  return 0;
}
