// Branch-free double log, atan2 (y >= 0) and fused sincos for SIMD loops (the "fused" Julia kernel,
// julia_batch.h): every lane runs the same instructions, so `#pragma omp simd` loops that call them
// vectorize without a vector math library, and sin and cos share one range reduction.
//
// The polynomials are the classical ones: log from fdlibm (e_log.c: 2 atanh(s), s = f / (2 + f),
// a degree-14 even polynomial), atan from Cephes (atan.c: a 4/5 rational in x^2 after reduction to
// |x| <= 0.66), sin and cos from Cephes (sin.c: degree 13 and 14 on |r| <= pi/4) after a
// three-part Cody-Waite reduction by pi/2 (fdlibm's constants; exact for |x| < kSinCosMax).
// Error bounds against glibc's scalar functions, asserted by tests/core/vector_math_test.cpp on a
// million seeded random arguments each (measured, not proven):
//   VmLog     <= 1 ulp for positive finite x, subnormals included; 0 -> -inf, inf -> inf, NaN -> NaN
//   VmAtan2   <= 2 ulp for y >= 0 (the angle of a versor, in [0, pi]); atan2(0, -0) = pi
//   VmSinCos  absolute error <= 2^-52 for |x| < kSinCosMax (<= 2 ulp for |x| < 4); beyond, the
//             caller uses another method
// glibc's libmvec, which the "vector" kernel calls, documents at most 4 ulp for its variants.
#pragma once

#include <bit>
#include <cmath>
#include <cstdint>

