// Reading grey-scale PNG images (heightmaps) with libpng: 1-, 2-, 4-, 8- and 16-bit grey, with or
// without an alpha channel (ignored). Colour and palette images are refused: a heightmap has one
// value per pixel, and guessing a grey from colours would hide a wrong file.
#pragma once

#include <string>
#include <vector>

namespace sandflow {

struct GrayImage {
  int width = 0;
  int height = 0;
  std::vector<double> value;  ///< row-major from the top row, each in [0, 1] (grey / max grey)
};

/// Reads `path`. Images wider or taller than max_side are refused before their pixels are read.
/// Throws InputError with a message that starts with the path.
GrayImage read_gray_png(const std::string& path, int max_side);

/// Writes an 8- or 16-bit grey PNG (for tests and tools); values are clamped to [0, 1]. Throws
/// OutputError naming the path.
void write_gray_png(const std::string& path, int width, int height,
                    const std::vector<double>& value, int bit_depth);

}  // namespace sandflow
