#include "util/image.h"

#include <png.h>

#include <cmath>
#include <cstdio>

#include "util/error.h"
#include "util/io.h"

namespace quijibo {

void Image::disc(double cx, double cy, double radius, Rgb color) {
  for (int y = int(std::floor(cy - radius)); y <= int(std::ceil(cy + radius)); ++y)
    for (int x = int(std::floor(cx - radius)); x <= int(std::ceil(cx + radius)); ++x)
      if (x >= 0 && y >= 0 && x < width && y < height && (x - cx) * (x - cx) + (y - cy) * (y - cy) <= radius * radius)
        at(x, y) = color;
}

namespace {
void Append(png_structp png, png_bytep data, png_size_t length) {
  auto* out = static_cast<std::string*>(png_get_io_ptr(png));
  out->append(reinterpret_cast<const char*>(data), length);
}
void Flush(png_structp) {}
}  // namespace

void WritePng(const std::string& path, const Image& image) {
  std::string bytes;
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  if (!png || !info) throw Error(path + ": cannot encode PNG (libpng)");
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    throw Error(path + ": cannot encode PNG (libpng)");
  }
  png_set_write_fn(png, &bytes, Append, Flush);
  png_set_IHDR(png, info, png_uint_32(image.width), png_uint_32(image.height), 8, PNG_COLOR_TYPE_RGB,
               PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  for (int y = 0; y < image.height; ++y)
    png_write_row(png, reinterpret_cast<png_const_bytep>(&image.pixels[std::size_t(y) * image.width]));
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  WriteFileAtomically(path, bytes);
}

}  // namespace quijibo
