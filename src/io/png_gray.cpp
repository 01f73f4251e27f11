// libpng reports errors by longjmp. The functions that set a jump point hold only trivially
// destructible locals (raw buffers freed by hand), so a longjmp never skips a destructor; the C++
// wrappers below turn the outcome into exceptions.
#include "io/png_gray.hpp"

#include <png.h>

#include <algorithm>
#include <cerrno>
#include <csetjmp>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string_view>
#include <vector>

#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "core/read_file.hpp"

namespace sandflow {
namespace {

struct ErrorText {
  char text[256];
  char warning[256];  ///< the last warning: libpng often says what is wrong in one before failing
};

void on_error(png_structp png, png_const_charp msg) {
  auto* e = static_cast<ErrorText*>(png_get_error_ptr(png));
  std::snprintf(e->text, sizeof e->text, "%s", msg);
  png_longjmp(png, 1);
}

void on_warning(png_structp png, png_const_charp msg) {
  auto* e = static_cast<ErrorText*>(png_get_error_ptr(png));
  std::snprintf(e->warning, sizeof e->warning, "%s", msg);
}

// PNG data in memory, handed to libpng by read_memory(); `pos` is where the reading stopped, for
// messages.
struct Memory {
  const unsigned char* data = nullptr;
  std::size_t size = 0;
  std::size_t pos = 0;
};

void read_memory(png_structp png, png_bytep out, png_size_t n) {
  auto* m = static_cast<Memory*>(png_get_io_ptr(png));
  if (n > m->size - m->pos) {
    m->pos = m->size;
    png_error(png, "unexpected end of data (file truncated?)");
  }
  std::memcpy(out, m->data + m->pos, n);
  m->pos += n;
}

enum class ReadStatus { Ok, NotPng, Colour, TooLarge, Corrupt };

struct RawImage {
  int width = 0, height = 0, color_type = 0;
  double* value = nullptr;  // malloc'ed, width * height
};

ReadStatus read_raw(Memory* in, int max_side, RawImage* out, ErrorText* err) {
  if (in->size < 8 || png_sig_cmp(in->data, 0, 8) != 0) return ReadStatus::NotPng;
  in->pos = 8;
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, err, on_error, on_warning);
  if (!png) return ReadStatus::Corrupt;
  png_infop info = png_create_info_struct(png);
  unsigned char* volatile pixels = nullptr;
  double* volatile value = nullptr;
  if (!info || setjmp(png_jmpbuf(png))) {
    std::free(pixels);
    std::free(value);
    png_destroy_read_struct(&png, info ? &info : nullptr, nullptr);
    return ReadStatus::Corrupt;
  }
  png_set_read_fn(png, in, read_memory);
  png_set_sig_bytes(png, 8);
  // Every ancillary chunk but tRNS is skipped unread: none says anything about the heights, and
  // libpng 1.6.39 only warns that an iTXt of 1.4 GB is too large, then allocates and zeroes it
  // (found by fuzzing: a 56-byte file took 6 s and 1.4 GB).
  png_set_keep_unknown_chunks(png, PNG_HANDLE_CHUNK_NEVER, nullptr, -1);
#ifdef FUZZING_BUILD_MODE_UNSAFE_FOR_PRODUCTION
  // the fuzz build only: mutated files would rarely get past the checksums otherwise
  png_set_crc_action(png, PNG_CRC_QUIET_USE, PNG_CRC_QUIET_USE);
  png_set_option(png, PNG_IGNORE_ADLER32, PNG_OPTION_ON);
#endif
  png_read_info(png, info);
  const png_uint_32 w = png_get_image_width(png, info), h = png_get_image_height(png, info);
  const int depth = png_get_bit_depth(png, info), type = png_get_color_type(png, info);
  out->width = static_cast<int>(std::min<png_uint_32>(w, 0x7fffffff));
  out->height = static_cast<int>(std::min<png_uint_32>(h, 0x7fffffff));
  out->color_type = type;
  ReadStatus status = ReadStatus::Ok;
  if (type != PNG_COLOR_TYPE_GRAY && type != PNG_COLOR_TYPE_GRAY_ALPHA)
    status = ReadStatus::Colour;
  else if (w > static_cast<png_uint_32>(max_side) || h > static_cast<png_uint_32>(max_side))
    status = ReadStatus::TooLarge;
  if (status != ReadStatus::Ok) {
    png_destroy_read_struct(&png, &info, nullptr);
    return status;
  }
  // samples of 8 or 16 bits, big-endian, the alpha (if any) after the grey; grey of 1, 2 or 4
  // bits is expanded by scaling onto 0..255
  if (depth < 8) png_set_expand_gray_1_2_4_to_8(png);
  // an Adam7-interlaced image comes in 7 passes, each a sparse subset of the rows: libpng puts
  // them together when every pass is read into the whole image (without this, the heights of
  // an interlaced file came out scrambled)
  const int passes = png_set_interlace_handling(png);
  png_read_update_info(png, info);
  const std::size_t rowbytes = png_get_rowbytes(png, info);
  const int channels = png_get_channels(png, info);
  const int bytes = depth == 16 ? 2 : 1;
  const double scale = depth == 16 ? 65535.0 : 255.0;
  pixels = static_cast<unsigned char*>(std::calloc(h, rowbytes));  // passes fill it in parts
  value = static_cast<double*>(std::malloc(sizeof(double) * w * h));
  if (!pixels || !value) png_error(png, "out of memory");
  for (int pass = 0; pass < passes; ++pass)
    for (png_uint_32 y = 0; y < h; ++y) png_read_row(png, pixels + rowbytes * y, nullptr);
  for (png_uint_32 y = 0; y < h; ++y) {
    const unsigned char* row = pixels + rowbytes * y;
    for (png_uint_32 x = 0; x < w; ++x) {
      const unsigned char* px = row + static_cast<std::size_t>(x) * channels * bytes;
      const unsigned v = bytes == 2 ? (static_cast<unsigned>(px[0]) << 8) | px[1] : px[0];
      value[static_cast<std::size_t>(y) * w + x] = v / scale;
    }
  }
  png_read_end(png, nullptr);
  png_destroy_read_struct(&png, &info, nullptr);
  std::free(pixels);
  out->value = value;
  return ReadStatus::Ok;
}

bool write_raw(std::FILE* fp, int width, int height, const double* value, int bit_depth,
               ErrorText* err) {
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, err, on_error, on_warning);
  if (!png) return false;
  png_infop info = png_create_info_struct(png);
  unsigned char* volatile row = nullptr;
  if (!info || setjmp(png_jmpbuf(png))) {
    std::free(row);
    png_destroy_write_struct(&png, info ? &info : nullptr);
    return false;
  }
  png_init_io(png, fp);
  png_set_IHDR(png, info, static_cast<png_uint_32>(width), static_cast<png_uint_32>(height),
               bit_depth, PNG_COLOR_TYPE_GRAY, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
               PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  const int bytes = bit_depth == 16 ? 2 : 1;
  const double full = bit_depth == 16 ? 65535.0 : 255.0;
  row = static_cast<unsigned char*>(std::malloc(static_cast<std::size_t>(width) * bytes));
  if (!row) png_error(png, "out of memory");
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const double v = std::clamp(value[static_cast<std::size_t>(y) * width + x], 0.0, 1.0);
      const unsigned q = static_cast<unsigned>(v * full + 0.5);
      if (bytes == 2) {
        row[2 * x] = static_cast<unsigned char>(q >> 8);
        row[2 * x + 1] = static_cast<unsigned char>(q & 0xff);
      } else {
        row[x] = static_cast<unsigned char>(q);
      }
    }
    png_write_row(png, row);
  }
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  std::free(row);
  return true;
}

}  // namespace

