// The energy between the grid's nodes (OptimizeOptions::between_nodes): the corner twin of a grid
// (CornerGrid) and psi as the sum over both grids, in every evaluator; what it changes in a run.
#include <gtest/gtest.h>

#include <cmath>

#include "optim/objective.h"
#include "optim/optimizer.h"
#include "optim/small_run.h"
#include "quijibo/loglinear_energy.h"
#include "quijibo/target.h"
#include "util/error.h"

namespace quijibo::optim {
namespace {

TEST(CornerGrid, HoldsTheInteriorCornersWithTheWeightsOfTheDistanceThere) {
  const SmallRun run;
  const std::vector<double> w = ComputeWeights(run.sdf, WeightField::kBalanced);
  const EnergyGrid level = MakeEnergyGrid(run.sdf, w, WeightField::kBalanced, 0, LevelWeights::kSampleFinest, 0.0);
  const EnergyGrid corners = CornerGrid(run.sdf, WeightField::kBalanced, level);
  const GridFrame& f = level.frame;
  for (int a = 0; a < 3; ++a) EXPECT_EQ(corners.frame.dims[a], f.dims[a] - 1);
  EXPECT_EQ(corners.frame.spacing, f.spacing);
  // Corner (i, j, k) is the centre of level cells i..i+1, j..j+1, k..k+1.
  const Vec3 c = corners.frame.cell_center(2, 5, 7);
  const Vec3 a = f.cell_center(2, 5, 7), b = f.cell_center(3, 6, 8);
  for (int d = 0; d < 3; ++d) EXPECT_NEAR(c[d], 0.5 * (a[d] + b[d]), 1e-12);
  ScalarGrid distance{corners.frame, {}, "signed-distance", run.sdf.coordinates};
  for (std::int64_t i = 0; i < corners.frame.cell_count(); ++i)
    distance.values.push_back(run.sdf.sample(corners.frame.cell_center(i)));
  const std::vector<double> expected = ComputeWeights(distance, WeightField::kBalanced);
  double eta = 0;
  for (std::int64_t i = 0; i < corners.frame.cell_count(); ++i) {
    EXPECT_EQ(corners.weight[std::size_t(i)], expected[std::size_t(i)]);
    // The weight's sign is the distance's: a corner inside is rewarded for being in the set.
    EXPECT_EQ(corners.weight[std::size_t(i)] < 0, distance.values[std::size_t(i)] < 0);
    eta += std::abs(corners.weight[std::size_t(i)]);
  }
  EXPECT_DOUBLE_EQ(corners.eta, eta);
  EnergyGrid flat = level;
  flat.frame.dims[2] = 1;
  EXPECT_THROW(CornerGrid(run.sdf, WeightField::kBalanced, flat), Error);
}

// psi with between_nodes is (eta psi on the nodes + eta' psi' on the corners) / (eta + eta'),
// each psi as the energy on its own grid gives it, and so is its gradient.
class BetweenNodesEnergy : public ::testing::TestWithParam<std::string> {};

TEST_P(BetweenNodesEnergy, IsTheEtaWeightedSumOfTheNodesAndTheCorners) {
  const SmallRun run;
  OptimizeOptions o;
  o.evaluator = GetParam();
  o.between_nodes = ThinWallSwitch::kOn;
  const Eigen::VectorXd x = run.map.variables();
  Objective both(run.sdf, run.map, o);
  const std::vector<double> w = ComputeWeights(run.sdf, o.weights);
  const EnergyGrid nodes = MakeEnergyGrid(run.sdf, w, o.weights, 0, LevelWeights::kSampleFinest, 0.0);
  const EnergyGrid corners = CornerGrid(run.sdf, o.weights, nodes);
  LogLinearEnergy on_nodes(run.map, nodes, o.energy), on_corners(run.map, corners, o.energy);
  const Evaluation<double> a = on_nodes.Evaluate(x), b = on_corners.Evaluate(x);
  const double eta = nodes.eta + corners.eta;
  const double expected = (nodes.eta * a.energy + corners.eta * b.energy) / eta;
  // The absolute energy is counted from the better trivial set (quijibo/energy.h); a pass's is not.
  const double trivial = TrivialSetEnergy({&nodes, &corners});
  EXPECT_NEAR(both.Absolute(x), expected - trivial, 1e-12 * std::abs(expected));
  both.BeginPass(PassKind::kFull, x);
  const Evaluation<double> e = both.Evaluate(x);
  EXPECT_NEAR(e.energy, expected, 1e-12 * std::abs(expected));
  const Eigen::VectorXd g = (nodes.eta * a.gradient + corners.eta * b.gradient) / eta;
  ASSERT_EQ(e.gradient.size(), g.size());
  EXPECT_LT((e.gradient - g).lpNorm<Eigen::Infinity>(), 1e-10 * g.lpNorm<Eigen::Infinity>());
  EXPECT_EQ(e.counts.cells, nodes.frame.cell_count() + corners.frame.cell_count());
  // Off, psi is the nodes' alone.
  o.between_nodes = ThinWallSwitch::kOff;
  Objective nodes_only(run.sdf, run.map, o);
  EXPECT_NEAR(nodes_only.Absolute(x), a.energy - TrivialSetEnergy({&nodes}), 1e-12 * std::abs(a.energy));
}

INSTANTIATE_TEST_SUITE_P(Evaluators, BetweenNodesEnergy, ::testing::Values("band", "dense", "cached"));

// A run with between_nodes logs the two-grid psi, lowers it, and ends elsewhere than a run
// without; a run without is unchanged by the option's existence (the other optimizer tests).
TEST(BetweenNodesRun, MinimizesTheTwoGridEnergy) {
  const SmallRun run;
  OptimizeOptions o;
  o.max_iterations = {6, 20, 8};
  o.schedule = o.ScheduleFromNotation("20(VF)");
  o.between_nodes = ThinWallSwitch::kOff;
  RationalMap plain = run.map;
  const OptimizeSummary s0 = Optimize(run.sdf, plain, o);
  o.between_nodes = ThinWallSwitch::kOn;
  RationalMap staggered = run.map;
  const OptimizeSummary s1 = Optimize(run.sdf, staggered, o);
  ASSERT_TRUE(s0.complete);
  ASSERT_TRUE(s1.complete);
  Objective both(run.sdf, run.map, o);
  EXPECT_EQ(s1.absolute_start, both.Absolute(run.map.variables()));
  EXPECT_EQ(s1.absolute_end, both.Absolute(staggered.variables()));
  EXPECT_LT(s1.absolute_end, s1.absolute_start);
  EXPECT_NE(s1.absolute_start, s0.absolute_start);
  EXPECT_GT((staggered.variables() - plain.variables()).norm(), 0.0);
  EXPECT_FALSE(s0.between_nodes);
  EXPECT_TRUE(s1.between_nodes);
}

// auto follows the target's walls: the 20^3 torus (tube 2.3 cells deep) is thin-walled, the same
// torus on 60^3 is not; the default, on, fits the corners of both; the summary says which was used.
TEST(BetweenNodesRun, AutoIsOnForAThinWalledTargetOnlyAndTheDefaultForEvery) {
  const SmallRun run;
  OptimizeOptions o;
  o.max_iterations = {2, 2, 2};
  o.schedule = o.ScheduleFromNotation("20(V)");
  ASSERT_EQ(o.between_nodes, ThinWallSwitch::kOn);  // the default: on for every target
  o.between_nodes = ThinWallSwitch::kAuto;
  RationalMap a = run.map;
  EXPECT_TRUE(Optimize(run.sdf, a, o).between_nodes);
  const ScalarGrid fine = AnalyticTarget("torus", GridFrame::Cube(60, {0, 0, 0}, 3.0));
  o.schedule = o.ScheduleFromNotation("60(V)");
  RationalMap b = run.map;
  EXPECT_FALSE(Optimize(fine, b, o).between_nodes);
  o.between_nodes = OptimizeOptions{}.between_nodes;  // the default fits the corners of thick targets too
  RationalMap c = run.map;
  EXPECT_TRUE(Optimize(fine, c, o).between_nodes);
}

}  // namespace
}  // namespace quijibo::optim
