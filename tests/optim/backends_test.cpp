// Every back end and every precision through Optimize, end to end on small real problems: the Ceres
// back end (bounds, descent; its exact resume is in resume_test.cpp) and the cached evaluator in
// float, double, long double and float128, each asserted to give what its range allows.
#include <gtest/gtest.h>

#include <filesystem>

#include "optim/optimizer.h"
#include "optim/small_run.h"
#include "quijibo/cached_energy.h"

namespace quijibo::optim {
namespace {

// The Ceres back end (L-BFGS on x = y^2) through the whole optimizer: a two-level schedule with a
// reweighted pass, checkpoints that restart its memory, exponents kept >= 0, every V and F pass
// going down, and the result the best absolute energy, below the start.
TEST(CeresThroughOptimize, RespectsTheBoundsAndLowersTheEnergy) {
  SmallRun run;
  OptimizeOptions o = ScheduleAsWritten("10(VFRF)20(VF)", 40, TempDir("ceres"));
  o.backend = "ceres";
  o.weights = WeightField::kLayer;
  o.checkpoint_every = 9;
  const OptimizeSummary s = Optimize(run.sdf, run.map, o);
  ASSERT_TRUE(s.complete);
  ASSERT_EQ(s.passes.size(), 6u);
  int iterations = 0;
  for (const PassSummary& p : s.passes) {
    EXPECT_NE(p.stop, "non-finite") << p.message;
    EXPECT_LE(p.iterations, 40);
    iterations += p.iterations;
    if (p.kind != 'R') {
      EXPECT_LE(p.energy_end, p.energy_start + 1e-12) << p.level << " " << p.kind;
    }
  }
  EXPECT_GT(iterations, 40);  // it did run, past several checkpoints
  EXPECT_LT(s.absolute_end, s.absolute_start - 0.05);
  for (double e : run.map.top_exponents) EXPECT_GE(e, 0.0);
  for (double e : run.map.bottom_exponents) EXPECT_GE(e, 0.0);
  EXPECT_GE(run.map.tau, 0.0);
  EXPECT_GE(run.map.beta, 0.0);
  EXPECT_NEAR(run.AbsoluteEnergy(run.map, WeightField::kLayer), s.absolute_end, 1e-12);
  std::filesystem::remove_all(o.out_dir);
}

struct PrecisionResult {
  OptimizeSummary summary;
  RationalMap map;
};

PrecisionResult RunCached(Precision precision, const SmallRun& start) {
  PrecisionResult r{{}, start.map};
  OptimizeOptions o = ScheduleAsWritten("8(VF)", 8, TempDir(PrecisionName(precision)));
  o.evaluator = "cached";
  o.precision = precision;
  o.weights = WeightField::kLayer;
  r.summary = Optimize(start.sdf, r.map, o);
  std::filesystem::remove_all(o.out_dir);
  return r;
}

// 60 roots with exponents up to 6: products of up to 36 powers of |q - t| that float's range
// (1e38) cannot hold in many cells, while double's can.
TEST(PrecisionsThroughOptimize, EachPrecisionGivesWhatItsRangeAllows) {
  const SmallRun start(36, 24, 6.0);
  const PrecisionResult dbl = RunCached(Precision::kDouble, start);
  const PrecisionResult ld = RunCached(Precision::kLongDouble, start);
  const PrecisionResult q = RunCached(Precision::kFloat128, start);
  const PrecisionResult flt = RunCached(Precision::kFloat, start);
  // double, long double and float128: no overflow, a descent, and the same optimization (the
  // trajectories differ only by rounding over 16 iterations).
  for (const PrecisionResult* r : {&dbl, &ld, &q}) {
    ASSERT_TRUE(r->summary.complete);
    ASSERT_EQ(r->summary.passes.size(), 2u);
    for (const PassSummary& p : r->summary.passes) {
      EXPECT_EQ(p.overflowed_cells, 0);
      EXPECT_GT(p.iterations, 0);
      EXPECT_NE(p.stop, "non-finite");
    }
    EXPECT_LT(r->summary.absolute_end, r->summary.absolute_start);
  }
  EXPECT_NEAR(ld.summary.absolute_end, q.summary.absolute_end, 1e-9);
  EXPECT_NEAR(dbl.summary.absolute_end, q.summary.absolute_end, 1e-6);
  // float: the start map overflows in some cells; the summary counts them (at least the start's,
  // as the float evaluator itself counts them), and the result is still a map whose exact energy
  // is the reported one, never above the start.
  const EnergyGrid level = MakeEnergyGrid(start.sdf, WeightField::kLayer, 8);
  const Evaluation<float> at_start =
      CachedEnergy<float>(start.map, level).Evaluate(start.map.variables().cast<float>(), EnergyMode::kVariable);
  ASSERT_GT(at_start.counts.overflowed, 0) << "float does not overflow on this map: the test proves less";
  EXPECT_TRUE(flt.summary.complete);
  ASSERT_EQ(flt.summary.passes.size(), 2u);
  EXPECT_GE(flt.summary.passes[0].overflowed_cells, at_start.counts.overflowed);
  EXPECT_LE(flt.summary.absolute_end, flt.summary.absolute_start);
  EXPECT_NEAR(start.AbsoluteEnergy(flt.map, WeightField::kLayer), flt.summary.absolute_end, 1e-12);
  // The exact (log-linear) energy of float's result is worse than double's: the overflowed cells
  // were left out of what it minimized.
  EXPECT_GT(flt.summary.absolute_end, dbl.summary.absolute_end);
}

}  // namespace
}  // namespace quijibo::optim
