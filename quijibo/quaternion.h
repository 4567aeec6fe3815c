// Quaternion<Real>: q = w + x i + y j + z k, templated on the real type (float, double,
// long double, float128).
//
// A spatial point (X, Y, Z) on slice S is the quaternion [X, Y, Z, S] (real part X), as in the
// 2015 paper and the reference code.
//
//   log q = [ln|q|, v/|v| * theta],  theta = atan2(|v|, w) in [0, pi]
//   exp q = e^w [cos|v|, v/|v| sin|v|]
//   q^a   = exp(a log q) for every real a, negative ones included (the reference code drops the
//           imaginary part when a * theta <= 0; we don't).
// For a negative real q (v = 0, w < 0) the axis of log q is taken to be i, as for complex
// numbers; any unit axis is a valid logarithm there.
#pragma once

#include <ostream>

#include "quijibo/real.h"

namespace quijibo {

template <class Real>
struct Quaternion {
  Real w{0}, x{0}, y{0}, z{0};

  Quaternion() = default;
  constexpr Quaternion(Real w_, Real x_, Real y_, Real z_) : w(w_), x(x_), y(y_), z(z_) {}

  template <class Other>
  static Quaternion From(const Quaternion<Other>& q) {
    return Quaternion(Real(q.w), Real(q.x), Real(q.y), Real(q.z));
  }

  Quaternion operator+(const Quaternion& b) const { return {w + b.w, x + b.x, y + b.y, z + b.z}; }
  Quaternion operator-(const Quaternion& b) const { return {w - b.w, x - b.x, y - b.y, z - b.z}; }
  Quaternion operator-() const { return {-w, -x, -y, -z}; }
  Quaternion operator*(const Real& s) const { return {w * s, x * s, y * s, z * s}; }
  Quaternion& operator+=(const Quaternion& b) { return *this = *this + b; }

  // Hamilton product.
  Quaternion operator*(const Quaternion& b) const {
    return {w * b.w - x * b.x - y * b.y - z * b.z, w * b.x + x * b.w + y * b.z - z * b.y,
            w * b.y - x * b.z + y * b.w + z * b.x, w * b.z + x * b.y - y * b.x + z * b.w};
  }
  Quaternion& operator*=(const Quaternion& b) { return *this = *this * b; }

  Quaternion conj() const { return {w, -x, -y, -z}; }
  Real dot(const Quaternion& b) const { return w * b.w + x * b.x + y * b.y + z * b.z; }
  Real norm2() const { return dot(*this); }
  Real norm() const {
    using std::sqrt;
    return sqrt(norm2());
  }
  Real vector_norm() const {
    using std::sqrt;
    return sqrt(x * x + y * y + z * z);
  }
  // q^-1 = conj(q) / |q|^2 (inf/NaN for q = 0, as division by zero).
  Quaternion inverse() const { return conj() * (Real(1) / norm2()); }
  // Right division p / q = p q^-1 (the paper's convention).
  Quaternion operator/(const Quaternion& q) const { return *this * q.inverse(); }

  bool operator==(const Quaternion&) const = default;
};

template <class Real>
Quaternion<Real> operator*(const Real& s, const Quaternion<Real>& q) {
  return q * s;
}

// Unit axis of the vector part, or i when the vector part vanishes (see header comment).
template <class Real>
void VersorAxis(const Quaternion<Real>& q, Real& vn, Real& ax, Real& ay, Real& az) {
  vn = q.vector_norm();
  if (vn > Real(0)) {
    ax = q.x / vn;
    ay = q.y / vn;
    az = q.z / vn;
  } else {
    ax = Real(1);
    ay = Real(0);
    az = Real(0);
  }
}

template <class Real>
Quaternion<Real> log(const Quaternion<Real>& q) {
  using std::atan2;
  using std::log;
  Real vn, ax, ay, az;
  VersorAxis(q, vn, ax, ay, az);
  const Real theta = atan2(vn, q.w);
  return {log(q.norm()), ax * theta, ay * theta, az * theta};
}

template <class Real>
Quaternion<Real> exp(const Quaternion<Real>& q) {
  using std::cos;
  using std::exp;
  using std::sin;
  const Real vn = q.vector_norm();
  const Real ew = exp(q.w);
  if (vn == Real(0)) return {ew, Real(0), Real(0), Real(0)};
  const Real s = ew * sin(vn) / vn;
  return {ew * cos(vn), q.x * s, q.y * s, q.z * s};
}

// q^a for real a. a = 0 gives exactly 1 (also for q = 0); q = 0 with a > 0 gives 0.
template <class Real>
Quaternion<Real> pow(const Quaternion<Real>& q, const Real& a) {
  if (a == Real(0)) return {Real(1), Real(0), Real(0), Real(0)};
  if (q.norm2() == Real(0)) {
    const Real m = a > Real(0) ? Real(0) : std::numeric_limits<Real>::infinity();
    return {m, Real(0), Real(0), Real(0)};
  }
  return exp(log(q) * a);
}

// The polar form of d that the fused kernels (LogAndPower, the Julia iteration's versors) start from:
// |v| of the vector part, ln|d| and the angle theta = atan2(|v|, w), from one sum of squares.
template <class Real>
struct PolarForm {
  Real vector_norm, log_norm, theta;
};

template <class Real>
PolarForm<Real> Polar(const Quaternion<Real>& d) {
  using std::atan2;
  using std::log;
  using std::sqrt;
  const Real v2 = d.x * d.x + d.y * d.y + d.z * d.z;
  const Real vn = sqrt(v2);
  return {vn, Real(0.5) * log(d.w * d.w + v2), atan2(vn, d.w)};
}

// Fused log and power of one quaternion: lg = log(d) and p = d^a = exp(a lg), sharing the
// norms and the angle (the evaluators need both for every root of every cell).
template <class Real>
void LogAndPower(const Quaternion<Real>& d, const Real& a, Quaternion<Real>& lg, Quaternion<Real>& p) {
  using std::cos;
  using std::exp;
  using std::sin;
  const auto [vn, log_norm, theta] = Polar(d);
  Real ax(1), ay(0), az(0);  // axis i for reals, as log()
  if (vn > Real(0)) {
    const Real inv = Real(1) / vn;
    ax = d.x * inv;
    ay = d.y * inv;
    az = d.z * inv;
  }
  lg = {log_norm, ax * theta, ay * theta, az * theta};
  if (a == Real(0)) {
    p = {Real(1), Real(0), Real(0), Real(0)};
    return;
  }
  const Real m = exp(a * log_norm), phi = a * theta;
  const Real s = m * sin(phi);
  p = {m * cos(phi), ax * s, ay * s, az * s};
}

template <class Real>
std::ostream& operator<<(std::ostream& o, const Quaternion<Real>& q) {
  return o << "[" << q.w << ", " << q.x << ", " << q.y << ", " << q.z << "]";
}

}  // namespace quijibo
