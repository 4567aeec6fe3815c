// Iterating any quaternion map H -> H and the field that is meshed or drawn: the generic form
// the shape modulus (2023) and portals (2024) use, and QUIJIBO rational maps through an adapter
// over JuliaMap (julia.h, which holds the rational map's log-polar iteration and its options).
//
//   q_0 = start + offset;  while |q| < escape_radius and n < iterations
//                                and not (n > 0 and |q| < capture_radius): q <- F(q), n += 1
//   field(start) = log|q_n|
//
// The surface is field = 0 (|q_n| = 1); inside is field < 0. This is the reference codes'
// convention for both the 2015 meshing and the 2023 shape modulus (log|q_n| - log 1). The value
// is clamped to [-700, 700] so that an iterate that underflows to 0 (deep inside) or overflows to
// infinity (far outside) stays finite, with the right sign; NaN iterates count as outside (+700).
#pragma once

#include <cmath>

#include <memory>

#include "util/image.h"
#include "quijibo/julia.h"
#include "quijibo/quaternion.h"
#include "quijibo/rational_map.h"

namespace quijibo {

using Quat = Quaternion<double>;

// A map H -> H applied once per iteration. Implementations must be thread-safe (const).
class QuaternionMap {
 public:
  virtual ~QuaternionMap() = default;
  virtual Quat Apply(const Quat& q) const = 0;
};

struct IterationOptions {
  int iterations = 3;
  double escape_radius = 20.0;
  // Which set is the inside: false, |q_n| < 1 (the convention of QUIJIBO, the shape modulus and
  // portals: the field log|q_n|); true, the orbit stays within the escape radius for n steps (the
  // filled Julia set of a polynomial such as q^2 + c: the field log|q_m| - log(escape radius)).
  bool bounded = false;
  // Added to every starting point. A QUIJIBO map with a root translation t moves its samples with
  // its roots (q_0 = p + t, julia.h), and the inside stays |q_n| < 1 in the translated coordinates,
  // so the translation is not a change of variables of F and is carried here.
  Quat offset{0.0, 0.0, 0.0, 0.0};
  // An iterate (after the first step) with |q| below this stops and counts as inside: the
  // reference's bail-out that keeps a translated map's deep inside in the set (JuliaOptions). 0: off.
  double capture_radius = 0.0;
  std::string Validate() const;
};

inline constexpr double kFieldClamp = 700.0;

// log|q_n| clamped to [-700, 700], minus log(escape radius) when `bounded`; `used` (if given)
// receives n.
inline double IterateField(const QuaternionMap& map, Quat q, const IterationOptions& o, int* used = nullptr) {
  const double escape2 = o.escape_radius * o.escape_radius;
  const double capture2 = o.capture_radius * o.capture_radius;
  q += o.offset;
  int n = 0;
  double r2 = q.norm2();
  while (r2 < escape2 && n < o.iterations && !(n > 0 && r2 < capture2)) {
    q = map.Apply(q);
    r2 = q.norm2();
    ++n;
  }
  if (used) *used = n;
  if (std::isnan(r2)) return kFieldClamp;
  if (r2 <= 0.0) return -kFieldClamp;
  const double v = 0.5 * std::log(r2);
  const double clamped = v < -kFieldClamp ? -kFieldClamp : (v > kFieldClamp ? kFieldClamp : v);
  return o.bounded ? clamped - std::log(o.escape_radius) : clamped;
}

// A QUIJIBO rational map R(q) = e^C T(q) B(q)^-1 as a QuaternionMap: one application of
// JuliaMap<double>::Apply (the log-polar form, julia.h) turned back into a quaternion. Only the
// final e^{log|R|} can over/underflow (to inf/0, which the iteration treats as escaped/inside).
class RationalQuaternionMap : public QuaternionMap {
 public:
  explicit RationalQuaternionMap(const RationalMap& map);
  // With `options`' root translation and scale (its roots moved; the samples' offset is the
  // iteration's, IterationOptions::offset).
  RationalQuaternionMap(const RationalMap& map, const JuliaOptions& options);
  Quat Apply(const Quat& q) const override;
  // log|R(q)| alone (the 2015 energy's L).
  double LogModulus(const Quat& q) const;

 private:
  JuliaMap<double> julia_;
};

// 2D (complex plane) sampling: pixel (px, py), row 0 at the top, is the point
//   x = x_min + (px + 1/2) (x_max - x_min) / width,  y = y_max - (py + 1/2) (y_max - y_min) / height
// iterated from q = [x, y, 0, 0]. OpenMP over rows.
struct View2D {
  double x_min = -1, x_max = 1, y_min = -1, y_max = 1;
  int width = 1600, height = 1600;
  std::string Validate() const;
};
std::vector<double> SampleField2D(const QuaternionMap& map, const IterationOptions& options, const View2D& view);
// Inside (field < 0) black; outside grey, brighter the sooner it escapes (field scaled by
// `outside_scale`, e.g. log(escape radius)).
Image FieldImage(const std::vector<double>& field, const View2D& view, double outside_scale);

// d^a for a unit quaternion d (|d| = 1): by repeated squaring when a is a non-negative integer
// (exact, and cheap: no transcendental functions), else in polar form cos(a t) + n sin(a t).
Quat UnitPower(const Quat& d, double a);

}  // namespace quijibo
