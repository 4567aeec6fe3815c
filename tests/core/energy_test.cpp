#include <gtest/gtest.h>

#include "tests/core/energy_fixtures.h"
#include "quijibo/cached_energy.h"
#include "util/error.h"
#include "quijibo/loglinear_energy.h"

#include <omp.h>

namespace quijibo {
namespace {

using testing::EnergyProblem;
using testing::MakeEnergyProblem;

// Central differences of psi, componentwise, in the evaluator's own type.
template <class Real, class Eval>
Eigen::Matrix<Real, -1, 1> FiniteDifferences(const Eval& eval, Eigen::Matrix<Real, -1, 1> x,
                                             Real h, int count) {
  Eigen::Matrix<Real, -1, 1> g(count);
  for (int k = 0; k < count; ++k) {
    const Real x0 = x[k];
    x[k] = x0 + h;
    const Real fp = eval(x);
    x[k] = x0 - h;
    const Real fm = eval(x);
    x[k] = x0;
    g[k] = (fp - fm) / (2 * h);
  }
  return g;
}

template <class Real>
class CachedEnergyTest : public ::testing::Test {};
using RealTypes = ::testing::Types<float, double, long double, float128>;
TYPED_TEST_SUITE(CachedEnergyTest, RealTypes);

template <class Real>
void Tolerances(Real& h, double& tol) {
  if constexpr (std::is_same_v<Real, float>) h = Real(3e-3), tol = 3e-2;
  else if constexpr (std::is_same_v<Real, double>) h = Real(1e-6), tol = 1e-6;
  else if constexpr (std::is_same_v<Real, long double>) h = Real(1e-7), tol = 1e-9;
  else h = Real(1e-12), tol = 1e-14;
}

TYPED_TEST(CachedEnergyTest, GradientMatchesCentralDifferences) {
  using Real = TypeParam;
  using V = Eigen::Matrix<Real, -1, 1>;
  const EnergyProblem p = MakeEnergyProblem(8, 4, 3, 0.3, 1.5, 5, WeightField::kLayer, true);
  const CachedEnergy<Real> energy(p.map, p.grid);
  const V x = p.map.variables().cast<Real>();
  const Evaluation<Real> ev = energy.Evaluate(x);
  ASSERT_EQ(ev.counts.overflowed, 0);
  EXPECT_EQ(ev.gradient.size(), p.map.variable_count());
  Real h;
  double tol;
  Tolerances(h, tol);
  const V fd = FiniteDifferences<Real>(
      [&](const V& y) { return energy.Evaluate(y, EnergyMode::kFull, false).energy; }, x, h,
      int(x.size()));
  const double scale = ToDouble(ev.gradient.cwiseAbs().maxCoeff());
  ASSERT_GT(scale, 1e-3);
  for (int k = 0; k < x.size(); ++k)
    EXPECT_NEAR(ToDouble(ev.gradient[k]), ToDouble(fd[k]), tol * scale) << "variable " << k;
  // The V mode gives the first three entries of the same gradient.
  const Evaluation<Real> v = energy.Evaluate(x, EnergyMode::kVariable);
  ASSERT_EQ(v.gradient.size(), 3);
  for (int k = 0; k < 3; ++k)
    EXPECT_NEAR(ToDouble(v.gradient[k]), ToDouble(ev.gradient[k]), 1e-5 * scale);
  EXPECT_EQ(ToDouble(v.energy), ToDouble(ev.energy));
}

TEST(LogLinearEnergyTest, GradientMatchesCentralDifferences) {
  for (WeightField w : {WeightField::kLayer, WeightField::kInverse}) {
    const EnergyProblem p = MakeEnergyProblem(9, 6, 5, 0.3, 2.0, 9, w);
    for (auto storage : {LogLinearOptions::Storage::kDouble, LogLinearOptions::Storage::kOnTheFly}) {
      LogLinearOptions lo;
      lo.storage = storage;
      const LogLinearEnergy energy(p.map, p.grid, {}, lo);
      const Eigen::VectorXd x = p.map.variables();
      const auto ev = energy.Evaluate(x);
      const Eigen::VectorXd fd = FiniteDifferences<double>(
          [&](const Eigen::VectorXd& y) { return energy.Evaluate(y, EnergyMode::kFull, false).energy; },
          x, 1e-6, int(x.size()));
      const double scale = ev.gradient.cwiseAbs().maxCoeff();
      ASSERT_GT(scale, 1e-3);
      for (int k = 0; k < x.size(); ++k) EXPECT_NEAR(ev.gradient[k], fd[k], 1e-6 * scale) << k;
    }
  }
}

TEST(LogLinearEnergyTest, VariablePassMatchesFullEvaluation) {
  const EnergyProblem p = MakeEnergyProblem(10, 7, 6, 0.3, 2.0, 4);
  LogLinearEnergy energy(p.map, p.grid);
  Eigen::VectorXd x = p.map.variables();
  EXPECT_THROW(energy.Evaluate(x, EnergyMode::kVariable), Error);
  energy.BeginVariablePass(x);
  x[0] += 0.3;
  x[1] *= 1.2;
  x[2] *= 0.8;
  const auto full = energy.Evaluate(x);
  const auto v = energy.Evaluate(x, EnergyMode::kVariable);
  EXPECT_NEAR(v.energy, full.energy, 1e-14);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(v.gradient[k], full.gradient[k], 1e-13) << k;
}

TEST(LogLinearEnergyTest, ResultDoesNotDependOnThreadCount) {
  const EnergyProblem p = MakeEnergyProblem(16, 8, 6, 0.3, 2.0, 2);
  const LogLinearEnergy energy(p.map, p.grid);
  const Eigen::VectorXd x = p.map.variables();
  const int saved = omp_get_max_threads();
  omp_set_num_threads(1);
  const auto one = energy.Evaluate(x);
  omp_set_num_threads(3);
  const auto three = energy.Evaluate(x);
  omp_set_num_threads(saved);
  EXPECT_EQ(one.energy, three.energy);
  EXPECT_EQ(one.gradient, three.gradient);
}

// The paper's evaluator in 80 and 128 bits and the log-linear one in double compute the same
// numbers wherever the former does not overflow.
TEST(EvaluatorAgreement, CachedExtendedAndLogLinearAgreeTo1e12) {
  const EnergyProblem p = MakeEnergyProblem(14, 11, 9, 0.5, 3.0, 21, WeightField::kLayer, true);
  const Eigen::VectorXd x = p.map.variables();
  const auto ll = LogLinearEnergy(p.map, p.grid).Evaluate(x);
  const auto ld = CachedEnergy<long double>(p.map, p.grid).Evaluate(x);
  const auto qd = CachedEnergy<float128>(p.map, p.grid).Evaluate(x);
  ASSERT_EQ(ld.counts.overflowed, 0);
  ASSERT_EQ(qd.counts.overflowed, 0);
  auto rel = [](double a, double b) { return std::abs(a - b) / std::max(std::abs(b), 1e-300); };
  EXPECT_LE(rel(ll.energy, ToDouble(qd.energy)), 1e-12);
  EXPECT_LE(rel(ToDouble(ld.energy), ToDouble(qd.energy)), 1e-12);
  for (int k = 0; k < x.size(); ++k) {
    const double ref = ToDouble(qd.gradient[k]);
    EXPECT_LE(rel(ll.gradient[k], ref), 1e-12) << "loglinear, variable " << k;
    EXPECT_LE(rel(ToDouble(ld.gradient[k]), ref), 1e-12) << "long double, variable " << k;
  }
}

// Realistic exponents make |T(q)| exceed double's range: the paper's evaluator in double loses
// cells (counted, not propagated), the log-linear evaluator in double stays exact.
TEST(EvaluatorAgreement, CachedDoubleOverflowsWhereLogLinearIsRight) {
  const EnergyProblem p = MakeEnergyProblem(12, 60, 40, 20.0, 40.0, 8);
  const Eigen::VectorXd x = p.map.variables();
  const auto dbl = CachedEnergy<double>(p.map, p.grid).Evaluate(x);
  const auto ld = CachedEnergy<long double>(p.map, p.grid).Evaluate(x);
  const auto ll = LogLinearEnergy(p.map, p.grid).Evaluate(x);
  EXPECT_GT(dbl.counts.overflowed, p.grid.frame.cell_count() / 10);
  ASSERT_EQ(ld.counts.overflowed, 0);
  EXPECT_EQ(ll.counts.overflowed, 0);
  EXPECT_NEAR(ll.energy, ToDouble(ld.energy), 1e-12 * std::abs(ToDouble(ld.energy)));
  EXPECT_GT(std::abs(ToDouble(dbl.energy) - ToDouble(ld.energy)), 1e-3);
  // Norm-wise: with exponents this large L is a sum of terms of magnitude ~1e3 that cancel to
  // O(1) near the surface, so double carries ~1e-13 absolute error in L (measured: the largest
  // componentwise error 3e-10, on a component 1e-3 of the largest).
  const double scale = ToDouble(ld.gradient.cwiseAbs().maxCoeff());
  for (int k = 0; k < x.size(); ++k) EXPECT_NEAR(ll.gradient[k], ToDouble(ld.gradient[k]), 1e-11 * scale) << k;
}

// The reference's leading zero roots sit on the centre sample of an odd grid centred at the
// origin. Both evaluators leave such a sample out, count it, and agree elsewhere.
TEST(EvaluatorAgreement, SingularCellsAreCountedAndLeftOut) {
  ScalarGrid sdf = AnalyticTarget("sphere:radius=1", GridFrame::Cube(9, {0, 0, 0}, 3.0));
  const EnergyGrid grid = MakeEnergyGrid(sdf, WeightField::kLayer);
  RandomMapOptions o;
  o.top = 5;
  o.bottom = 4;
  o.leading_zero_roots = true;
  RationalMap m = RandomMap(o);
  m.ln_C = -MedianLogModulus(m, grid);
  const auto ll = LogLinearEnergy(m, grid).Evaluate(m.variables());
  const auto ld = CachedEnergy<long double>(m, grid).Evaluate(m.variables());
  EXPECT_EQ(ll.counts.singular, 1);
  EXPECT_EQ(ld.counts.singular, 1);
  EXPECT_EQ(ld.counts.overflowed, 0);
  EXPECT_TRUE(std::isfinite(ll.energy));
  EXPECT_NEAR(ll.energy, ToDouble(ld.energy), 1e-13);
  for (int k = 0; k < ll.gradient.size(); ++k) EXPECT_TRUE(std::isfinite(ll.gradient[k]));
}

TEST(EnergyTest, PerfectAndInvertedFitsReachTheBounds) {
  // One top root at the centre of a sphere: |R| = e^C |q|, so with ln C = -ln r the Julia set
  // of one step is exactly the sphere of radius r: psi is close to -1 (up to the steepness of
  // tanh), and swapping top and bottom inverts it to close to +1.
  ScalarGrid sdf = AnalyticTarget("sphere:radius=1", GridFrame::Cube(20, {0, 0, 0}, 3.0));
  const EnergyGrid grid = MakeEnergyGrid(sdf, WeightField::kLayer);
  RationalMap m;
  m.top_roots = {{0, 0, 0, 0}};
  m.top_exponents = {40.0};
  const LogLinearEnergy e(m, grid);
  const double psi = e.Evaluate(m.variables(), EnergyMode::kFull, false).energy;
  EXPECT_LT(psi, -0.95);
  RationalMap inv;
  inv.bottom_roots = m.top_roots;
  inv.bottom_exponents = m.top_exponents;
  EXPECT_GT(LogLinearEnergy(inv, grid).Evaluate(inv.variables(), EnergyMode::kFull, false).energy, 0.95);
}

// In every weight mode the empty set (L > 0 everywhere) and the full box (L < 0) score >= 0:
// psi is counted from the better of the two (TrivialSetEnergy). Without that constant the balanced
// field, whose outside outweighs its inside, would score the empty set below 0 (the test can fail).
TEST(EnergyTest, NoWeightModeRewardsATrivialSet) {
  for (const char* shape : {"torus", "sphere:radius=1.3"}) {
    const ScalarGrid sdf = AnalyticTarget(shape, GridFrame::Cube(24, {0, 0, 0}, 3.2));
    for (WeightField w : {WeightField::kLayer, WeightField::kInverse, WeightField::kBalanced}) {
      const EnergyGrid grid = MakeEnergyGrid(sdf, w);
      const std::vector<double> empty(std::size_t(grid.frame.cell_count()), 5.0), full(empty.size(), -5.0);
      const double psi_empty = EnergyOfField(grid, empty, 10.0), psi_full = EnergyOfField(grid, full, 10.0);
      EXPECT_GE(psi_empty, -1e-12) << shape << " " << WeightFieldName(w);
      EXPECT_GE(psi_full, -1e-12) << shape << " " << WeightFieldName(w);
      EXPECT_NEAR(std::min(psi_empty, psi_full), 0.0, 1e-12) << shape << " " << WeightFieldName(w);
      // A perfect fit scores below both: -1 + |sum W| / eta = -2 (sum of the smaller side's |W|) / eta.
      std::vector<double> perfect(empty.size());
      double in = 0, out = 0;
      for (std::size_t c = 0; c < perfect.size(); ++c) {
        perfect[c] = sdf.values[c] < 0 ? -5.0 : 5.0;
        (sdf.values[c] < 0 ? in : out) += std::abs(grid.weight[c]);
      }
      EXPECT_NEAR(EnergyOfField(grid, perfect, 10.0), -2 * std::min(in, out) / grid.eta, 1e-9)
          << shape << " " << WeightFieldName(w);
      EXPECT_LT(EnergyOfField(grid, perfect, 10.0), -0.2) << shape << " " << WeightFieldName(w);
      if (w == WeightField::kBalanced) {
        EXPECT_LT(TrivialSetEnergy({&grid}), -0.1) << shape;  // the raw sum rewards the empty set
      } else {
        EXPECT_EQ(TrivialSetEnergy({&grid}), 0.0) << shape;  // halves: nothing changes
      }
    }
  }
}

TEST(EnergyTest, BadVariablesAreRejected) {
  const EnergyProblem p = MakeEnergyProblem(6, 2, 2, 0.5, 1.0, 1);
  const LogLinearEnergy e(p.map, p.grid);
  Eigen::VectorXd x = p.map.variables();
  EXPECT_THROW(e.Evaluate(x.head(3)), Error);
  x[4] = std::nan("");
  EXPECT_THROW(e.Evaluate(x), Error);
  EXPECT_THROW(CachedEnergy<double>(p.map, p.grid).Evaluate(x), Error);
}

TEST(WeightsTest, LayerWeightsAreNormalizedHalves) {
  for (WeightField w : {WeightField::kLayer, WeightField::kInverse}) {
    const ScalarGrid sdf = AnalyticTarget("torus", GridFrame::Cube(24, {0, 0, 0}, 3.2));
    const std::vector<double> W = ComputeWeights(sdf, w);
    double in = 0, out = 0;
    for (std::size_t c = 0; c < W.size(); ++c) {
      (sdf.values[c] < 0 ? in : out) += W[c];
      EXPECT_EQ(W[c] < 0, sdf.values[c] < 0);
    }
    EXPECT_NEAR(in, -0.5, 1e-12);
    EXPECT_NEAR(out, 0.5, 1e-12);
  }
  // Layer weights: shell cells carry the largest magnitude, decaying as 1/k away from it.
  const ScalarGrid sdf = AnalyticTarget("sphere", GridFrame::Cube(21, {0, 0, 0}, 3.0));
  const std::vector<double> W = ComputeWeights(sdf, WeightField::kLayer);
  const std::int64_t corner = sdf.frame.index(0, 0, 0);
  const std::int64_t near_surface = sdf.frame.index(10, 10, 17);  // x = 0, z ~ 1.07
  EXPECT_GT(std::abs(W[near_surface]), 5 * std::abs(W[corner]));
}

TEST(WeightsTest, CoarseLevelsSampleOrRecompute) {
  const ScalarGrid sdf = AnalyticTarget("sphere", GridFrame::Cube(40, {0, 0, 0}, 3.0));
  const EnergyGrid sampled = MakeEnergyGrid(sdf, WeightField::kLayer, 10);
  const EnergyGrid recomputed = MakeEnergyGrid(sdf, WeightField::kLayer, 10, LevelWeights::kRecompute);
  EXPECT_EQ(sampled.frame.dims[0], 10);
  EXPECT_EQ(sampled.frame, recomputed.frame);
  EXPECT_NEAR(recomputed.eta, 1.0, 1e-12);
  EXPECT_GT(sampled.eta, 0.0);
  EXPECT_THROW(MakeEnergyGrid(AnalyticTarget("sphere:radius=5", sdf.frame), WeightField::kLayer), Error);
}

// A level whose cells are wider than the target's parts fits another shape (issue 14: the
// pretzel's plate at 25^3); LevelFidelity measures that and ResolvedLevelResolution raises the level.
TEST(WeightsTest, LevelFidelitySaysWhetherALevelSeesTheTarget) {
  const GridFrame frame = GridFrame::Cube(48, {0, 0, 0}, 3.2);
  const ScalarGrid sphere = AnalyticTarget("sphere", frame);
  const ScalarGrid tube = AnalyticTarget("torus:major=1,minor=0.08", frame);  // 2.4 cells across
  const WeightField w = WeightField::kBalanced;
  const LevelWeights lw = LevelWeights::kSampleFinest;
  const std::vector<double> sphere_w = ComputeWeights(sphere, w), tube_w = ComputeWeights(tube, w);
  const EnergyGrid sphere_finest = MakeEnergyGrid(sphere, sphere_w, w, 0, lw, 0.0);
  const EnergyGrid tube_finest = MakeEnergyGrid(tube, tube_w, w, 0, lw, 0.0);
  EXPECT_EQ(LevelFidelity(tube_finest, tube_finest), 1.0);
  EXPECT_GT(LevelFidelity(sphere_finest, MakeEnergyGrid(sphere, sphere_w, w, 12, lw, 0.0)), 0.8);
  EXPECT_LT(LevelFidelity(tube_finest, MakeEnergyGrid(tube, tube_w, w, 12, lw, 0.0)), 0.5);

  double fid = 0;
  EXPECT_EQ(ResolvedLevelResolution(sphere, sphere_w, w, 12, lw, 0.8, &fid), 12);
  EXPECT_GT(fid, 0.8);
  const int raised = ResolvedLevelResolution(tube, tube_w, w, 12, lw, 0.8, &fid);
  EXPECT_GT(raised, 12);
  EXPECT_LE(raised, 48);
  EXPECT_GE(fid, 0.8);
  if (raised < 48) {  // the smallest such level: the one below it does not reach the bar
    EXPECT_LT(LevelFidelity(tube_finest, MakeEnergyGrid(tube, tube_w, w, raised - 1, lw, 0.0)), 0.8);
  }
  EXPECT_EQ(ResolvedLevelResolution(tube, tube_w, w, 12, lw, 0.0, &fid), 12);  // 0: the schedule as written
  EXPECT_EQ(ResolvedLevelResolution(tube, tube_w, w, 64, lw, 0.8, &fid), 64);  // at or above the finest: kept
}

// The wall depth is the inside's 90th percentile depth in cells: for a ball of radius R cells,
// R (1 - 0.1^(1/3)) = 0.536 R. A ball 10 cells in radius is thick, one 4 cells in radius thin.
TEST(WeightsTest, WallDepthSaysWhetherATargetIsThinWalled) {
  const ScalarGrid thick = AnalyticTarget("sphere", GridFrame::Cube(60, {0, 0, 0}, 6.0));
  const ScalarGrid thin = AnalyticTarget("sphere", GridFrame::Cube(24, {0, 0, 0}, 6.0));
  EXPECT_NEAR(WallDepthCells(thick), 0.536 * 10, 0.25);  // within a quarter cell of the continuous ball
  EXPECT_NEAR(WallDepthCells(thin), 0.536 * 4, 0.25);
  EXPECT_FALSE(ThinWallsOn(AutoSwitch::kAuto, thick));
  EXPECT_TRUE(ThinWallsOn(AutoSwitch::kAuto, thin));
  EXPECT_TRUE(ThinWallsOn(AutoSwitch::kOn, thick));
  EXPECT_FALSE(ThinWallsOn(AutoSwitch::kOff, thin));
  ScalarGrid empty = thin;
  for (double& v : empty.values) v = 1.0;
  EXPECT_EQ(WallDepthCells(empty), 0.0);
  for (const std::string& name : kAutoSwitchNames) EXPECT_EQ(AutoSwitchName(ParseAutoSwitch(name)), name);
  EXPECT_THROW(ParseAutoSwitch("yes"), Error);
}

}  // namespace
}  // namespace quijibo
