// The paper's monopole start (initial kind "monopoles"): an inverted start is refused with what to
// do, a fit above epsilon is warned of, and a simple shape gets an upright start (issue 29).
#include <gtest/gtest.h>

#include "experiments/pipeline/initial.h"
#include "experiments/pipeline/target.h"
#include "mesh/triangle_mesh.h"
#include "util/error.h"
#include "tests/mesh/mesh_fixtures.h"

namespace quijibo::pipeline {
namespace {

monopole::GreedyFitSummary Fit(double residual, monopole::FitStop stop) {
  monopole::GreedyFitSummary f;
  f.final_relative_residual = residual;
  f.stop = stop;
  f.monopoles = 1000;
  f.candidates_examined = 100000;
  return f;
}

// The verdict on `start` after a fit that stopped at `residual` for `stop`, with epsilon 0.04 and
// 100000 candidates.
MonopoleStartVerdict Judge(double residual, monopole::FitStop stop, const monopole::StartCheck& start) {
  return JudgeMonopoleStart(Fit(residual, stop), 0.04, 100000, start);
}

TEST(MonopoleStart, AnInvertedStartIsRefusedWithTheResidualAndWhatToDo) {
  const monopole::StartCheck start{.median_inside = -0.607, .median_outside = -0.656, .iou = 0.0914, .inverted = true};
  const MonopoleStartVerdict v = Judge(0.0407289, monopole::FitStop::kCandidatesExhausted, start);
  ASSERT_FALSE(v.refusal.empty());
  for (const char* part : {"inverted", "0.04073", "0.04 ", "candidates exhausted", "-0.607", "-0.656", "0.0914",
                           "\"fit_target\": \"potential\"", "log-kernel"})
    EXPECT_NE(v.refusal.find(part), std::string::npos) << part << " in: " << v.refusal;
}

// The tooth's 1 - P start on the unit box (issue 29): upright by the medians, but the optimizer
// collapsed from it to an empty set. Refused, saying why and what to do.
TEST(MonopoleStart, AStartThatBarelyOverlapsTheShapeIsRefused) {
  const monopole::StartCheck start{.median_inside = -0.36, .median_outside = -0.22, .iou = 0.108};
  const MonopoleStartVerdict v = Judge(0.041, monopole::FitStop::kCandidatesExhausted, start);
  EXPECT_FALSE(v.refusal.empty());
  for (const char* part : {"0.041", "IoU 0.108", "empty the set", "--epsilon", "potential", "log-kernel"})
    EXPECT_NE(v.refusal.find(part), std::string::npos) << part << " in: " << v.refusal;
}

TEST(MonopoleStart, AnUprightConvergedStartPassesAndAnUnconvergedOneIsWarnedOf) {
  const monopole::StartCheck start{.median_inside = -1.4, .median_outside = -0.19, .iou = 0.28, .psi = -0.1};
  EXPECT_TRUE(Judge(0.0396, monopole::FitStop::kConverged, start).refusal.empty());
  EXPECT_TRUE(Judge(0.0396, monopole::FitStop::kConverged, start).warning.empty());
  const MonopoleStartVerdict v = Judge(0.05, monopole::FitStop::kMaxMonopoles, start);
  EXPECT_TRUE(v.refusal.empty());
  EXPECT_NE(v.warning.find("0.05"), std::string::npos) << v.warning;
  EXPECT_NE(v.warning.find("max_monopoles reached"), std::string::npos) << v.warning;
}

// The hand's start (docs/benchmarks.md §22): upright and overlapping the shape, but no better than
// the empty set under the energy, so the V pass empties it. Refused, saying why and what to do.
TEST(MonopoleStart, AStartNoBetterThanTheEmptySetIsRefused) {
  const monopole::StartCheck start{.median_inside = -0.5, .median_outside = 0.3, .iou = 0.347, .psi = 0.032};
  const MonopoleStartVerdict v = Judge(0.0025, monopole::FitStop::kConverged, start);
  ASSERT_FALSE(v.refusal.empty());
  for (const char* part : {"psi = 0.032", "empty set", "0.347", "log-kernel"})
    EXPECT_NE(v.refusal.find(part), std::string::npos) << part << " in: " << v.refusal;
  monopole::StartCheck better = start;
  better.psi = -0.01;
  EXPECT_TRUE(Judge(0.0025, monopole::FitStop::kConverged, better).refusal.empty());
  // Better than the empty set on the nodes but not with the cell corners a default run adds (the
  // dragon's start): refused, with both figures.
  better.psi_between_nodes = 0.00016;
  const MonopoleStartVerdict corners = Judge(0.0025, monopole::FitStop::kConverged, better);
  ASSERT_FALSE(corners.refusal.empty());
  for (const char* part : {"psi = 0.00016", "-0.01 on the target grid's nodes", "0.00016 with the cell corners"})
    EXPECT_NE(corners.refusal.find(part), std::string::npos) << part << " in: " << corners.refusal;
  better.psi_between_nodes = -0.002;
  EXPECT_TRUE(Judge(0.0025, monopole::FitStop::kConverged, better).refusal.empty());
}

// A sphere, small enough for seconds: the paper's fit converges and its start is upright, on the
// default (unit) target box.
TEST(MonopoleStart, TheSphereGetsAConvergedUprightStart) {
  const testing::TempDir dir;
  const std::string path = dir.file("sphere.obj");
  mesh::WriteObj(path, testing::Icosphere(3));
  TargetOptions t;
  t.mesh = path;
  t.resolution = 24;
  const TargetResult target = Target(t);
  InitialGuessStageOptions o;
  o.kind = "monopoles";
  o.monopole.sampling.count = 4000;
  o.monopole.fit.epsilon = 0.04;
  o.png_size = 32;
  const InitialGuessResult r = InitialGuess(target, o);
  EXPECT_LE(r.summary.at("relative_residual").get<double>(), 0.04);
  EXPECT_EQ(r.summary.at("fit_stop").get<std::string>(), "converged");
  EXPECT_FALSE(r.summary.at("start").at("inverted").get<bool>());
  EXPECT_LT(r.summary.at("start").at("psi").get<double>(), 0.0);  // better than the empty set
  EXPECT_LT(r.summary.at("start").at("psi_between_nodes").get<double>(), 0.0);  // with the corners too
  EXPECT_GT(r.summary.at("start").at("iou").get<double>(), 0.25);  // no low-overlap warning
  // The IoU scan (the default) starts unsaturated, with the best one-step IoU of the monopoles'
  // sets: at least the reference scan's, whose amplitude saturates the start.
  EXPECT_LT(r.summary.at("start").at("saturated_fraction").get<double>(), 0.1);
  // The hollow and attract roots' common exponent: the start's IoU at it is the start check's, and
  // at least the IoU with them at 0; without the scan (or with the reference scan) they stay at 0.
  ASSERT_TRUE(r.summary.contains("offset_scan"));
  const nlohmann::json& scan = r.summary.at("offset_scan");
  EXPECT_GE(scan.at("exponent").get<double>(), 0.0);
  EXPECT_GE(scan.at("iou").get<double>(), scan.at("iou_before").get<double>());
  EXPECT_NEAR(scan.at("iou").get<double>(), r.summary.at("start").at("iou").get<double>(), 1e-9);
  o.guess.offset_scan = false;
  const InitialGuessResult unscanned = InitialGuess(target, o);
  EXPECT_FALSE(unscanned.summary.contains("offset_scan"));
  EXPECT_NEAR(unscanned.summary.at("start").at("iou").get<double>(), scan.at("iou_before").get<double>(), 1e-9);
  o.guess.offset_scan = true;
  o.guess.scan = monopole::StartScan::kReference;
  const InitialGuessResult ref = InitialGuess(target, o);
  EXPECT_GE(r.summary.at("start").at("iou").get<double>(), ref.summary.at("start").at("iou").get<double>() - 1e-3);
  EXPECT_GT(ref.summary.at("start").at("saturated_fraction").get<double>(),
            r.summary.at("start").at("saturated_fraction").get<double>());
  EXPECT_FALSE(ref.summary.contains("offset_scan"));
}

}  // namespace
}  // namespace quijibo::pipeline
