#include "monopole/initial_guess.h"

#include <gtest/gtest.h>

#include <cmath>

#include "util/error.h"
#include "quijibo/frame.h"
#include "quijibo/target.h"
#include "tests/ball_map.h"

namespace quijibo::monopole {
namespace {

// A sphere of radius a about the origin on a 49^3 grid of side 4 (fractal frame).
ScalarGrid Sphere(double a) {
  return AnalyticTarget("sphere:radius=" + std::to_string(a), GridFrame::Cube(49, {0.0, 0.0, 0.0}, 4.0));
}

// 40 points on the unit sphere, spread in latitude and longitude.
std::vector<Vec3> PointsOnUnitSphere() {
  std::vector<Vec3> points;
  for (int i = 0; i < 40; ++i) {
    const double t = 0.3 + 0.07 * i, u = 0.9 * i;
    points.push_back({std::sin(t) * std::cos(u), std::sin(t) * std::sin(u), std::cos(t)});
  }
  return points;
}

TEST(InitialGuess, SplitsWeightsIntoTopAndBottomRootsWithTheAmplitude) {
  FractalFrame frame;
  frame.fractal_radius = 4.0;
  const std::vector<Monopole> monopoles = {{{0.5, 0.0, 0.0}, 0.2}, {{-0.5, 0.1, 0.0}, -0.1}, {{0.0, 0.5, 0.2}, 0.05}};
  InitialGuessOptions o;
  o.both_signs = false;  // one root per monopole, by its sign
  o.amplitude = 40.0;
  // The IoU scan (the default): one top root at the origin instead of the zero roots, every exponent
  // scaled by the same steepness (the monopoles' ratios kept), no bottom root at the origin.
  const RationalMap scanned = InitialMap(monopoles, frame, Sphere(1.0), o);
  ASSERT_EQ(scanned.top_count(), 3);
  ASSERT_EQ(scanned.bottom_count(), 1);
  EXPECT_FALSE(scanned.leading_zero_roots);
  EXPECT_EQ(scanned.top_roots[0], (Vec4{0, 0, 0, 0}));
  EXPECT_NE(scanned.bottom_roots[0], (Vec4{0, 0, 0, 0}));
  EXPECT_NEAR(scanned.top_exponents[1] / scanned.top_exponents[2], 0.2 / 0.05, 1e-12);
  EXPECT_NEAR(scanned.bottom_exponents[0] / scanned.top_exponents[1], 0.1 / 0.2, 1e-12);
  EXPECT_NEAR(scanned.top_exponents[0], scanned.top_exponents[2], 1e-12);  // the smallest monopole's
  // The steepness is tau and beta alike, the exponents the monopoles' (w / radius * amplitude): the
  // bottom roots keep the top roots' leverage in the passes.
  EXPECT_EQ(scanned.tau, scanned.beta);
  EXPECT_GT(scanned.tau, 0.0);
  EXPECT_DOUBLE_EQ(scanned.top_exponents[1], 0.2 / 4.0 * 40.0);
  o.scan = StartScan::kReference;
  RationalMap m = InitialMap(monopoles, frame, Sphere(1.0), o);
  // The reference scan: leading zero roots first, exponent 1, not amplified.
  ASSERT_EQ(m.top_count(), 3);
  ASSERT_EQ(m.bottom_count(), 2);
  EXPECT_EQ(m.top_roots[0], (Vec4{0, 0, 0, 0}));
  EXPECT_EQ(m.top_exponents[0], 1.0);
  EXPECT_EQ(m.bottom_exponents[0], 1.0);
  // w / fractal radius * amplitude.
  EXPECT_DOUBLE_EQ(m.top_exponents[1], 0.2 / 4.0 * 40.0);
  EXPECT_DOUBLE_EQ(m.top_exponents[2], 0.05 / 4.0 * 40.0);
  EXPECT_DOUBLE_EQ(m.bottom_exponents[1], 0.1 / 4.0 * 40.0);
  EXPECT_EQ(m.bottom_roots[1], (Vec4{-0.5, 0.1, 0.0, 0.0}));
  EXPECT_EQ(m.tau, 1.0);
  EXPECT_EQ(m.beta, 1.0);

  o.leading_zero_roots = false;
  m = InitialMap(monopoles, frame, Sphere(1.0), o);
  EXPECT_EQ(m.top_count(), 2);
  EXPECT_EQ(m.bottom_count(), 1);
}

// both_signs: each monopole also in the other polynomial at exponent 0, so the start's field, its
// level and its steepness are those without; only the optimizer's freedom grows.
TEST(InitialGuess, BothSignsAddsZeroTwinsAndKeepsTheStart) {
  FractalFrame frame;
  frame.fractal_radius = 4.0;
  const std::vector<Monopole> monopoles = {{{0.5, 0.0, 0.0}, 0.2}, {{-0.5, 0.1, 0.0}, -0.1}, {{0.0, 0.5, 0.2}, 0.05}};
  InitialGuessOptions o;
  o.both_signs = false;
  const RationalMap plain = InitialMap(monopoles, frame, Sphere(1.0), o);
  o.both_signs = true;
  const RationalMap both = InitialMap(monopoles, frame, Sphere(1.0), o);
  ASSERT_EQ(both.top_count(), 4);     // the origin and the three monopoles
  ASSERT_EQ(both.bottom_count(), 3);  // the three monopoles
  EXPECT_EQ(both.ln_C, plain.ln_C);
  EXPECT_EQ(both.top_exponents[0], plain.top_exponents[0]);  // the origin: the smallest nonzero
  EXPECT_EQ(both.top_exponents[1], plain.top_exponents[1]);
  EXPECT_EQ(both.top_exponents[2], 0.0);  // the bottom monopole's twin
  EXPECT_EQ(both.top_roots[2], (Vec4{-0.5, 0.1, 0.0, 0.0}));
  EXPECT_EQ(both.top_exponents[3], plain.top_exponents[2]);
  EXPECT_EQ(both.bottom_exponents[0], 0.0);
  EXPECT_EQ(both.bottom_exponents[1], plain.bottom_exponents[0]);
  EXPECT_EQ(both.bottom_exponents[2], 0.0);
  EXPECT_EQ(both.bottom_roots[2], (Vec4{0.0, 0.5, 0.2, 0.0}));
}

// Hollow roots go where the start's set reaches outside the shape, hollow_offset_cells outside the
// surface, at exponent 0 (the start's field unchanged), at most hollow_roots of them.
TEST(InitialGuess, HollowRootsGoWhereTheSetSpillsOutOfTheShape) {
  const ScalarGrid sdf = Sphere(1.0);
  const double h = sdf.frame.spacing;
  const std::vector<Vec3> surface = PointsOnUnitSphere();
  InitialGuessOptions o;
  o.hollow_roots = 25;
  RationalMap fat = testing::BallMap(1.5);  // reaches 2 cells (0.167) outside the unit sphere
  const RationalMap before = fat;
  EXPECT_EQ(AddHollowRoots(fat, sdf, surface, o), 25);
  ASSERT_EQ(fat.bottom_count(), 25);
  for (int i = 0; i < 25; ++i) {
    EXPECT_EQ(fat.bottom_exponents[i], 0.0);
    const Vec4& r = fat.bottom_roots[i];
    EXPECT_NEAR(std::sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]), 1.0 + 2.0 * h, 0.2 * h);  // outward, 2 cells
    const Vec3 q{r[0], r[1], r[2]};
    const Vec3& p = surface[std::size_t(i)];  // taken in the given order
    EXPECT_NEAR(q[0] - p[0], 2.0 * h * p[0], 0.2 * h);
  }
  const Vec3 x{0.3, -0.2, 0.5};
  EXPECT_DOUBLE_EQ(OneStepLogModulus(fat, x), OneStepLogModulus(before, x));
  RationalMap tight = testing::BallMap(1.1);  // ends within the 2 cells: nothing spills that far
  EXPECT_EQ(AddHollowRoots(tight, sdf, surface, o), 0);
  EXPECT_EQ(tight.bottom_count(), 0);
  o.hollow_roots = -1;
  EXPECT_THROW(AddHollowRoots(fat, sdf, surface, o), Error);
}

