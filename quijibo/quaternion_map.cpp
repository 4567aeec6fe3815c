#include "quijibo/quaternion_map.h"

#include <algorithm>
#include <cmath>

namespace quijibo {

std::string IterationOptions::Validate() const {
  if (iterations < 1 || iterations > 100000) return "iterations must be in [1, 100000]";
  if (!(escape_radius > 0) || !std::isfinite(escape_radius)) return "escape radius must be a positive number";
  if (!(capture_radius >= 0) || !(capture_radius < escape_radius)) return "capture radius must be in [0, escape radius)";
  if (!std::isfinite(offset.norm2())) return "the starting points' offset must be finite";
  return {};
}

std::string View2D::Validate() const {
  if (width < 1 || height < 1 || width > 32768 || height > 32768) return "image size must be in [1, 32768]";
  if (!(x_max > x_min) || !(y_max > y_min)) return "the view box must have x_max > x_min and y_max > y_min";
  return {};
}

std::vector<double> SampleField2D(const QuaternionMap& map, const IterationOptions& o, const View2D& v) {
  std::vector<double> field(std::size_t(v.width) * v.height);
  const double dx = (v.x_max - v.x_min) / v.width, dy = (v.y_max - v.y_min) / v.height;
#pragma omp parallel for schedule(dynamic, 4)
  for (int py = 0; py < v.height; ++py)
    for (int px = 0; px < v.width; ++px) {
      const Quat q{v.x_min + (px + 0.5) * dx, v.y_max - (py + 0.5) * dy, 0.0, 0.0};
      field[std::size_t(py) * v.width + px] = IterateField(map, q, o);
    }
  return field;
}

Image FieldImage(const std::vector<double>& field, const View2D& v, double outside_scale) {
  Image img(v.width, v.height);
  for (std::size_t i = 0; i < field.size(); ++i) {
    const double f = field[i];
    if (f < 0) {
      img.pixels[i] = {0, 0, 0};
    } else {
      const double t = std::clamp(f / std::max(outside_scale, 1e-9), 0.0, 1.0);
      const auto g = std::uint8_t(std::lround(120 + 135 * std::sqrt(t)));
      img.pixels[i] = {g, g, g};
    }
  }
  return img;
}

Quat UnitPower(const Quat& d, double a) {
  if (a >= 0 && a <= 1024 && a == std::floor(a)) {
    unsigned n = unsigned(a);
    Quat result{1, 0, 0, 0}, base = d;
    while (n) {
      if (n & 1u) result = result * base;
      n >>= 1u;
      if (n) base = base * base;
    }
    return result;
  }
  const double vn = std::sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
  const double theta = std::atan2(vn, d.w);
  double ax = 1, ay = 0, az = 0;
  if (vn > 0) {
    ax = d.x / vn;
    ay = d.y / vn;
    az = d.z / vn;
  }
  const double phi = a * theta, s = std::sin(phi);
  return {std::cos(phi), ax * s, ay * s, az * s};
}

RationalQuaternionMap::RationalQuaternionMap(const RationalMap& map) : julia_(map, JuliaOptions{}) {}

RationalQuaternionMap::RationalQuaternionMap(const RationalMap& map, const JuliaOptions& options)
    : julia_(map, options) {}

double RationalQuaternionMap::LogModulus(const Quat& q) const {
  double log_modulus = 0.0;
  Quat versor;
  const double n = q.norm();
  julia_.Apply(q, std::log(n), n > 0 ? q * (1.0 / n) : Quat{1, 0, 0, 0}, log_modulus, versor);
  return log_modulus;
}

Quat RationalQuaternionMap::Apply(const Quat& q) const {
  double log_modulus = 0.0;
  Quat versor;
  const double n = q.norm();
  julia_.Apply(q, std::log(n), n > 0 ? q * (1.0 / n) : Quat{1, 0, 0, 0}, log_modulus, versor);
  return versor * std::exp(log_modulus);
}

}  // namespace quijibo
