// The optimizer's energy used on its own (optim::Objective): the same figures as the run's log;
// and a run without an output folder: nothing written, the same map as with one.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <unistd.h>

#include "optim/objective.h"
#include "optim/optimizer.h"
#include "optim/small_run.h"
#include "util/error.h"

namespace quijibo::optim {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

std::vector<json> ReadLog(const std::string& path) {
  std::vector<json> lines;
  std::ifstream in(path);
  for (std::string line; std::getline(in, line);) lines.push_back(json::parse(line));
  return lines;
}

struct RecordingCallback : IterationCallback {
  std::function<void(const IterationSummary&)> f;
  explicit RecordingCallback(std::function<void(const IterationSummary&)> fn) : f(std::move(fn)) {}
  CallbackReturnType operator()(const IterationSummary& s) override {
    f(s);
    return CallbackReturnType::kContinue;
  }
};

// Each level starts with a pass whose start map the test knows (the initial map, then the first
// level's map_level file), and R begins the first level, so that V, R and F start energies, the
// absolute energies and the raised level are all checked against the log.
OptimizeOptions ObjectiveRunOptions(const std::string& evaluator, Precision precision) {
  OptimizeOptions o;
  o.evaluator = evaluator;
  o.precision = precision;
  o.max_iterations = {6, 10, 8};
  o.schedule = o.ScheduleFromNotation("8(RF)20(VF)");
  return o;
}

class ObjectiveTest : public ::testing::TestWithParam<std::pair<std::string, Precision>> {};

TEST_P(ObjectiveTest, GivesTheEnergiesOfTheOptimizersLog) {
  const SmallRun run;
  OptimizeOptions o = ObjectiveRunOptions(GetParam().first, GetParam().second);
  o.out_dir = TestCaseDir("objective", "run");
  RationalMap result = run.map;
  const OptimizeSummary s = Optimize(run.sdf, result, o);
  ASSERT_TRUE(s.complete);
  ASSERT_EQ(s.passes.size(), 4u);
  const std::vector<json> log = ReadLog(o.out_dir + "/log.jsonl");
  ASSERT_FALSE(log.empty());
  ASSERT_EQ(log[0]["type"], "run");

  const Eigen::VectorXd x0 = run.map.variables();
  Objective first(run.sdf, run.map, o, 8);
  EXPECT_GT(s.levels[0].resolution, 8);  // raised by min_level_fidelity: 8^3 does not represent the torus
  EXPECT_EQ(first.resolution(), s.levels[0].resolution);
  EXPECT_EQ(first.evaluator(), log[0]["evaluator"].get<std::string>());
  // The run's absolute energy of the start map, and the R pass's start energy (its weights
  // reweighted at the start map).
  EXPECT_EQ(first.Absolute(x0), log[0]["absolute_energy"].get<double>());
  EXPECT_EQ(first.Absolute(x0), s.absolute_start);
  first.BeginPass(PassKind::kReweighted, x0);
  EXPECT_EQ(first.Evaluate(x0).energy, s.passes[0].energy_start);
  // The level's own weights (F; the default before any BeginPass on a new objective).
  Objective fresh(run.sdf, run.map, o, 8);
  const Evaluation<double> f = fresh.Evaluate(x0);
  first.BeginPass(PassKind::kFull, x0);
  EXPECT_EQ(first.Evaluate(x0).energy, f.energy);
  EXPECT_EQ(f.gradient.size(), x0.size());

  // The second level starts from the first level's map: its V pass's start energy.
  const Eigen::VectorXd x1 = ReadMap(o.out_dir + "/map_level_" + std::to_string(s.levels[0].resolution) + ".json")
                                 .variables();
  EXPECT_EQ(first.Absolute(x1), s.passes[1].absolute_end);
  Objective second(run.sdf, run.map, o, 20);
  EXPECT_EQ(second.resolution(), 20);
  second.BeginPass(PassKind::kVariable, x1);
  const Evaluation<double> v = second.Evaluate(x1);
  EXPECT_EQ(v.energy, s.passes[2].energy_start);
  EXPECT_EQ(v.gradient.size(), 3);
  // The result's absolute energy, at the finest level: the target's own grid.
  Objective finest(run.sdf, run.map, o);
  EXPECT_EQ(finest.resolution(), 0);
  EXPECT_EQ(finest.Absolute(result.variables()), s.absolute_end);
  fs::remove_all(o.out_dir);
}

INSTANTIATE_TEST_SUITE_P(Evaluators, ObjectiveTest,
                         ::testing::Values(std::make_pair(std::string("band"), Precision::kDouble),
                                           std::make_pair(std::string("dense"), Precision::kDouble),
                                           std::make_pair(std::string("cached"), Precision::kDouble),
                                           std::make_pair(std::string("cached"), Precision::kLongDouble)),
                         [](const auto& info) {
                           return info.param.first + (info.param.second == Precision::kDouble ? "" : "LongDouble");
                         });

TEST(ObjectiveInputTest, RefusesBadInput) {
  const SmallRun run;
  OptimizeOptions o;
  EXPECT_THROW(Objective(run.sdf, run.map, o, -1), Error);
  o.evaluator = "fastest";
  EXPECT_THROW(Objective(run.sdf, run.map, o, 8), Error);
}

// A run without an output folder writes nothing (not in the working folder either) and is the
// run with one: the same records but for the clock, the same summary and the same map.
TEST(OptimizeWithoutFolder, WritesNothingAndGivesTheSameMap) {
  const SmallRun run;
  auto records = [](std::vector<json>& into) {
    return RecordingCallback([&into](const IterationSummary& s) {
      json j = s.ToJson();
      j.erase("seconds");  // a pass_end record's is the run's clock, not the pass's
      into.push_back(j);
    });
  };
  OptimizeOptions o = ObjectiveRunOptions("auto", Precision::kDouble);
  o.schedule = o.ScheduleFromNotation("8(VFRF)20(VF)");
  o.checkpoint_every = 3;  // checkpoints restart the L-BFGS memory, with or without a folder
  o.absolute_every = 2;

  std::vector<json> with_records, without_records;
  RecordingCallback with_callback = records(with_records), without_callback = records(without_records);
  OptimizeOptions with = o;
  with.out_dir = TestCaseDir("objective", "with");
  with.callbacks = {&with_callback};
  RationalMap with_map = run.map;
  const OptimizeSummary with_summary = Optimize(run.sdf, with_map, with);
  ASSERT_TRUE(with_summary.complete);
  ASSERT_TRUE(fs::exists(with.out_dir + "/log.jsonl"));

  const std::string cwd = TestCaseDir("objective", "cwd");
  fs::create_directories(cwd);
  const fs::path before = fs::current_path();
  fs::current_path(cwd);
  OptimizeOptions without = o;
  without.callbacks = {&without_callback};
  RationalMap without_map = run.map;
  const OptimizeSummary without_summary = Optimize(run.sdf, without_map, without);
  fs::current_path(before);
  ASSERT_TRUE(without_summary.complete);
  EXPECT_TRUE(fs::is_empty(cwd));
  for (const char* file : {"log.jsonl", "checkpoint.json", "summary.json", "map_level_20.json"})
    EXPECT_FALSE(fs::exists(fs::path("/") / file)) << file;

  EXPECT_EQ(without_map.variables(), with_map.variables());
  EXPECT_EQ(without_records, with_records);
  auto without_clock = [&o](const OptimizeSummary& s) {
    json j = s.ToJson(o);
    j.erase("seconds");
    for (json& p : j["passes"]) p.erase("seconds");
    return j;
  };
  EXPECT_EQ(without_clock(without_summary), without_clock(with_summary));
  fs::remove_all(with.out_dir);
  fs::remove_all(cwd);
}

TEST(OptimizeWithoutFolder, CannotResume) {
  const SmallRun run;
  OptimizeOptions o = ObjectiveRunOptions("auto", Precision::kDouble);
  o.resume = true;
  RationalMap map = run.map;
  try {
    Optimize(run.sdf, map, o);
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("resume"), std::string::npos) << e.what();
  }
}