// Attract roots, the inward mirror: top roots where the shape reaches beyond the start's set,
// attract_offset_cells inside the surface, at exponent 0, at most attract_roots of them.
TEST(InitialGuess, AttractRootsGoWhereTheSetFallsShortOfTheShape) {
  const ScalarGrid sdf = Sphere(1.0);
  const double h = sdf.frame.spacing;
  const std::vector<Vec3> surface = PointsOnUnitSphere();
  InitialGuessOptions o;
  o.attract_roots = 25;
  RationalMap thin = testing::BallMap(0.6);  // stops well inside the unit sphere
  const RationalMap before = thin;
  EXPECT_EQ(AddAttractRoots(thin, sdf, surface, o), 25);
  ASSERT_EQ(thin.top_count(), 26);
  EXPECT_EQ(thin.bottom_count(), 0);
  for (int i = 0; i < 25; ++i) {
    EXPECT_EQ(thin.top_exponents[std::size_t(i) + 1], 0.0);
    const Vec4& r = thin.top_roots[std::size_t(i) + 1];
    EXPECT_NEAR(std::sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]), 1.0 - 2.0 * h, 0.2 * h);  // inward, 2 cells
    const Vec3& p = surface[std::size_t(i)];  // taken in the given order
    EXPECT_NEAR(r[0] - p[0], -2.0 * h * p[0], 0.2 * h);
  }
  const Vec3 x{0.3, -0.2, 0.5};
  EXPECT_DOUBLE_EQ(OneStepLogModulus(thin, x), OneStepLogModulus(before, x));
  RationalMap full = testing::BallMap(0.95);  // reaches within the 2 cells: nothing falls short that deep
  EXPECT_EQ(AddAttractRoots(full, sdf, surface, o), 0);
  EXPECT_EQ(full.top_count(), 1);
  // A part thinner than the offset: the point is taken at half the depth. On a sphere of radius
  // 0.5 (6 cells) 14 cells in is outside again; 7 cells in is inside, a cell past the centre.
  o.attract_offset_cells = 14.0;
  const ScalarGrid small = Sphere(0.5);
  std::vector<Vec3> on_small;
  for (const Vec3& p : surface) on_small.push_back({0.5 * p[0], 0.5 * p[1], 0.5 * p[2]});
  RationalMap tiny = testing::BallMap(0.05);
  EXPECT_EQ(AddAttractRoots(tiny, small, on_small, o), 25);
  for (int i = 1; i <= 25; ++i) {
    const Vec4& r = tiny.top_roots[std::size_t(i)];
    EXPECT_NEAR(std::sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]), 7.0 * h - 0.5, 0.2 * h);
  }
  o.attract_roots = 4001;
  EXPECT_THROW(AddAttractRoots(thin, sdf, surface, o), Error);
}

