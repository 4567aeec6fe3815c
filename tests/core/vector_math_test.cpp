// quijibo/vector_math.h against glibc's scalar functions: the error bounds its header states, on
// millions of seeded random arguments, and the special values the Julia kernel meets.
#include <gtest/gtest.h>

#include <cfloat>
#include <cmath>
#include <limits>
#include <random>

#include "quijibo/vector_math.h"

namespace quijibo::vm {
namespace {

// |a - b| in units in the last place of b.
double Ulps(double a, double b) {
  if (a == b) return 0;
  const double u = b == 0 ? DBL_TRUE_MIN : std::nextafter(std::fabs(b), HUGE_VAL) - std::fabs(b);
  return std::fabs(a - b) / u;
}

constexpr int kSamples = 1 << 20;

TEST(VectorMath, LogWithinOneUlp) {
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> u(0, 1);
  double worst = 0;
  for (int i = 0; i < kSamples; ++i) {
    const double x = std::ldexp(1 + u(rng), int(u(rng) * 2098) - 1075);  // subnormal to near overflow
    const double near_one = 0.5 + 1.5 * u(rng);
    worst = std::max({worst, Ulps(VmLog(x), std::log(x)), Ulps(VmLog(near_one), std::log(near_one))});
  }
  std::printf("VmLog: max %.3g ulp from glibc's log\n", worst);
  EXPECT_LE(worst, 1.0);
  EXPECT_EQ(VmLog(0.0), -HUGE_VAL);
  EXPECT_EQ(VmLog(HUGE_VAL), HUGE_VAL);
  EXPECT_TRUE(std::isnan(VmLog(std::numeric_limits<double>::quiet_NaN())));
  EXPECT_TRUE(std::isnan(VmLog(-1.0)));
  EXPECT_EQ(VmLog(1.0), 0.0);
}

TEST(VectorMath, Atan2WithinTwoUlpForNonNegativeY) {
  std::mt19937_64 rng(2);
  std::uniform_real_distribution<double> u(0, 1);
  double worst = 0;
  for (int i = 0; i < kSamples; ++i) {
    const double y = std::ldexp(u(rng), int(u(rng) * 60) - 30), x = std::ldexp(u(rng) - 0.5, int(u(rng) * 60) - 30);
    worst = std::max(worst, Ulps(VmAtan2(y, x), std::atan2(y, x)));
  }
  std::printf("VmAtan2: max %.3g ulp from glibc's atan2\n", worst);
  EXPECT_LE(worst, 2.0);
  EXPECT_EQ(VmAtan2(0.0, 0.0), 0.0);
  EXPECT_EQ(VmAtan2(0.0, -0.0), std::atan2(0.0, -0.0));  // pi
  EXPECT_EQ(VmAtan2(0.0, -1.0), std::atan2(0.0, -1.0));
  EXPECT_EQ(VmAtan2(1.0, 0.0), std::atan2(1.0, 0.0));
  EXPECT_EQ(VmAtan2(2.0, -0.0), std::atan2(2.0, -0.0));
  EXPECT_TRUE(std::isnan(VmAtan2(std::numeric_limits<double>::quiet_NaN(), 1.0)));
  EXPECT_TRUE(std::isnan(VmAtan2(1.0, std::numeric_limits<double>::quiet_NaN())));
}

TEST(VectorMath, SinCosWithinTwoToTheMinus52) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  double worst_abs = 0, worst_ulp_small = 0;
  for (int i = 0; i < kSamples; ++i) {
    const double big = u(rng) * kSinCosMax, small = 4 * u(rng);
    double s, c;
    VmSinCos(big, s, c);
    worst_abs = std::max({worst_abs, std::fabs(s - std::sin(big)), std::fabs(c - std::cos(big))});
    VmSinCos(small, s, c);
    worst_abs = std::max({worst_abs, std::fabs(s - std::sin(small)), std::fabs(c - std::cos(small))});
    worst_ulp_small = std::max({worst_ulp_small, Ulps(s, std::sin(small)), Ulps(c, std::cos(small))});
  }
  std::printf("VmSinCos: max absolute error %.3g (|x| < %g), max %.3g ulp for |x| < 4\n", worst_abs, kSinCosMax,
              worst_ulp_small);
  EXPECT_LE(worst_abs, DBL_EPSILON);
  EXPECT_LE(worst_ulp_small, 2.0);
  double s, c;
  VmSinCos(0.0, s, c);
  EXPECT_EQ(s, 0.0);
  EXPECT_EQ(c, 1.0);
  VmSinCos(std::numeric_limits<double>::quiet_NaN(), s, c);
  EXPECT_TRUE(std::isnan(s) && std::isnan(c));
}

}  // namespace
}  // namespace quijibo::vm
