// Reading grey-scale PNG images (heightmaps) with libpng: 1-, 2-, 4-, 8- and 16-bit grey, with or
// without an alpha channel (ignored). Colour and palette images are refused: a heightmap has one
// value per pixel, and guessing a grey from colours would hide a wrong file.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

namespace sandflow {

struct GrayImage {
  int width = 0;
  int height = 0;
  std::vector<double> value;  ///< row-major from the top row, each in [0, 1] (grey / max grey)
};

/// Largest PNG file read_gray_png reads [bytes]: far above a 4096 x 4096 grey image of 16 bits
/// with alpha (64 MiB unpacked), so only a file that is not a heightmap meets it.
inline constexpr std::size_t kMaxPngFileBytes = std::size_t{256} << 20;

/// Reads `path` (at most kMaxPngFileBytes). Images wider or taller than max_side are refused
/// before their pixels are read. Throws InputError "PATH: byte N: what", N the offset in the file
/// where the reading stopped.
GrayImage read_gray_png(const std::string& path, int max_side);

/// Decodes PNG data already in memory, `name` standing for the file in messages; the same checks
/// and messages as read_gray_png. The entry point for fuzzing.
GrayImage parse_gray_png(std::string_view bytes, const std::string& name, int max_side);

/// Writes an 8- or 16-bit grey PNG (for tests and tools); values are clamped to [0, 1]. Throws
/// OutputError naming the path.
void write_gray_png(const std::string& path, int width, int height,
                    const std::vector<double>& value, int bit_depth);

}  // namespace sandflow