// The one-step IoU of {L < 0} against {sdf < 0} on the cells of `sdf`.
double OneStepIou(const RationalMap& m, const ScalarGrid& sdf) {
  std::int64_t both = 0, either = 0;
  for (std::int64_t c = 0; c < sdf.frame.cell_count(); ++c) {
    const bool in_set = OneStepLogModulus(m, sdf.frame.cell_center(c)) < 0, in_shape = sdf.values[std::size_t(c)] < 0;
    both += in_set && in_shape;
    either += in_set || in_shape;
  }
  return double(both) / double(either);
}

// The offset roots' common exponent: a start that falls short on one side and spills on the other
// (a ball off the sphere's centre) is pulled onto the shape by its attract and hollow roots.
TEST(InitialGuess, OffsetScanStartsTheOffsetRootsWhereTheSetFollowsTheShapeBetter) {
  const ScalarGrid sdf = Sphere(1.0);
  RationalMap m;
  m.top_roots = {Vec4{-0.4, 0.0, 0.0, 0.0}};
  m.top_exponents = {1.0};
  m.ln_C = -std::log(0.9);
  InitialGuessOptions o;
  o.attract_roots = o.hollow_roots = 40;
  RootGroup hollow{m.top_count(), 0, m.bottom_count(), 0};
  AddHollowRoots(m, sdf, PointsOnUnitSphere(), o);
  hollow.top_end = m.top_count(), hollow.bottom_end = m.bottom_count();
  RootGroup attract{m.top_count(), 0, m.bottom_count(), 0};
  AddAttractRoots(m, sdf, PointsOnUnitSphere(), o);
  attract.top_end = m.top_count(), attract.bottom_end = m.bottom_count();
  ASSERT_GT(hollow.size(), 0);
  ASSERT_GT(attract.size(), 0);
  const double before = OneStepIou(m, sdf);
  const OffsetExponentScan s = ScanOffsetExponents(m, sdf, hollow, attract, 10.0);
  EXPECT_EQ(s.hollow, hollow.size());
  EXPECT_EQ(s.attract, attract.size());
  EXPECT_GE(s.iou_before, before);  // the level rescanned: at least the given one's
  EXPECT_GT(s.iou, s.iou_before + 0.03);
  EXPECT_GT(s.exponent, 0.0);
  for (int i = attract.top_begin; i < attract.top_end; ++i) EXPECT_EQ(m.top_exponents[std::size_t(i)], s.exponent);
  for (int i = hollow.bottom_begin; i < hollow.bottom_end; ++i)
    EXPECT_EQ(m.bottom_exponents[std::size_t(i)], s.exponent);
  EXPECT_EQ(m.tau, m.beta);
  EXPECT_NEAR(OneStepIou(m, sdf), s.iou, 1e-12);  // the map is the scanned set, its level and steepness

  // Hollow roots alone: a ball that spills out on one side is carved back by its bottom roots.
  RationalMap fat;
  fat.top_roots = {Vec4{0.4, 0.0, 0.0, 0.0}};
  fat.top_exponents = {1.0};
  fat.ln_C = -std::log(1.0);
  RootGroup spill{1, 1, 0, 0};
  AddHollowRoots(fat, sdf, PointsOnUnitSphere(), o);
  spill.bottom_end = fat.bottom_count();
  ASSERT_GT(spill.size(), 0);
  const OffsetExponentScan carved = ScanOffsetExponents(fat, sdf, spill, RootGroup{}, 10.0);
  EXPECT_GT(carved.exponent, 0.0);
  EXPECT_GT(carved.iou, carved.iou_before + 0.03);
  EXPECT_NEAR(OneStepIou(fat, sdf), carved.iou, 1e-12);

  // Roots that can only pull the set off the shape (all on one side, outside it) stay at 0, and the
  // start's set is kept.
  RationalMap ball = testing::BallMap(1.0);
  RootGroup far{1, 6, 0, 0};
  for (int i = 0; i < 5; ++i) {
    ball.top_roots.push_back(Vec4{1.6, -0.2 + 0.1 * i, 0.0, 0.0});
    ball.top_exponents.push_back(0.0);
  }
  const double ball_iou = OneStepIou(ball, sdf);
  const OffsetExponentScan none = ScanOffsetExponents(ball, sdf, RootGroup{}, far, 10.0);
  EXPECT_EQ(none.exponent, 0.0);
  EXPECT_EQ(none.iou, none.iou_before);
  EXPECT_NEAR(OneStepIou(ball, sdf), ball_iou, 1e-12);
  ball.beta = 2.0;
  EXPECT_THROW(ScanOffsetExponents(ball, sdf, RootGroup{}, far, 10.0), Error);
}

