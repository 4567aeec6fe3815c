// Small Vec3 helpers shared by the monopole sources (internal; not part of the public API).
#pragma once

#include <cmath>

#include "quijibo/grid.h"

namespace quijibo::monopole::monopole_detail {

inline Vec3 Sub(const Vec3& a, const Vec3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
inline Vec3 Add(const Vec3& a, const Vec3& b) { return {a[0] + b[0], a[1] + b[1], a[2] + b[2]}; }
inline Vec3 Scale(const Vec3& a, double s) { return {a[0] * s, a[1] * s, a[2] * s}; }
inline double Dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
inline Vec3 Cross(const Vec3& a, const Vec3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
inline double Norm(const Vec3& a) { return std::sqrt(Dot(a, a)); }
inline double Distance(const Vec3& a, const Vec3& b) { return Norm(Sub(a, b)); }

// The gradient of `sdf` at p by central differences one grid spacing wide (trilinear samples).
inline Vec3 Gradient(const ScalarGrid& sdf, const Vec3& p) {
  const double h = sdf.frame.spacing;
  Vec3 g;
  for (int a = 0; a < 3; ++a) {
    Vec3 lo = p, hi = p;
    lo[a] -= h, hi[a] += h;
    g[a] = (sdf.sample(hi) - sdf.sample(lo)) / (2 * h);
  }
  return g;
}

}  // namespace quijibo::monopole::monopole_detail
