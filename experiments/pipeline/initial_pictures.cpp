#include "experiments/pipeline/initial_pictures.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "util/io.h"

namespace quijibo::pipeline {

void WriteRootsPly(const std::string& path, const RationalMap& map, bool user_frame) {
  std::string body;
  int count = 0;
  auto add = [&](const Vec4& r, std::uint8_t red, std::uint8_t blue) {
    Vec3 p{r[0], r[1], r[2]};
    if (user_frame) p = map.frame.fractal_to_user(p);
    for (double c : p) {
      const float f = float(c);
      body.append(reinterpret_cast<const char*>(&f), 4);
    }
    const std::uint8_t rgb[3] = {red, 40, blue};
    body.append(reinterpret_cast<const char*>(rgb), 3);
    ++count;
  };
  // A root of exponent 0 (a `both_signs` twin) is not a factor of R: not written.
  for (int i = 0; i < map.top_count(); ++i)
    if (map.top_exponents[i] != 0) add(map.top_roots[i], 30, 230);
  for (int i = 0; i < map.bottom_count(); ++i)
    if (map.bottom_exponents[i] != 0) add(map.bottom_roots[i], 230, 30);
  const std::string header =
      "ply\nformat binary_little_endian 1.0\ncomment quijibo roots: blue top, red bottom\n"
      "element vertex " +
      std::to_string(count) +
      "\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\n"
      "property uchar green\nproperty uchar blue\nend_header\n";
  WriteFileAtomically(path, header + body);
}

Image PotentialSlice(const monopole::ExteriorPotential& potential, const ScalarGrid& sdf, const RationalMap& map,
                     int size) {
  const Vec3 lo = sdf.frame.min_corner;
  const double side = sdf.frame.spacing * sdf.frame.dims[0];
  Image img(size, size);
  auto pixel_point = [&](double x, double y) {
    return Vec3{lo[0] + side * (x + 0.5) / size, lo[1] + side * (size - y - 0.5) / size, 0.0};
  };
  // P is smooth at the pixel scale: evaluate it on a 4x coarser lattice and interpolate bilinearly
  // (the full-resolution evaluation took longer than the whole fit).
  const int step = 4, nc = (size + step - 1) / step + 1;
  std::vector<Vec3> coarse;
  coarse.reserve(std::size_t(nc) * nc);
  for (int j = 0; j < nc; ++j)
    for (int i = 0; i < nc; ++i) coarse.push_back(pixel_point(i * step, j * step));
  const std::vector<double> Pc = potential.Evaluate(coarse);
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      const int i = x / step, j = y / step;
      const double fx = double(x % step) / step, fy = double(y % step) / step;
      auto at = [&](int ii, int jj) { return Pc[std::size_t(jj) * nc + ii]; };
      const double P =
          (1 - fy) * ((1 - fx) * at(i, j) + fx * at(i + 1, j)) + fy * ((1 - fx) * at(i, j + 1) + fx * at(i + 1, j + 1));
      const auto g = std::uint8_t(std::lround(255 * std::clamp(P, 0.0, 1.0)));
      img.at(x, y) = {g, g, g};
    }
  std::vector<Vec3> points;
  points.reserve(std::size_t(size) * size);
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) points.push_back(pixel_point(x, y));
  // Outline: pixels whose sdf sign differs from a neighbour's.
  auto inside = [&](int x, int y) { return sdf.sample(points[std::size_t(y) * size + x]) < 0; };
  for (int y = 0; y + 1 < size; ++y)
    for (int x = 0; x + 1 < size; ++x)
      if (inside(x, y) != inside(x + 1, y) || inside(x, y) != inside(x, y + 1)) img.at(x, y) = {40, 200, 60};
  const double slab = 2 * sdf.frame.spacing;
  auto draw = [&](const Vec4& r, Rgb c) {
    if (std::abs(r[2]) > slab) return;
    img.disc((r[0] - lo[0]) / side * size, size - (r[1] - lo[1]) / side * size, std::max(2.0, size / 150.0), c);
  };
  for (int i = 0; i < map.top_count(); ++i)
    if (map.top_exponents[i] != 0) draw(map.top_roots[i], {30, 80, 255});
  for (int i = 0; i < map.bottom_count(); ++i)
    if (map.bottom_exponents[i] != 0) draw(map.bottom_roots[i], {255, 40, 30});
  return img;
}

Image StartSlice(const ScalarGrid& sdf, const RationalMap& map, int size) {
  const Vec3 lo = sdf.frame.min_corner;
  const double side = sdf.frame.spacing * sdf.frame.dims[0];
  Image img(size, size);
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      const Vec3 p{lo[0] + side * (x + 0.5) / size, lo[1] + side * (size - y - 0.5) / size, 0.0};
      const bool set = OneStepLogModulus(map, p) < 0, inside = sdf.sample(p) < 0;
      img.at(x, y) = set && inside ? Rgb{70, 70, 70}
                     : set         ? Rgb{255, 140, 20}
                     : inside      ? Rgb{60, 120, 255}
                                   : Rgb{255, 255, 255};
    }
  const double slab = 2 * sdf.frame.spacing;
  auto draw = [&](const Vec4& r, Rgb c) {
    if (std::abs(r[2]) > slab) return;
    img.disc((r[0] - lo[0]) / side * size, size - (r[1] - lo[1]) / side * size, std::max(1.5, size / 250.0), c);
  };
  for (int i = 0; i < map.top_count(); ++i)
    if (map.top_exponents[i] != 0) draw(map.top_roots[i], {30, 80, 255});
  for (int i = 0; i < map.bottom_count(); ++i)
    if (map.bottom_exponents[i] != 0) draw(map.bottom_roots[i], {255, 40, 30});
  return img;
}

}  // namespace quijibo::pipeline
