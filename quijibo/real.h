// The floating types the toolkit runs in, and the few generic helpers they need.
//
// Precision modes: float, double, long double (x87 80-bit on x86-64) and float128 (IEEE quad,
// Boost.Multiprecision over GCC's __float128, in software). Generic code calls the math
// functions unqualified after `using std::log;` etc., so Boost's overloads are found by ADL.
#pragma once

#include <boost/multiprecision/float128.hpp>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

namespace quijibo {

using float128 = boost::multiprecision::float128;

enum class Precision { kFloat, kDouble, kLongDouble, kFloat128 };

template <class Real>
constexpr Precision PrecisionOf();
template <> constexpr Precision PrecisionOf<float>() { return Precision::kFloat; }
template <> constexpr Precision PrecisionOf<double>() { return Precision::kDouble; }
template <> constexpr Precision PrecisionOf<long double>() { return Precision::kLongDouble; }
template <> constexpr Precision PrecisionOf<float128>() { return Precision::kFloat128; }

// "float", "double", "long-double", "float128".
std::string PrecisionName(Precision p);
inline const std::vector<std::string> kPrecisionNames = {"float", "double", "long-double", "float128"};
// Inverse of PrecisionName (also accepts "long_double", "ld", "quad"); throws quijibo::Error.
Precision ParsePrecision(const std::string& name);

template <class Real>
inline bool IsFinite(const Real& x) {
  if constexpr (std::is_same_v<Real, float128>) {
    return boost::multiprecision::isfinite(x);
  } else {
    return std::isfinite(x);
  }
}

template <class Real>
inline double ToDouble(const Real& x) {
  return static_cast<double>(x);
}

// Calls fn.template operator()<Real>() with the Real of precision p.
template <class Fn>
decltype(auto) DispatchPrecision(Precision p, Fn&& fn) {
  switch (p) {
    case Precision::kFloat: return fn.template operator()<float>();
    case Precision::kDouble: return fn.template operator()<double>();
    case Precision::kLongDouble: return fn.template operator()<long double>();
    case Precision::kFloat128: break;
  }
  return fn.template operator()<float128>();
}

}  // namespace quijibo