namespace quijibo::vm {

// Arguments of VmSinCos above this are not reduced accurately (n pi/2 with n >= 2^19).
inline constexpr double kSinCosMax = 8.0e5;

[[gnu::always_inline]] inline double VmLog(double x) {
  constexpr double ln2_hi = 6.93147180369123816490e-01, ln2_lo = 1.90821492927058770002e-10;
  constexpr double Lg1 = 6.666666666666735130e-01, Lg2 = 3.999999999940941908e-01, Lg3 = 2.857142874366239149e-01,
                   Lg4 = 2.222219843214978396e-01, Lg5 = 1.818357216161805012e-01, Lg6 = 1.531383769920937332e-01,
                   Lg7 = 1.479819860511658591e-01;
  const bool sub = x < 0x1p-1022;  // subnormal (and 0): scaled into the normal range
  const double xs = sub ? x * 0x1p54 : x;
  std::uint64_t u = std::bit_cast<std::uint64_t>(xs);
  // 1 + f in [sqrt(2)/2, sqrt(2)): the exponent taken from u shifted by the mantissa of sqrt(2)/2.
  u += 0x3ff0000000000000ull - 0x3fe6a09e667f3bcdull;
  const std::uint64_t e = u >> 52;  // k + 1023 (as bits of a small integer)
  const double k = std::bit_cast<double>(e | 0x4330000000000000ull) - (0x1p52 + 1023.0) - (sub ? 54.0 : 0.0);
  const double m = std::bit_cast<double>((u & 0x000fffffffffffffull) + 0x3fe6a09e667f3bcdull);
  const double f = m - 1.0;
  const double s = f / (2.0 + f), z = s * s, w = z * z;
  const double t1 = w * (Lg2 + w * (Lg4 + w * Lg6));
  const double t2 = z * (Lg1 + w * (Lg3 + w * (Lg5 + w * Lg7)));
  const double R = t2 + t1, hfsq = 0.5 * f * f;
  const double r = k * ln2_hi - ((hfsq - (s * (hfsq + R) + k * ln2_lo)) - f);
  // Special values: 0 -> -inf, +inf and NaN themselves, negative -> NaN.
  const double special = x == 0 ? -HUGE_VAL : x < 0 ? (x - x) / 0.0 : x + x;
  return (x > 0 && x < HUGE_VAL) ? r : special;
}

// atan2(y, x) for y >= 0 (or NaN): in [0, pi].
[[gnu::always_inline]] inline double VmAtan2(double y, double x) {
  constexpr double P0 = -8.750608600031904122785E-1, P1 = -1.615753718733365076637E1,
                   P2 = -7.500855792314704667340E1, P3 = -1.228866684490136173410E2,
                   P4 = -6.485021904942025371773E1;
  constexpr double Q0 = 2.485846490142306297962E1, Q1 = 1.650270098316988542046E2, Q2 = 4.328810604912902668951E2,
                   Q3 = 4.853903996359136964868E2, Q4 = 1.945506571482613964425E2;
  constexpr double T3P8 = 2.41421356237309504880, MOREBITS = 6.123233995736765886130E-17;
  constexpr double PIO2 = 1.57079632679489661923, PIO4 = 7.85398163397448309616E-1;
  constexpr double PI_HI = 3.14159265358979311600e+00, PI_LO = 1.2246467991473531772E-16;
  const double ax = std::fabs(x);
  // atan(y / ax) = y0 + atan(t): one division for the three ranges of y / ax.
  const bool big = y > T3P8 * ax, mid = !big && y > 0.66 * ax;
  const double num = big ? -ax : mid ? y - ax : y;
  const double den = big ? y : mid ? y + ax : ax;
  const double t = num / den;
  const double y0 = big ? PIO2 : mid ? PIO4 : 0.0;
  const double more = big ? 0.5 * MOREBITS : mid ? 0.25 * MOREBITS : 0.0;
  const double z = t * t;
  const double p = (((P0 * z + P1) * z + P2) * z + P3) * z + P4;
  const double q = ((((z + Q0) * z + Q1) * z + Q2) * z + Q3) * z + Q4;
  const double a = y0 + ((t * (z * p / q) + t) + more);  // atan(y / |x|) in [0, pi/2]
  const double r = x < 0 ? (PI_HI - a) + PI_LO : a;
  // y = 0 (0 / 0 above when x = 0 too): 0 or pi by the sign bit of x (atan2(0, -0) = pi), taken by
  // an integer compare (std::signbit and std::isnan keep GCC from vectorizing); NaN stays NaN.
  const double zero = std::bit_cast<std::int64_t>(x) < 0 ? PI_HI : 0.0;
  return y == 0 && x == x ? zero : r;
}

// sin(x) and cos(x) with one reduction; |x| < kSinCosMax.
[[gnu::always_inline]] inline void VmSinCos(double x, double& s, double& c) {
  constexpr double S0 = 1.58962301576546568060E-10, S1 = -2.50507477628578072866E-8, S2 = 2.75573136213857245213E-6,
                   S3 = -1.98412698295895385996E-4, S4 = 8.33333333332211858878E-3, S5 = -1.66666666666666307295E-1;
  constexpr double C0 = -1.13585365213876817300E-11, C1 = 2.08757008419747316778E-9, C2 = -2.75573141792967388112E-7,
                   C3 = 2.48015872888517045348E-5, C4 = -1.38888888888730564116E-3, C5 = 4.16666666666665929218E-2;
  constexpr double INV_PIO2 = 6.36619772367581382433e-01;
  constexpr double PIO2_1 = 1.57079632673412561417e+00, PIO2_2 = 6.07710050630396597660e-11,
                   PIO2_3 = 2.02226624871116645580e-21;
  // n = rint(x 2 / pi) by the 1.5 2^52 shift: its low bits are n's (two's complement).
  const double shifted = x * INV_PIO2 + 0x1.8p52;
  const double n = shifted - 0x1.8p52;
  const std::uint64_t quadrant = std::bit_cast<std::uint64_t>(shifted) & 3;
  const double r = ((x - n * PIO2_1) - n * PIO2_2) - n * PIO2_3;
  const double z = r * r;
  const double sr = r + r * z * (((((S0 * z + S1) * z + S2) * z + S3) * z + S4) * z + S5);
  const double cr = 1.0 - 0.5 * z + z * z * (((((C0 * z + C1) * z + C2) * z + C3) * z + C4) * z + C5);
  const bool swap = quadrant & 1;
  const double s0 = swap ? cr : sr, c0 = swap ? sr : cr;
  s = (quadrant & 2) ? -s0 : s0;
  c = ((quadrant + 1) & 2) ? -c0 : c0;
}

}  // namespace quijibo::vm
