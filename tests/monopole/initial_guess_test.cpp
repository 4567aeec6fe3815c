#include "monopole/initial_guess.h"

#include <gtest/gtest.h>

#include <cmath>

#include "util/error.h"
#include "quijibo/frame.h"
#include "quijibo/target.h"

namespace quijibo::monopole {
namespace {

// A sphere of radius a about the origin on a 49^3 grid of side 4 (fractal frame).
ScalarGrid Sphere(double a) {
  return AnalyticTarget("sphere:radius=" + std::to_string(a), GridFrame::Cube(49, {0.0, 0.0, 0.0}, 4.0));
}

TEST(InitialGuess, SplitsWeightsIntoTopAndBottomRootsWithTheAmplitude) {
  FractalFrame frame;
  frame.fractal_radius = 4.0;
  const std::vector<Monopole> monopoles = {{{0.5, 0.0, 0.0}, 0.2}, {{-0.5, 0.1, 0.0}, -0.1}, {{0.0, 0.5, 0.2}, 0.05}};
  InitialGuessOptions o;
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
