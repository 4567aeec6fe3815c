#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <utility>
#include <vector>

#include "quijibo/quaternion.h"

namespace quijibo {
namespace {

template <class Real>
class QuaternionTest : public ::testing::Test {};
using RealTypes = ::testing::Types<float, double, long double, float128>;
TYPED_TEST_SUITE(QuaternionTest, RealTypes);

template <class Real>
Real Tol() {
  if constexpr (std::is_same_v<Real, float>) return Real(2e-5);
  else if constexpr (std::is_same_v<Real, double>) return Real(1e-13);
  else if constexpr (std::is_same_v<Real, long double>) return Real(1e-16);
  else return Real(1e-30);
}

template <class Real>
Real Dist(const Quaternion<Real>& a, const Quaternion<Real>& b) {
  return (a - b).norm() / std::max(Real(1), b.norm());
}

// `count` quaternions with components uniform in [-2, 2), drawn in order from a generator seeded
// with `seed`.
template <class Real>
std::vector<Quaternion<Real>> RandomQuaternions(std::uint64_t seed, int count) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-2, 2);
  std::vector<Quaternion<Real>> q(count);
  for (auto& x : q) x = {Real(u(rng)), Real(u(rng)), Real(u(rng)), Real(u(rng))};
  return q;
}

// RandomQuaternions(seed, count), the n-th paired with the exponent first + n step.
template <class Real>
std::vector<std::pair<Quaternion<Real>, Real>> RandomPowers(std::uint64_t seed, int count, double first, double step) {
  const std::vector<Quaternion<Real>> q = RandomQuaternions<Real>(seed, count);
  std::vector<std::pair<Quaternion<Real>, Real>> powers;
  for (int n = 0; n < count; ++n) powers.emplace_back(q[n], Real(first + n * step));
  return powers;
}

TYPED_TEST(QuaternionTest, ProductIsHamiltonAndNormIsMultiplicative) {
  using Real = TypeParam;
  using Q = Quaternion<Real>;
  const Q i(0, 1, 0, 0), j(0, 0, 1, 0), k(0, 0, 0, 1), m1(-1, 0, 0, 0);
  EXPECT_EQ(i * j, k);
  EXPECT_EQ(j * i, -k);
  EXPECT_EQ(i * i, m1);
  EXPECT_EQ(i * j * k, m1);
  const std::vector<Q> q = RandomQuaternions<Real>(7, 3 * 50);
  for (int n = 0; n < 50; ++n) {
    const Q &a = q[3 * n], &b = q[3 * n + 1], &c = q[3 * n + 2];
    EXPECT_LE(abs((a * b).norm() - a.norm() * b.norm()), Tol<Real>() * 16);
    EXPECT_LE(Dist((a * b) * c, a * (b * c)), Tol<Real>() * 16);
    EXPECT_LE(Dist(a * a.inverse(), Q(1, 0, 0, 0)), Tol<Real>() * 4);
    EXPECT_LE(Dist((a / b) * b, a), Tol<Real>() * 16);
  }
}

TYPED_TEST(QuaternionTest, ExpInvertsLog) {
  using Real = TypeParam;
  using Q = Quaternion<Real>;
  for (const Q& a : RandomQuaternions<Real>(11, 50)) EXPECT_LE(Dist(exp(log(a)), a), Tol<Real>() * 16);
  // Negative reals: log has angle pi about the i axis, so exp(log) still inverts it.
  const Q neg(-2, 0, 0, 0);
  EXPECT_LE(Dist(exp(log(neg)), neg), Tol<Real>() * 16);
}

TYPED_TEST(QuaternionTest, PowerIsRightForEveryExponentSign) {
  using Real = TypeParam;
  using Q = Quaternion<Real>;
  for (const auto& [a, x] : RandomPowers<Real>(3, 30, 0.37, 0.1)) {
    // Integer powers against repeated products, both signs.
    EXPECT_LE(Dist(pow(a, Real(3)), a * a * a), Tol<Real>() * 64);
    EXPECT_LE(Dist(pow(a, Real(-2)), (a * a).inverse()), Tol<Real>() * 64);
    // a^x a^-x = 1 and |a^x| = |a|^x for fractional x (the reference code breaks this: it drops
    // the imaginary part for negative exponents).
    EXPECT_LE(Dist(pow(a, x) * pow(a, -x), Q(1, 0, 0, 0)), Tol<Real>() * 64);
    using std::pow;
    EXPECT_LE(abs(pow(a, -x).norm() - pow(a.norm(), -x)) / pow(a.norm(), -x), Tol<Real>() * 64);
    // Powers of one quaternion commute and add.
    EXPECT_LE(Dist(pow(a, Real(0.5)) * pow(a, Real(1.25)), pow(a, Real(1.75))), Tol<Real>() * 64);
  }
  EXPECT_EQ(pow(Q(0, 0, 0, 0), Real(0)), Q(1, 0, 0, 0));
  EXPECT_EQ(pow(Q(0, 0, 0, 0), Real(2)), Q(0, 0, 0, 0));
}

TYPED_TEST(QuaternionTest, FusedLogAndPowerMatchesLogAndPow) {
  using Real = TypeParam;
  using Q = Quaternion<Real>;
  for (const auto& [d, a] : RandomPowers<Real>(5, 30, -2.5, 0.2)) {
    Q lg, p;
    LogAndPower(d, a, lg, p);
    EXPECT_LE(Dist(lg, log(d)), Tol<Real>() * 16);
    EXPECT_LE(Dist(p, pow(d, a)), Tol<Real>() * 64);
  }
}

}  // namespace
}  // namespace quijibo
