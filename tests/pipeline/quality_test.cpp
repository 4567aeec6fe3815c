// The Quality section's verdict on the optimization itself: the one-step IoU on the target grid
// before and after (experiments/pipeline/quality.h).
#include <gtest/gtest.h>

#include "quijibo/julia_setup.h"
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <tuple>
#include <nlohmann/json.hpp>

#include "experiments/pipeline/quality.h"
#include "monopole/kernel_fit.h"
#include "quijibo/grid.h"
#include "quijibo/iou.h"
#include "quijibo/julia_setup.h"
#include "quijibo/rational_map.h"
#include "tests/ball_map.h"

namespace quijibo::pipeline {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// A run folder holding only the fidelity stage's figures, as RunQuality reads them.
std::string FolderWithFidelity(const std::string& name, const json& fidelity) {
  const std::string dir = (fs::temp_directory_path() / (name + "_" + std::to_string(::getpid()))).string();
  fs::remove_all(dir);
  fs::create_directories(dir + "/fidelity");
  std::ofstream(dir + "/fidelity/fidelity.json") << fidelity.dump(1);
  return dir;
}

json Fidelity(double start_iou, double optimized_iou) {
  return {{"lattice", 32},
          {"iterations", 1},
          {"one_step", {{"iou", 0.95}, {"leak", 0.0}}},
          {"start", {{"iou", start_iou}, {"saturated_fraction", 0.0}, {"inverted", false}}},
          {"target_grid", {{"resolution", 97}, {"start_iou", start_iou}, {"iou", optimized_iou}}}};
}

bool Warns(const json& q, const std::string& what) {
  for (const json& w : q["warnings"])
    if (w.get<std::string>().find(what) != std::string::npos) return true;
  return false;
}

TEST(Quality, AnOptimizationThatLosesIoUOnTheTargetGridIsWarnedAbout) {
  const std::string dir = FolderWithFidelity("quality_loss", Fidelity(0.9778, 0.9628));
  const json q = RunQuality(Experiment{}, dir);
  EXPECT_TRUE(Warns(q, "the optimization made the one-step set worse on the target grid: IoU 0.9778 at the "
                       "start, 0.9628 optimized"))
      << q;
  EXPECT_EQ(q["figures"]["target_grid"]["iou"], 0.9628);
  EXPECT_NE(QualitySection(q).find("| one-step IoU on the target grid (97^3): start -> optimized | 0.9778 -> 0.9628 |"),
            std::string::npos)
      << QualitySection(q);
  fs::remove_all(dir);
}

TEST(Quality, AGainOrALossWithinTheToleranceIsNotWarnedAbout) {
  for (const double after : {0.9807, 0.9778, 0.9778 - 0.0015}) {
    const std::string dir = FolderWithFidelity("quality_gain", Fidelity(0.9778, after));
    const json q = RunQuality(Experiment{}, dir);
    EXPECT_FALSE(Warns(q, "worse on the target grid")) << q;
    fs::remove_all(dir);
  }
}

// Between "does not follow the shape" (IoU < 0.5) and a good fit (>= 0.8) the set follows the shape
// coarsely; the warning says what the run's files suggest: more iterations when the last pass hit its
// cap, the log-kernel start when the run began from the monopoles.
TEST(Quality, ASetThatFollowsTheShapeOnlyCoarselyIsWarnedAboutWithWhatToDo) {
  json fidelity = Fidelity(0.646, 0.654);
  fidelity["one_step"]["iou"] = 0.656;
  const std::string dir = FolderWithFidelity("quality_coarse", fidelity);
  fs::create_directories(dir + "/optimized");
  std::ofstream(dir + "/optimized/summary.json")
      << json{{"passes", json::array({json{{"pass", "V"}, {"stop", "tolerance"}},
                                      json{{"pass", "F"}, {"stop", "max-iterations"}}})}}.dump();
  Experiment monopoles;
  monopoles.initial.kind = "monopoles";
  const json q = RunQuality(monopoles, dir);
  EXPECT_TRUE(Warns(q, "the optimized map's one-step set follows the shape only coarsely: one-step IoU 0.656 "
                       "(below 0.80")) << q;
  EXPECT_TRUE(Warns(q, "stopped at its iteration cap")) << q;
  EXPECT_TRUE(Warns(q, "the log-kernel start")) << q;
  EXPECT_FALSE(Warns(q, "does not follow the shape")) << q;

  // The log-kernel start, its last pass converged: the warning alone, no remedy that does not apply.
  std::ofstream(dir + "/optimized/summary.json")
      << json{{"passes", json::array({json{{"pass", "F"}, {"stop", "tolerance"}}})}}.dump();
  const json k = RunQuality(Experiment{}, dir);
  EXPECT_TRUE(Warns(k, "follows the shape only coarsely")) << k;
  EXPECT_FALSE(Warns(k, "iteration cap")) << k;
  EXPECT_FALSE(Warns(k, "log-kernel start")) << k;

  // Above the bar no such warning; below 0.5 the stronger one instead.
  for (const auto& [iou, coarse, lost] : {std::tuple{0.80, false, false}, std::tuple{0.95, false, false},
                                          std::tuple{0.40, false, true}}) {
    fidelity["one_step"]["iou"] = iou;
    std::ofstream(dir + "/fidelity/fidelity.json") << fidelity.dump(1);
    const json w = RunQuality(monopoles, dir);
    EXPECT_EQ(Warns(w, "follows the shape only coarsely"), coarse) << iou << w;
    EXPECT_EQ(Warns(w, "does not follow the shape"), lost) << iou << w;
  }
  fs::remove_all(dir);
}

// The unit sphere's distance on a cube of side `side` with `cells` cells per axis.
ScalarGrid UnitSphere(int cells, double side) {
  ScalarGrid sphere;
  sphere.frame = GridFrame::Cube(cells, {0.0, 0.0, 0.0}, side);
  sphere.values.resize(sphere.frame.cell_count());
  for (std::int64_t c = 0; c < sphere.frame.cell_count(); ++c) {
    const Vec3 p = sphere.frame.cell_center(c);
    sphere.values[std::size_t(c)] = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]) - 1.0;
  }
  return sphere;
}

