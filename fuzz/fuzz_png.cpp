// libFuzzer target: the grey PNG reader of heightmaps, with the scene loader's size limit. libpng
// is Debian's (not instrumented): coverage guides the fuzzer through our side only. Built with
// FUZZING_BUILD_MODE_UNSAFE_FOR_PRODUCTION, the reader ignores CRC and Adler-32 checksums so that
// mutated files get past them (src/io/png_gray.cpp).
#include "fuzz_common.hpp"
#include "geometry/heightmap.hpp"
#include "io/png_gray.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  sandflow_fuzz::expect_clean(
      [&] {
        sandflow::parse_gray_png(sandflow_fuzz::as_text(data, size), "fuzz.png",
                                 sandflow::kMaxHeightmapSide);
      },
      "fuzz.png");
  return 0;
}
