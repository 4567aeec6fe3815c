// RGB images and PNG output (libpng), for slices and previews.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace quijibo {

struct Rgb {
  std::uint8_t r = 0, g = 0, b = 0;
};

struct Image {
  int width = 0, height = 0;
  std::vector<Rgb> pixels;  // row-major, row 0 at the top
  Image(int w, int h, Rgb fill = {}) : width(w), height(h), pixels(std::size_t(w) * h, fill) {}
  Rgb& at(int x, int y) { return pixels[std::size_t(y) * width + x]; }
  // A filled disc, clipped to the image.
  void disc(double cx, double cy, double radius, Rgb color);
};

// Writes an 8-bit RGB PNG atomically; throws quijibo::Error naming the path.
void WritePng(const std::string& path, const Image& image);

}  // namespace quijibo