// MeasureQuality states the chosen map's IoU on the target grid beside the start's: a map with a
// larger one-step ball than the target's sphere scores lower than one that matches it.
TEST(Quality, MeasureQualityGivesTheChosenMapsIoUOnTheTargetGrid) {
  const ScalarGrid sphere = UnitSphere(24, 3.0);
  JuliaOptions julia;
  julia.iterations = 1;
  QualityOptions options;
  options.lattice = 16;
  options.iterated =
      std::make_shared<const RationalMap>(MakeJuliaSetup(testing::BallMap(1.3), JuliaSetupOptions{}).map);
  const json j = MeasureQuality(testing::BallMap(1.0), testing::BallMap(1.3), sphere, julia, 0.0, 10.0, nullptr, options);
  const double start = j["target_grid"]["start_iou"], optimized = j["target_grid"]["iou"];
  EXPECT_EQ(start, monopole::CheckStart(testing::BallMap(1.0), sphere).iou);
  EXPECT_GT(start, 0.9);
  EXPECT_LT(optimized, 0.6);  // (1 / 1.3)^3 = 0.455 of the larger ball is the sphere
  EXPECT_EQ(j["target_grid"]["resolution"], 24);
}

// A fit tight at the nodes and loose between them (the chair as optimized on the nodes alone) is
// warned about; a gap within the tolerance is not. Both figures are node_fit's.
TEST(Quality, AFitThatNarrowsBetweenTheNodesIsWarnedAbout) {
  for (const auto& [between, warned] : {std::pair{0.70, true}, std::pair{0.86, false}}) {
    json f = Fidelity(0.7895, 0.8715);
    f["target_grid"]["node_fit"] = {{"on_nodes_iou", 0.9}, {"between_nodes_iou", between}};
    const std::string dir = FolderWithFidelity("quality_nodes", f);
    const json q = RunQuality(Experiment{}, dir);
    EXPECT_EQ(Warns(q, "fits the target grid's nodes (IoU 0.900) but not the space between them (IoU " +
                           Fixed(between, 3)),
              warned)
        << q;
    EXPECT_NE(QualitySection(q).find("on the target grid's nodes / between them (cell corners) | 0.9000 / " +
                                      Fixed(between, 4) + " |"),
              std::string::npos)
        << QualitySection(q);
    fs::remove_all(dir);
  }
}


// MeasureNodeFit: a ball that matches the sphere fits the corners as well as the nodes, a ball too
// large fits both as badly; every node and interior corner is counted or undecided, and leaving the
// undecided out only raises the nodes' figure above CheckStart's, which counts them all.
TEST(Quality, NodeFitMeasuresTheNodesAndTheCorners) {
  const ScalarGrid sphere = UnitSphere(24, 3.0);
  const mesh::NodeFit fit = mesh::MeasureNodeFit(testing::BallMap(1.0), sphere), large = mesh::MeasureNodeFit(testing::BallMap(1.3), sphere);
  EXPECT_GE(fit.on_nodes, monopole::CheckStart(testing::BallMap(1.0), sphere).iou);
  EXPECT_EQ(fit.nodes + fit.undecided_nodes, 24 * 24 * 24);
  EXPECT_GT(fit.undecided_nodes, 0);
  EXPECT_EQ(fit.corners + fit.undecided_corners, 23 * 23 * 23);
  EXPECT_GT(fit.undecided_corners, 0);
  EXPECT_GT(fit.between_nodes, 0.9);
  EXPECT_NEAR(fit.between_nodes, fit.on_nodes, 0.05);
  EXPECT_LT(large.on_nodes, 0.6);
  EXPECT_LT(large.between_nodes, 0.6);
}

// On a coarse grid (a sphere about nine cells across, the run's analytic sphere at resolution 16)
// trilinear phi at the corners is biased outward; the exact set is not scored below its fit on the
// nodes for it (IoU 0.948 when every corner counted), while a ball a cell too small still is.
TEST(Quality, NodeFitDoesNotBlameTheExactSetForTrilinearBias) {
  const ScalarGrid sphere = UnitSphere(16, 3.375);
  const mesh::NodeFit exact = mesh::MeasureNodeFit(testing::BallMap(1.0), sphere);
  EXPECT_EQ(exact.on_nodes, 1.0);
  EXPECT_GT(exact.between_nodes, 0.995);
  const mesh::NodeFit small = mesh::MeasureNodeFit(testing::BallMap(0.75), sphere);
  EXPECT_LT(small.between_nodes, 0.6);
}

// One IoU for every figure: two empty sets are the same set.
TEST(Quality, IntersectionOverUnionHasOneConventionForEmptySets) {
  EXPECT_EQ(IntersectionOverUnion(0, 0), 1.0);
  EXPECT_EQ(IntersectionOverUnion(0, 5), 0.0);
  EXPECT_EQ(IntersectionOverUnion(3, 4), 0.75);
}

}  // namespace
}  // namespace quijibo::pipeline