TEST(InitialGuess, ScanPutsTheZeroLevelOnTheSphere) {
  // One top root at the centre: L = ln C + ln|q|, zero on |q| = e^{-ln C}. The scan must find
  // ln C = -ln a to within a scan cell.
  for (double a : {0.6, 1.0, 1.4}) {
    RationalMap m;
    m.top_roots = {{0.0, 0.0, 0.0, 0.0}};
    m.top_exponents = {1.0};
    const LnCScan s = ScanLnC(m, Sphere(a), 25, 10.0);
    const double cell = 4.0 / 25;
    EXPECT_NEAR(std::exp(-s.ln_C), a, cell) << "a = " << a;
    EXPECT_LT(s.energy, 0.0);
  }
}

TEST(InitialGuess, ScanIsInvariantToAConstantFactor) {
  // Doubling every exponent doubles L; the zero level is the same sphere, so ln C doubles.
  RationalMap m;
  m.top_roots = {{0.3, 0.0, 0.0, 0.0}, {-0.3, 0.0, 0.0, 0.0}};
  m.top_exponents = {1.0, 1.0};
  const LnCScan one = ScanLnC(m, Sphere(1.0), 25, 10.0);
  m.top_exponents = {2.0, 2.0};
  const LnCScan two = ScanLnC(m, Sphere(1.0), 25, 20.0 / 2.0);
  EXPECT_NEAR(two.ln_C, 2.0 * one.ln_C, 0.05 * std::abs(one.ln_C) + 0.05);
}

TEST(InitialGuess, BadInputIsRejected) {
  FractalFrame frame;
  const std::vector<Monopole> one = {{{0.5, 0.0, 0.0}, 0.2}};
  InitialGuessOptions o;
  EXPECT_THROW(InitialMap({}, frame, Sphere(1.0), o), Error);
  o.amplitude = 0.0;
  EXPECT_THROW(InitialMap(one, frame, Sphere(1.0), o), Error);
  o.amplitude = std::nan("");
  EXPECT_THROW(InitialMap(one, frame, Sphere(1.0), o), Error);
  o = {};
  o.scan_resolution = 2;
  EXPECT_THROW(InitialMap(one, frame, Sphere(1.0), o), Error);
}

}  // namespace
}  // namespace quijibo::monopole