// The absolute energy of the empty set and of the full box is >= 0 in every weight mode, with and
// without the cell corners: no trivial set beats psi = 0 (quijibo/energy.h TrivialSetEnergy).
TEST(ObjectiveTrivialSets, ScoreNoBetterThanZeroInEveryWeightMode) {
  const SmallRun run;
  RationalMap far;
  far.top_roots = {{100, 0, 0, 0}};
  far.top_exponents = {1.0};
  for (WeightField w : {WeightField::kLayer, WeightField::kInverse, WeightField::kBalanced})
    for (AutoSwitch corners : {AutoSwitch::kOff, AutoSwitch::kOn}) {
      OptimizeOptions o;
      o.weights = w;
      o.between_nodes = corners;
      Objective objective(run.sdf, far, o);
      Eigen::VectorXd x = far.variables();
      x[0] = 20;  // L = 20 + log|q - r| > 0 on the grid: the empty set
      EXPECT_GE(objective.Absolute(x), -1e-12) << WeightFieldName(w) << " " << AutoSwitchName(corners);
      x[0] = -20;  // L < 0: the full box
      EXPECT_GE(objective.Absolute(x), -1e-12) << WeightFieldName(w) << " " << AutoSwitchName(corners);
    }
}

}  // namespace
}  // namespace quijibo::optim
