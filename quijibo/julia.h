// Iterating the rational map: the quaternion Julia set of a map and its field (2015 paper §5,
// design brief §3.2).
//
// The map is the one the energies optimize (rational_map.h): R(q) = e^C T(q) B(q)^-1 with
// T = prod_i (q - t_i)^(tau T_i), B = prod_i (q - b_i)^(beta B_i), products left to right. Starting
// from q_0 = [x, y, z, S] (S the slice), q_{k+1} = R(q_k), n times, stopping early when
// |q_k| >= escape radius (reference: 2000). The field the reference meshes is
//
//   f(x) = log|q_m|,   m = n, or the first k with |q_k| >= escape radius,
//
// and the surface is the iso value 0 (|q_n| = 1; inside: f < 0), which for n = 1 is exactly the
// L = log|R| whose sign the energy fits.
//
// Log-polar iteration (the default, `Iterate`): each value is kept as (log-magnitude, unit versor).
// Because |p q| = |p||q| and |p^a| = |p|^a,
//   log|R(q)| = ln C + tau sum_i T_i log|q - t_i| - beta sum_i B_i log|q - b_i|,
//   versor(R) = u(P_1) ... u(P_nt) conj(u(Q_nb)) ... conj(u(Q_1)),
// u(P) = [cos(a theta), axis sin(a theta)] the versor of (q - r)^a, theta and axis those of q - r.
// Nothing overflows (T and B alone can exceed the range of double by hundreds of orders of
// magnitude), and q_k itself is only formed while |q_k| < escape radius. `IterateDirect` is the
// paper's form with quaternion products (overflows in double for realistic maps; in float128 it is
// the reference value the tests compare against).
//
// Options (the reference's meshing settings, quijibo-code.md §6):
//   root_translation  added to every root AND to every sample (the reference's "root translation":
//                     no change for n = 1, a different set for n > 1); a 4-vector [w, i, j, k]
//   root_scale        roots multiplied by this about the origin (before the translation)
//   slice             S, the k component of q_0
//   placement         where the sampling box lands: w = center + rotation (p - center) (zoom boxes
//                     with a rotation; the box itself is the mesher's or the picture's)
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <string>
#include <vector>

#include "quijibo/grid.h"
#include "quijibo/quaternion.h"
#include "quijibo/rational_map.h"

namespace quijibo {

// A rigid placement of sampling coordinates p in the fractal frame: w = center + rotation (p - center).
struct SampleTransform {
  std::array<double, 9> rotation{1, 0, 0, 0, 1, 0, 0, 0, 1};  // row-major
  Vec3 center{0.0, 0.0, 0.0};

  Vec3 apply(const Vec3& p) const {
    Vec3 d{p[0] - center[0], p[1] - center[1], p[2] - center[2]}, w;
    for (int r = 0; r < 3; ++r)
      w[r] = center[r] + rotation[3 * r] * d[0] + rotation[3 * r + 1] * d[1] + rotation[3 * r + 2] * d[2];
    return w;
  }
  bool is_identity() const { return rotation == std::array<double, 9>{1, 0, 0, 0, 1, 0, 0, 0, 1}; }
  // Rotation by `degrees` about `axis` (right hand), about `center`. Throws quijibo::Error for a
  // zero or non-finite axis.
  static SampleTransform AxisAngle(const Vec3& axis, double degrees, const Vec3& center);
};

struct JuliaOptions {
  int iterations = 4;             // n
  double escape_radius = 2000.0;  // reference TRIANGLE_MESH::_escapeRadius
  // An iterate with |q| below this is captured: it stops and counts as inside (log|q| < 0).
  // 0 is a super-attracting fixed point of an untranslated map, so there this changes no set; a
  // translated map moves its roots off 0, and the reference's bail-out (10 FLT_MIN) is what keeps
  // the deep inside of a steep map in the set (docs/meshing.md "Root translation").
  double capture_radius = 0.0;
  double slice = 0.0;             // S
  Vec4 root_translation{0.0, 0.0, 0.0, 0.0};
  double root_scale = 1.0;
  SampleTransform placement;
  std::string Validate() const;   // empty when valid
};

template <class Real>
struct JuliaResult {
  Real log_modulus{0};       // log|q_m|, the field value
  Quaternion<Real> versor;   // q_m / |q_m| (1 for q_m = 0)
  int iterations = 0;        // m: map applications done
  bool escaped = false;      // |q_m| >= escape radius
};

// The map prepared for iteration in precision Real (float, double, long double, float128).
template <class Real>
class JuliaMap {
 public:
  // Throws quijibo::Error when the map or the options are invalid.
  JuliaMap(const RationalMap& map, const JuliaOptions& options);

  // q_0 of the sampling point p (before placement): [w + t_xyz, S + t_k], w = placement(p).
  Quaternion<Real> StartingPoint(const Vec3& p) const;
  // Log-polar iteration from q0 (see the header comment).
  JuliaResult<Real> Iterate(const Quaternion<Real>& q0) const;
  // The paper's direct form: T, B and R formed as quaternion products (may overflow).
  JuliaResult<Real> IterateDirect(const Quaternion<Real>& q0) const;
  // One application of the map in log-polar form: log|R(q)| and versor(R(q)). q is given both as
  // a quaternion and as (log|q|, q/|q|): roots exactly at the origin (the reference's zero roots)
  // use the latter, so an iterate that underflows to 0 keeps its magnitude, and their
  // contributions are summed as (sum of their top exponents - bottom exponents) log|q| (no
  // inf - inf at q = 0).
  void Apply(const Quaternion<Real>& q, const Real& q_log, const Quaternion<Real>& q_versor, Real& log_modulus,
             Quaternion<Real>& versor) const;

  JuliaResult<Real> At(const Vec3& p) const { return Iterate(StartingPoint(p)); }
  const JuliaOptions& options() const { return options_; }

  // One factor of R as Apply multiplies it in: its root (translated and scaled), its signed
  // exponent (tau T_i for top roots, -beta B_i for bottom roots: the versor of Q^-b is conj(u(Q)^b)
  // = u(Q)^-b) and whether the root is exactly at the origin. For batch kernels (julia_batch.h).
  struct Factor {
    Quaternion<Real> root;
    Real exponent;
    bool zero;
  };
  // The factors in Apply's order: top roots in order, then bottom roots last to first.
  std::vector<Factor> Factors() const;
  const Real& ln_C() const { return ln_C_; }
  const Real& log_escape() const { return log_escape_; }
  const Real& log_capture() const { return log_capture_; }  // -inf when capture is off

 private:
  JuliaOptions options_;
  std::vector<Quaternion<Real>> top_, bottom_;  // translated and scaled roots
  std::vector<Real> top_exp_, bottom_exp_;      // tau T_i, beta B_i
  std::vector<char> top_zero_, bottom_zero_;    // root exactly at the origin
  Real ln_C_{0}, log_escape_{0}, log_capture_{0};
};

extern template class JuliaMap<float>;
extern template class JuliaMap<double>;
extern template class JuliaMap<long double>;
extern template class JuliaMap<float128>;

}  // namespace quijibo
