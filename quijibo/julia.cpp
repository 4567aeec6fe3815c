#include "quijibo/julia.h"

#include <cmath>
#include <limits>

#include "util/error.h"

namespace quijibo {

SampleTransform SampleTransform::AxisAngle(const Vec3& axis, double degrees, const Vec3& center) {
  const double n = std::sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
  if (!(n > 0) || !std::isfinite(n) || !std::isfinite(degrees))
    throw Error("rotation: the axis must be finite and non-zero and the angle finite");
  const double x = axis[0] / n, y = axis[1] / n, z = axis[2] / n;
  const double a = degrees * M_PI / 180.0, c = std::cos(a), s = std::sin(a), t = 1 - c;
  SampleTransform r;
  r.rotation = {t * x * x + c,     t * x * y - s * z, t * x * z + s * y,
                t * x * y + s * z, t * y * y + c,     t * y * z - s * x,
                t * x * z - s * y, t * y * z + s * x, t * z * z + c};
  r.center = center;
  return r;
}

std::string JuliaOptions::Validate() const {
  if (iterations < 1 || iterations > 1000) return "iterations must be in [1, 1000]";
  if (!(escape_radius > 1.0) || !std::isfinite(escape_radius)) return "escape radius must be finite and > 1";
  if (!(capture_radius >= 0.0 && capture_radius <= 1.0)) return "capture radius must be in [0, 1]";
  if (!std::isfinite(slice)) return "slice must be finite";
  for (double t : root_translation)
    if (!std::isfinite(t)) return "root translation must be finite";
  if (!(root_scale > 0) || !std::isfinite(root_scale)) return "root scale must be finite and > 0";
  for (double r : placement.rotation)
    if (!std::isfinite(r)) return "rotation must be finite";
  return {};
}

template <class Real>
JuliaMap<Real>::JuliaMap(const RationalMap& map, const JuliaOptions& options) : options_(options) {
  if (auto why = map.Validate(); !why.empty()) throw Error("map: " + why);
  if (auto why = options.Validate(); !why.empty()) throw Error(why);
  const Vec4& t = options.root_translation;
  auto place = [&](const Vec4& r) {
    return Quaternion<Real>(Real(options.root_scale * r[0] + t[0]), Real(options.root_scale * r[1] + t[1]),
                            Real(options.root_scale * r[2] + t[2]), Real(options.root_scale * r[3] + t[3]));
  };
  // Roots with a zero exponent contribute exactly 1 (and would give 0 * inf on the root itself).
  for (int i = 0; i < map.top_count(); ++i)
    if (map.tau * map.top_exponents[i] != 0) {
      top_.push_back(place(map.top_roots[i]));
      top_zero_.push_back(top_.back() == Quaternion<Real>());
      top_exp_.push_back(Real(map.tau) * Real(map.top_exponents[i]));
    }
  for (int i = 0; i < map.bottom_count(); ++i)
    if (map.beta * map.bottom_exponents[i] != 0) {
      bottom_.push_back(place(map.bottom_roots[i]));
      bottom_zero_.push_back(bottom_.back() == Quaternion<Real>());
      bottom_exp_.push_back(Real(map.beta) * Real(map.bottom_exponents[i]));
    }
  ln_C_ = Real(map.ln_C);
  using std::log;
  log_escape_ = log(Real(options.escape_radius));
  log_capture_ = options.capture_radius > 0 ? log(Real(options.capture_radius)) : -std::numeric_limits<Real>::infinity();
}

template <class Real>
Quaternion<Real> JuliaMap<Real>::StartingPoint(const Vec3& p) const {
  const Vec3 w = options_.placement.apply(p);
  const Vec4& t = options_.root_translation;
  return {Real(w[0]) + Real(t[0]), Real(w[1]) + Real(t[1]), Real(w[2]) + Real(t[2]),
          Real(options_.slice) + Real(t[3])};
}

namespace {

// log|d| and the versor of d^a: [cos(a theta), axis sin(a theta)].
template <class Real>
inline void LogAndVersor(const Quaternion<Real>& d, const Real& a, Real& log_norm, Quaternion<Real>& u) {
  using std::cos;
  using std::sin;
  const PolarForm<Real> polar = Polar(d);
  const Real vn = polar.vector_norm;
  log_norm = polar.log_norm;
  const Real phi = a * polar.theta;
  const Real c = cos(phi), s = sin(phi);
  if (vn > Real(0)) {
    const Real k = s / vn;
    u = {c, d.x * k, d.y * k, d.z * k};
  } else {
    u = {c, s, Real(0), Real(0)};  // axis i for reals, as quaternion.h's log
  }
}

// The polar split of q that JuliaResult reports: log|q| and the versor q / |q| (1 for q = 0).
template <class Real>
void LogModulusAndVersor(const Quaternion<Real>& q, Real& log_modulus, Quaternion<Real>& versor) {
  using std::log;
  using std::sqrt;
  const Real n = sqrt(q.norm2());
  log_modulus = log(n);
  versor = n > Real(0) ? q * (Real(1) / n) : Quaternion<Real>(Real(1), Real(0), Real(0), Real(0));
}

// Multiplies one factor (q - root)^e of R into Apply's sums: its versor into u, and e log|q - root|
// into L; a bottom factor (kBottom) enters as its inverse: the conjugate versor, -e log|q - root|.
// A root at the origin takes q's own versor and adds +-e to zero_coefficient instead of L: the
// caller adds zero_coefficient log|q| once.
template <bool kBottom, class Real>
inline void MultiplyFactor(const Quaternion<Real>& q, const Quaternion<Real>& q_versor, const Quaternion<Real>& root,
                           const Real& e, bool root_at_origin, Real& L, Real& zero_coefficient, Quaternion<Real>& u) {
  Real ln;
  Quaternion<Real> f;
  if (root_at_origin) {
    LogAndVersor(q_versor, e, ln, f);
    if constexpr (kBottom)
      zero_coefficient -= e;
    else
      zero_coefficient += e;
  } else {
    LogAndVersor(q - root, e, ln, f);
    if constexpr (kBottom)
      L -= e * ln;
    else
      L += e * ln;
  }
  if constexpr (kBottom)
    u = u * f.conj();
  else
    u = u * f;
}

}  // namespace

template <class Real>
void JuliaMap<Real>::Apply(const Quaternion<Real>& q, const Real& q_log, const Quaternion<Real>& q_versor,
                           Real& log_modulus, Quaternion<Real>& versor) const {
  using std::sqrt;
  Real L = ln_C_, zero_coefficient(0);
  Quaternion<Real> u(Real(1), Real(0), Real(0), Real(0));
  for (std::size_t i = 0; i < top_.size(); ++i)
    MultiplyFactor<false>(q, q_versor, top_[i], top_exp_[i], top_zero_[i] != 0, L, zero_coefficient, u);
  // B^-1 = Q_nb^-1 ... Q_1^-1; the versor of Q^-1 is conj(u(Q)).
  for (std::size_t i = bottom_.size(); i-- > 0;)
    MultiplyFactor<true>(q, q_versor, bottom_[i], bottom_exp_[i], bottom_zero_[i] != 0, L, zero_coefficient, u);
  if (zero_coefficient != Real(0)) L += zero_coefficient * q_log;
  const Real un = sqrt(u.norm2());  // products of unit quaternions drift by rounding only
  log_modulus = L;
  versor = u * (Real(1) / un);
}

template <class Real>
std::vector<typename JuliaMap<Real>::Factor> JuliaMap<Real>::Factors() const {
  std::vector<Factor> f;
  for (std::size_t i = 0; i < top_.size(); ++i) f.push_back({top_[i], top_exp_[i], top_zero_[i] != 0});
  for (std::size_t i = bottom_.size(); i-- > 0;) f.push_back({bottom_[i], -bottom_exp_[i], bottom_zero_[i] != 0});
  return f;
}

template <class Real>
JuliaResult<Real> JuliaMap<Real>::Iterate(const Quaternion<Real>& q0) const {
  using std::exp;
  JuliaResult<Real> r;
  Quaternion<Real> q = q0;
  LogModulusAndVersor(q0, r.log_modulus, r.versor);
  for (int k = 0; k < options_.iterations; ++k) {
    if (!(r.log_modulus < log_escape_)) break;  // escaped (or NaN)
    if (k > 0 && r.log_modulus < log_capture_) break;  // captured (the start itself is not)
    Apply(q, r.log_modulus, r.versor, r.log_modulus, r.versor);
    ++r.iterations;
    if (r.log_modulus < log_escape_) q = r.versor * exp(r.log_modulus);
  }
  r.escaped = r.log_modulus >= log_escape_;
  return r;
}

template <class Real>
JuliaResult<Real> JuliaMap<Real>::IterateDirect(const Quaternion<Real>& q0) const {
  using std::exp;
  using std::sqrt;
  JuliaResult<Real> r;
  Quaternion<Real> q = q0;
  const Real escape(options_.escape_radius);
  const Real eC = exp(ln_C_);
  for (int k = 0; k < options_.iterations; ++k) {
    if (!(sqrt(q.norm2()) < escape)) break;
    if (k > 0 && sqrt(q.norm2()) < Real(options_.capture_radius)) break;
    Quaternion<Real> T(Real(1), Real(0), Real(0), Real(0)), B = T, lg, p;
    for (std::size_t i = 0; i < top_.size(); ++i) {
      LogAndPower(q - top_[i], top_exp_[i], lg, p);
      T = T * p;
    }
    for (std::size_t i = 0; i < bottom_.size(); ++i) {
      LogAndPower(q - bottom_[i], bottom_exp_[i], lg, p);
      B = B * p;
    }
    q = (T * B.inverse()) * eC;
    ++r.iterations;
  }
  LogModulusAndVersor(q, r.log_modulus, r.versor);
  r.escaped = !(sqrt(q.norm2()) < escape);
  return r;
}

template class JuliaMap<float>;
template class JuliaMap<double>;
template class JuliaMap<long double>;
template class JuliaMap<float128>;

}  // namespace quijibo
