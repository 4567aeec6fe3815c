// Iterating the map: log-polar form against the paper's direct products in float128, the
// one-application identity, escape, root translation.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "util/error.h"
#include "quijibo/julia.h"
#include "quijibo/rational_map.h"
#include "tests/core/julia_fixtures.h"

namespace quijibo {
namespace {

RationalMap SmallMap(std::uint64_t seed = 3) { return testing::JuliaTestMap(seed); }

// One top root at the origin with a steep exponent (and a negligible bottom root): L = ln C +
// 40 log|q|, with ln C = 0 the one-step set the unit ball, |grad L| = 40 on its surface.
RationalMap SteepBallMap() {
  RationalMap m;
  m.top_roots = {{0, 0, 0, 0}};
  m.top_exponents = {40.0};
  m.bottom_roots = {{2.9, 0, 0, 0}};
  m.bottom_exponents = {1e-9};
  m.ln_C = 0.0;
  return m;
}

std::vector<Vec3> Points(int n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::vector<Vec3> p(n);
  for (auto& x : p)
    for (double& c : x) c = -2.0 + 4.0 * double(rng() >> 11) / double(1ull << 53);
  return p;
}

// Acceptance criterion of issue 5: log-polar double iteration vs float128 (direct quaternion
// products) within 1e-9 relative on the points that do not escape.
TEST(Julia, LogPolarDoubleMatchesFloat128) {
  const RationalMap map = SmallMap();
  JuliaOptions o;
  o.iterations = 4;
  const JuliaMap<double> d(map, o);
  const JuliaMap<float128> q(map, o);
  int compared = 0, escaped = 0;
  double worst = 0;
  for (const Vec3& p : Points(1500, 7)) {
    const auto rq = q.IterateDirect(q.StartingPoint(p));
    const auto rd = d.Iterate(d.StartingPoint(p));
    if (rq.escaped || rd.escaped) {
      ++escaped;
      continue;
    }
    ASSERT_EQ(rq.iterations, rd.iterations);
    const double ref = ToDouble(rq.log_modulus);
    const double err = std::abs(rd.log_modulus - ref) / std::max(1.0, std::abs(ref));
    worst = std::max(worst, err);
    const double dv = std::abs(rd.versor.w - ToDouble(rq.versor.w)) + std::abs(rd.versor.x - ToDouble(rq.versor.x)) +
                      std::abs(rd.versor.y - ToDouble(rq.versor.y)) + std::abs(rd.versor.z - ToDouble(rq.versor.z));
    EXPECT_LT(dv, 1e-8);
    ++compared;
  }
  EXPECT_LT(worst, 1e-9);
  EXPECT_GT(compared, 200);  // the test means something: both kinds of points occur
  EXPECT_GT(escaped, 200);
}

TEST(Julia, LogPolarAndDirectAgreeInFloat128) {
  const RationalMap map = SmallMap(5);
  JuliaOptions o;
  o.iterations = 3;
  const JuliaMap<float128> q(map, o);
  for (const Vec3& p : Points(200, 9)) {
    const auto a = q.Iterate(q.StartingPoint(p));
    const auto b = q.IterateDirect(q.StartingPoint(p));
    EXPECT_EQ(a.escaped, b.escaped);
    if (a.escaped) continue;
    EXPECT_NEAR(ToDouble(a.log_modulus), ToDouble(b.log_modulus), 1e-20 * std::max(1.0, std::abs(ToDouble(b.log_modulus))));
  }
}

// One application: log|R(q)| = ln C + tau sum T_i log|q - t_i| - beta sum B_i log|q - b_i|, the
// quantity the energies fit.
TEST(Julia, OneApplicationIsTheLogLinearSum) {
  const RationalMap map = SmallMap();
  JuliaOptions o;
  o.iterations = 1;
  o.slice = 0.3;
  const JuliaMap<double> d(map, o);
  for (const Vec3& p : Points(50, 11)) {
    double L = map.ln_C;
    auto dist = [&](const Vec4& r) {
      return 0.5 * std::log((p[0] - r[0]) * (p[0] - r[0]) + (p[1] - r[1]) * (p[1] - r[1]) +
                            (p[2] - r[2]) * (p[2] - r[2]) + (0.3 - r[3]) * (0.3 - r[3]));
    };
    for (int i = 0; i < map.top_count(); ++i) L += map.tau * map.top_exponents[i] * dist(map.top_roots[i]);
    for (int i = 0; i < map.bottom_count(); ++i) L -= map.beta * map.bottom_exponents[i] * dist(map.bottom_roots[i]);
    const auto r = d.At(p);
    EXPECT_NEAR(r.log_modulus, L, 1e-12 * std::max(1.0, std::abs(L)));
    EXPECT_NEAR(r.versor.norm(), 1.0, 1e-14);
    EXPECT_EQ(r.iterations, 1);
  }
}

// The reference's zero roots (top and bottom at the origin): an iterate at or underflowing to 0
// keeps a finite log-modulus (no inf - inf).
TEST(Julia, ZeroRootsGiveFiniteValues) {
  RandomMapOptions ro;
  ro.top = 6;
  ro.bottom = 5;
  ro.leading_zero_roots = true;
  RationalMap map = RandomMap(ro);
  map.tau = 1.3;
  map.beta = 0.7;
  JuliaOptions o;
  o.iterations = 6;
  const JuliaMap<double> d(map, o);
  EXPECT_TRUE(std::isfinite(d.At({0, 0, 0}).log_modulus) || d.At({0, 0, 0}).log_modulus < 0);
  Quaternion<double> u(1, 0, 0, 0);
  double L = 0;
  d.Apply(Quaternion<double>(), -1e6, u, L, u);  // |q| = e^-1e6: underflows in double
  EXPECT_TRUE(std::isfinite(L));
  int bad = 0;
  for (const Vec3& p : Points(500, 17)) bad += std::isnan(d.At(p).log_modulus);
  EXPECT_EQ(bad, 0);
}

TEST(Julia, EscapeStopsTheIteration) {
  RationalMap map = SmallMap();
  map.ln_C = 12.0;  // everything is thrown out at once
  JuliaOptions o;
  o.iterations = 5;
  const JuliaMap<double> d(map, o);
  const auto r = d.At({0.1, 0.2, 0.3});
  EXPECT_TRUE(r.escaped);
  EXPECT_EQ(r.iterations, 1);
  EXPECT_GE(r.log_modulus, std::log(2000.0));
}

TEST(Julia, RootTranslationChangesNothingForOneIteration) {
  const RationalMap map = SmallMap();
  JuliaOptions o;
  o.iterations = 1;
  const JuliaMap<double> a(map, o);
  o.root_translation = {0, 0, 1.41, 0};
  const JuliaMap<double> b(map, o);
  o.iterations = 3;
  const JuliaMap<double> c(map, o);
  o.root_translation = {0, 0, 0, 0};
  const JuliaMap<double> c0(map, o);
  int differ = 0;
  for (const Vec3& p : Points(100, 13)) {
    EXPECT_NEAR(a.At(p).log_modulus, b.At(p).log_modulus, 1e-10);
    differ += std::abs(c.At(p).log_modulus - c0.At(p).log_modulus) > 1e-6;
  }
  EXPECT_GT(differ, 10);
}

// The reference's bail-out at |q| < 10 FLT_MIN, as an option. On the steep ball map translated by t = (0, 0, 1.5), every point of the
// ball is sent within |R| of -t, outside the ball, and escapes at the next step; with a capture
// radius the deep inside stops there and stays in the set.
TEST(Julia, ACaptureRadiusKeepsTheDeepInsideOfATranslatedSteepMap) {
  const RationalMap m = SteepBallMap();
  JuliaOptions o;
  o.iterations = 4;
  o.root_translation = {0, 0, 1.5, 0};
  const JuliaMap<double> free(m, o);
  o.capture_radius = 1e-10;
  const JuliaMap<double> captured(m, o);
  const Vec3 deep{0.5, 0, 0}, shallow{0.0, 0.9, 0}, outside{0.0, 0, 1.1};  // |q_1| = 0.5^40, 0.9^40, 1.1^40
  EXPECT_TRUE(free.At(deep).escaped);
  const JuliaResult<double> d = captured.At(deep);
  EXPECT_FALSE(d.escaped);
  EXPECT_EQ(d.iterations, 1);
  EXPECT_NEAR(d.log_modulus, 40 * std::log(0.5), 1e-9);
  EXPECT_TRUE(captured.At(shallow).escaped);  // |q_1| = 0.015 > 1e-10: iterated on, and out
  EXPECT_TRUE(captured.At(outside).escaped);
  // The direct products stop at the same point.
  EXPECT_EQ(captured.IterateDirect(captured.StartingPoint(deep)).iterations, 1);
  // A start inside the capture ball is still iterated (only iterates are captured).
  EXPECT_EQ(captured.At({0, 0, -1.5}).iterations, 1);
  // Untranslated, 0 is a super-attracting fixed point: capturing changes no point's fate.
  o.root_translation = {0, 0, 0, 0};
  o.capture_radius = 1.1754944e-37;
  const JuliaMap<double> plain_c(m, o);
  o.capture_radius = 0;
  const JuliaMap<double> plain(m, o);
  for (const Vec3& p : Points(300, 21)) EXPECT_EQ(plain_c.At(p).escaped, plain.At(p).escaped);
  o.capture_radius = -1;
  EXPECT_THROW(JuliaMap<double>(m, o), Error);
  o.capture_radius = 2;
  EXPECT_THROW(JuliaMap<double>(m, o), Error);
  o.capture_radius = std::nan("");
  EXPECT_THROW(JuliaMap<double>(m, o), Error);
}

TEST(Julia, AFrameChangeKeepsTheOneStepSetOfEveryUserPoint) {
  RationalMap map = SmallMap();
  map.frame.scale = 0.3, map.frame.translation = {0.1, 0.2, 0.05}, map.frame.origin = {0.45, 0.52, 0.6};
  map.frame.fractal_radius = 7.5;
  FractalFrame to = map.frame;
  to.fractal_radius = 2.5, to.origin = {0.5, 0.5, 0.5};
  const RationalMap moved = InFrame(map, to);
  for (const Vec3& p : Points(50, 5)) {
    const Vec3 q = to.user_to_fractal(map.frame.fractal_to_user(p));
    EXPECT_NEAR(OneStepLogModulus(moved, q), OneStepLogModulus(map, p), 1e-10);
  }
  // And back again.
  const RationalMap back = InFrame(moved, map.frame);
  EXPECT_NEAR(back.ln_C, map.ln_C, 1e-12);
  for (int i = 0; i < map.top_count(); ++i)
    for (int a = 0; a < 4; ++a) EXPECT_NEAR(back.top_roots[i][a], map.top_roots[i][a], 1e-12);
  // A frame of another normalization is refused.
  to.scale = 0.5;
  EXPECT_THROW(InFrame(map, to), Error);
}

TEST(Julia, TheReferenceFrameHasTheShapeThreeUnitsLongAboutTheBoxCentre) {
  FractalFrame f;
  f.origin = {0.4, 0.55, 0.5}, f.fractal_radius = 11.0;
  const FractalFrame r = ReferenceFrame(f);
  EXPECT_EQ(r.fractal_radius, 4.0);
  EXPECT_EQ(r.origin, (Vec3{0.5, 0.5, 0.5}));
  f.padding = 0.25;
  EXPECT_NEAR(ReferenceFrame(f).fractal_radius * (1 - 2 * f.padding), 3.0, 1e-12);
}

TEST(Julia, DetailWidensTheBandAboutTheSurfaceAndKeepsTheOneStepSet) {
  const RationalMap m = SteepBallMap();
  EXPECT_NEAR(SurfaceSteepness(m), 40.0, 0.5);
  // 10 % of the shape box's side (3 units): a band 0.3 wide, lambda = 2 / (0.3 * 40).
  double lambda = 0;
  const RationalMap d = WithDetail(m, 10.0, &lambda);
  EXPECT_NEAR(lambda, 2.0 / (0.3 * 40.0), 0.02);
  EXPECT_NEAR(SurfaceSteepness(d), 40.0 * lambda, 0.5);
  for (const Vec3& p : Points(200, 9)) {
    const double a = OneStepLogModulus(m, p), b = OneStepLogModulus(d, p);
    EXPECT_EQ(a < 0, b < 0);
    EXPECT_NEAR(b, lambda * a, 1e-9 * (1 + std::abs(a)));
  }
  // A band narrower than the map's: the map is made steeper (a gentle optimized map meshed smooth),
  // the one-step set again the same. Detail 0: the map as it is.
  const RationalMap s = WithDetail(m, 0.5, &lambda);
  EXPECT_NEAR(lambda, 2.0 / (0.015 * 40.0), 0.05);
  EXPECT_GT(lambda, 1.0);
  EXPECT_NEAR(SurfaceSteepness(s), 40.0 * lambda, 0.5 * lambda);
  for (const Vec3& p : Points(200, 10)) EXPECT_EQ(OneStepLogModulus(m, p) < 0, OneStepLogModulus(s, p) < 0);
  EXPECT_EQ(WithDetail(m, 0.0, &lambda).ln_C, m.ln_C);
  EXPECT_EQ(lambda, 1.0);
  EXPECT_THROW(WithDetail(m, -1.0), Error);
  EXPECT_THROW(WithDetail(m, std::nan("")), Error);
  // The iteration map: detail, then the reference frame.
  const RationalMap r = IterationMap(m, IterationFrame::kReference, 10.0);
  EXPECT_EQ(r.frame.fractal_radius, 4.0);
  EXPECT_NEAR(r.tau, d.tau, 1e-15);
}

// The translation by potential: -t lands where the iterated map's L is the value asked for, on the
// first crossing along the ray from the origin; bad requests are refused.
TEST(Julia, TranslationForPotentialPutsMinusTWhereLIsTheValueAsked) {
  RationalMap m = SteepBallMap();  // L = 40 log|q|: the unit ball, L(-t) = 40 log s
  m.frame.fractal_radius = 4.0;
  for (double potential : {-3.0, -2.0, -0.5}) {
    const Vec4 t = TranslationForPotential(m, {0, 0, 2}, potential);
    EXPECT_EQ(t[0], 0.0);
    EXPECT_EQ(t[3], 0.0);
    EXPECT_NEAR(t[2], std::exp(potential / 40.0), 1e-9);
    EXPECT_NEAR(OneStepLogModulus(m, {-t[0], -t[1], -t[2]}), potential, 1e-7);
  }
  // Another direction; its length does not matter.
  const Vec4 d = TranslationForPotential(m, {3, 4, 0}, -2.0);
  EXPECT_NEAR(d[0] / 3, d[1] / 4, 1e-12);
  EXPECT_NEAR(std::hypot(d[0], d[1]), std::exp(-2.0 / 40.0), 1e-9);
  // Deeper asked for, shorter translation: -t nearer the origin.
  EXPECT_LT(TranslationForPotential(m, {0, 0, 1}, -4.0)[2], TranslationForPotential(m, {0, 0, 1}, -1.0)[2]);
  EXPECT_THROW(TranslationForPotential(m, {0, 0, 0}, -2.0), Error);
  EXPECT_THROW(TranslationForPotential(m, {0, 0, std::nan("")}, -2.0), Error);
  EXPECT_THROW(TranslationForPotential(m, {0, 0, 1}, 0.0), Error);
  EXPECT_THROW(TranslationForPotential(m, {0, 0, 1}, -2000.0), Error);
  // The origin outside the set: refused, with the reason.
  RationalMap outside = m;
  outside.top_roots = {{2.0, 0, 0, 0}};
  try {
    TranslationForPotential(outside, {0, 0, 1}, -2.0);
    ADD_FAILURE() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("not below the potential"), std::string::npos) << e.what();
  }
}

TEST(Julia, RotationIsRigid) {
  const SampleTransform t = SampleTransform::AxisAngle({0, 0, 2}, 90, {1, 0, 0});
  const Vec3 w = t.apply({2, 0, 0});
  EXPECT_NEAR(w[0], 1, 1e-15);
  EXPECT_NEAR(w[1], 1, 1e-15);
  EXPECT_NEAR(w[2], 0, 1e-15);
  EXPECT_THROW(SampleTransform::AxisAngle({0, 0, 0}, 10, {0, 0, 0}), Error);
}

TEST(Julia, InvalidOptionsThrow) {
  const RationalMap map = SmallMap();
  JuliaOptions o;
  o.iterations = 0;
  EXPECT_THROW(JuliaMap<double>(map, o), Error);
  o = {};
  o.escape_radius = 0.5;
  EXPECT_THROW(JuliaMap<double>(map, o), Error);
  o = {};
  o.root_scale = 0;
  EXPECT_THROW(JuliaMap<double>(map, o), Error);
}

}  // namespace
}  // namespace quijibo