GrayImage parse_gray_png(std::string_view bytes, const std::string& name, int max_side) {
  Memory in{reinterpret_cast<const unsigned char*>(bytes.data()), bytes.size()};
  RawImage raw;
  ErrorText err{};
  const ReadStatus st = read_raw(&in, max_side, &raw, &err);
  // The fields of the IHDR chunk, which a PNG must start with, are at fixed offsets.
  constexpr int kWidthAt = 16, kColourTypeAt = 25;
  const auto at = [&name](std::size_t byte) {
    return name + ": byte " + std::to_string(byte) + ": ";
  };
  switch (st) {
    case ReadStatus::Ok:
      break;
    case ReadStatus::NotPng:
      throw InputError(at(0) + "not a PNG image (expected the 8-byte PNG signature)");
    case ReadStatus::Colour:
      throw InputError(at(kColourTypeAt) + "a colour PNG (" +
                       std::string(raw.color_type == PNG_COLOR_TYPE_PALETTE ? "palette" : "RGB") +
                       "): a heightmap must be a grey-scale PNG (1, 2, 4, 8 or 16 bits)");
    case ReadStatus::TooLarge:
      throw InputError(at(kWidthAt) + "the image is " + std::to_string(raw.width) + " x " +
                       std::to_string(raw.height) + " pixels: at most " +
                       std::to_string(max_side) + " x " + std::to_string(max_side));
    case ReadStatus::Corrupt:
      throw InputError(at(in.pos) + "cannot read the PNG: " +
                       (err.text[0] ? std::string(err.text) : std::string("corrupt data")) +
                       (err.warning[0] ? " (" + std::string(err.warning) + ")" : std::string()));
  }
  GrayImage img;
  img.width = raw.width;
  img.height = raw.height;
  img.value.assign(raw.value, raw.value + static_cast<std::size_t>(raw.width) * raw.height);
  std::free(raw.value);
  return img;
}

GrayImage read_gray_png(const std::string& path, int max_side) {
  return parse_gray_png(read_whole_file(path, "image", kMaxPngFileBytes), path, max_side);
}

void write_gray_png(const std::string& path, int width, int height,
                    const std::vector<double>& value, int bit_depth) {
  if (width < 1 || height < 1 || value.size() != static_cast<std::size_t>(width) * height ||
      (bit_depth != 8 && bit_depth != 16))
    throw OutputError(path + ": write_gray_png: bad image size or bit depth");
  errno = 0;
  std::FILE* fp = std::fopen(path.c_str(), "wb");
  if (!fp) throw OutputError(path + ": cannot create: " + system_reason(errno));
  ErrorText err{};
  const bool ok = write_raw(fp, width, height, value.data(), bit_depth, &err);
  const bool closed = std::fclose(fp) == 0;
  if (!ok || !closed)
    throw OutputError(path + ": cannot write the PNG" +
                      (err.text[0] ? ": " + std::string(err.text) : std::string()));
}

}  // namespace sandflow
