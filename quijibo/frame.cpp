#include "quijibo/frame.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "util/error.h"

namespace quijibo {

namespace {

std::string Number(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", x);
  return buf;
}

std::string Point(const Vec3& p) {
  char buf[96];
  std::snprintf(buf, sizeof buf, "(%.6g, %.6g, %.6g)", p[0], p[1], p[2]);
  return buf;
}

}  // namespace

std::string FrameDifference(const FractalFrame& a, const FractalFrame& b) {
  const auto same = [](double x, double y) { return std::abs(x - y) <= 1e-9 * std::max(1.0, std::abs(x)); };
  const auto same3 = [&](const Vec3& x, const Vec3& y) {
    return same(x[0], y[0]) && same(x[1], y[1]) && same(x[2], y[2]);
  };
  std::string d;
  const auto add = [&](const std::string& field, const std::string& x, const std::string& y) {
    d += (d.empty() ? "" : ", ") + field + " " + x + " vs " + y;
  };
  if (!same3(a.origin, b.origin)) add("origin", Point(a.origin), Point(b.origin));
  if (!same(a.fractal_radius, b.fractal_radius))
    add("fractal_radius", Number(a.fractal_radius), Number(b.fractal_radius));
  if (!same(a.scale, b.scale)) add("scale", Number(a.scale), Number(b.scale));
  if (!same3(a.translation, b.translation)) add("translation", Point(a.translation), Point(b.translation));
  if (!same(a.padding, b.padding)) add("padding", Number(a.padding), Number(b.padding));
  return d;
}

std::string FractalFrame::Validate() const {
  if (!(fractal_radius > 0.0) || !std::isfinite(fractal_radius))
    return "fractal_radius must be a positive finite number";
  if (!(padding >= 0.0 && padding < 0.5)) return "padding must be in [0, 0.5)";
  if (!(scale > 0.0) || !std::isfinite(scale)) return "scale must be a positive finite number";
  for (double t : translation)
    if (!std::isfinite(t)) return "translation must be finite";
  for (double o : origin)
    if (!(o >= 0.0 && o <= 1.0)) return "origin must lie in the unit cube [0, 1]^3";
  return {};
}


GridFrame TargetGridFrame(int n, const FractalFrame& frame, TargetBox box) {
  const double side = box == TargetBox::kUnitCube
                          ? frame.fractal_radius
                          : frame.fractal_radius * (1.0 - 2.0 * frame.padding) * (n + 2.0) / n;
  return GridFrame::Cube(n, frame.box_center(), side);
}

}  // namespace quijibo
