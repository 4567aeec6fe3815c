// Iteration callbacks (Ceres' IterationCallback): every record of the run reaches them as the log
// holds it; kAbort stops the run with a checkpoint that --resume continues; and --resume is
// refused after any change of the settings, the target or the initial map.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>

#include "optim/optimizer.h"
#include "optim/small_run.h"
#include "output_compare.h"
#include "util/error.h"

namespace quijibo::optim {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// A callback from a function.
struct Callback : IterationCallback {
  std::function<CallbackReturnType(const IterationSummary&)> f;
  explicit Callback(std::function<CallbackReturnType(const IterationSummary&)> fn) : f(std::move(fn)) {}
  CallbackReturnType operator()(const IterationSummary& s) override { return f(s); }
};

OptimizeOptions Small(const std::string& dir, const std::string& notation = "10(VFR)20(VF)") {
  OptimizeOptions o;
  o.weights = WeightField::kLayer;
  o.max_iterations = {6, 12, 8};
  o.schedule = o.ScheduleFromNotation(notation);
  o.min_level_fidelity = 0;  // the schedule as written: the level rule is tested on its own
  o.checkpoint_every = 4;
  o.absolute_every = 3;
  o.out_dir = dir;
  return o;
}

std::vector<std::string> Lines(const std::string& path) {
  std::vector<std::string> lines;
  std::ifstream in(path);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

TEST(IterationCallbackTest, EveryRecordIsTheLogLine) {
  SmallRun run;
  OptimizeOptions o = Small(TestCaseDir("callbacks", "records"));
  std::vector<std::string> records;
  int iterations = 0;
  Callback record([&](const IterationSummary& s) {
    records.push_back(s.ToJson().dump());
    if (s.type == IterationSummary::Type::kIteration) {
      ++iterations;
      EXPECT_GE(s.iteration, 1);
      EXPECT_TRUE(std::isfinite(s.energy));
    }
    return CallbackReturnType::kContinue;
  });
  o.callbacks = {&record};
  const OptimizeSummary s = Optimize(run.sdf, run.map, o);
  ASSERT_TRUE(s.complete);
  EXPECT_EQ(records, Lines(o.out_dir + "/log.jsonl"));
  int total = 0;
  for (const PassSummary& p : s.passes) total += p.iterations;
  EXPECT_EQ(iterations, total);
  EXPECT_GT(total, 10);
  fs::remove_all(o.out_dir);
}

// A pass whose start has tau and beta more than a factor 2 apart begins with them balanced (the same map),
// and says so in its pass_start record; with balance_scales off they stay as the last pass left them.
TEST(IterationCallbackTest, PassStartsShowTheScalesAndTheirBalancing) {
  for (bool balance : {true, false}) {
    SCOPED_TRACE(balance);
    SmallRun run;
    run.map.beta = 0.25 * run.map.tau;  // a start whose scales are apart, as after a monopole start's V pass
    OptimizeOptions o = Small("", "10(VF)");
    o.balance_scales = balance;
    std::vector<IterationSummary> starts;
    Callback record([&](const IterationSummary& s) {
      if (s.type == IterationSummary::Type::kPassStart) starts.push_back(s);
      return CallbackReturnType::kContinue;
    });
    o.callbacks = {&record};
    const double tau = run.map.tau, beta = run.map.beta;
    ASSERT_TRUE(Optimize(run.sdf, run.map, o).complete);
    ASSERT_EQ(starts.size(), 2u);
    EXPECT_EQ(starts[0].balanced, balance);
    if (balance) {
      EXPECT_DOUBLE_EQ(starts[0].tau, std::sqrt(tau * beta));
      EXPECT_EQ(starts[0].tau, starts[0].beta);
      EXPECT_EQ(starts[0].ToJson()["balanced"], true);
    } else {
      EXPECT_EQ(starts[0].tau, tau);
      EXPECT_EQ(starts[0].beta, beta);
    }
  }
}

// An abort on a checkpoint iteration, or at a pass's end, leaves a checkpoint from which --resume
// finishes exactly as the uninterrupted run did.
TEST(IterationCallbackTest, AnAbortedRunResumesToTheUninterruptedOne) {
  const std::string whole = TestCaseDir("callbacks", "whole");
  {
    SmallRun run;
    ASSERT_TRUE(Optimize(run.sdf, run.map, Small(whole)).complete);
  }
  using T = IterationSummary::Type;
  const std::vector<std::pair<std::string, std::function<bool(const IterationSummary&)>>> stops = {
      {"iteration", [](const IterationSummary& s) { return s.type == T::kIteration && s.kind == 'F' && s.iteration == 8; }},
      {"pass_end", [](const IterationSummary& s) { return s.type == T::kPassEnd && s.pass_index == 1; }},
      {"run", [](const IterationSummary& s) { return s.type == T::kRun; }},
      {"pass_start", [](const IterationSummary& s) { return s.type == T::kPassStart && s.level_index == 1; }}};
  for (const auto& [name, when] : stops) {
    SCOPED_TRACE(name);
    const std::string dir = TestCaseDir("callbacks", "aborted_" + name);
    SmallRun run;
    const RationalMap start = run.map;
    OptimizeOptions o = Small(dir);
    bool aborted = false;
    Callback stop([&](const IterationSummary& s) {
      if (aborted || !when(s)) return CallbackReturnType::kContinue;
      aborted = true;
      return CallbackReturnType::kAbort;
    });
    o.callbacks = {&stop};
    const OptimizeSummary first = Optimize(run.sdf, run.map, o);
    ASSERT_TRUE(aborted);
    EXPECT_FALSE(first.complete);
    EXPECT_EQ(first.stop_reason, "aborted by a callback");
    EXPECT_NE(first.Report().find("aborted by a callback"), std::string::npos);
    ASSERT_TRUE(fs::exists(dir + "/checkpoint.json"));
    EXPECT_FALSE(json::parse(std::ifstream(dir + "/checkpoint.json"))["complete"].get<bool>());
    RationalMap map = start;
    OptimizeOptions again = Small(dir);
    again.resume = true;
    const OptimizeSummary second = Optimize(run.sdf, map, again);
    EXPECT_TRUE(second.complete);
    if (name == "pass_start") {
      // Aborted after the pass began, the run stops after that pass's first iteration (not a
      // checkpoint iteration): it resumes correctly but restarts the L-BFGS memory there.
      EXPECT_EQ(second.passes.size(), 5u);
    } else {
      testing::ExpectSameOutputs(whole, dir);
    }
    fs::remove_all(dir);
  }
  fs::remove_all(whole);
}

// --- resume refusals: one test per class of setting, each against a control that resumes.

class ResumeRefusal : public ::testing::Test {
 protected:
  // A run stopped after its 5th iteration, with its start map.
  void SetUp() override {
    dir_ = TestCaseDir("callbacks", "refusal");
    OptimizeOptions o = Small(dir_, "10(VF)");
    Callback stop([](const IterationSummary& s) {
      return s.type == IterationSummary::Type::kIteration && s.step == 5 ? CallbackReturnType::kAbort
                                                                          : CallbackReturnType::kContinue;
    });
    o.callbacks = {&stop};
    RationalMap map = run_.map;
    ASSERT_FALSE(Optimize(run_.sdf, map, o).complete);
  }
  void TearDown() override { fs::remove_all(dir_); }
  OptimizeOptions Same() const {
    OptimizeOptions o = Small(dir_, "10(VF)");
    o.resume = true;
    return o;
  }
  // The message of the refused resume ("" if it was not refused; the folder is rebuilt by SetUp
  // of the next test).
  std::string Refusal(const OptimizeOptions& o, const ScalarGrid* sdf = nullptr, const RationalMap* map = nullptr) {
    RationalMap m = map ? *map : run_.map;
    try {
      Optimize(sdf ? *sdf : run_.sdf, m, o);
    } catch (const Error& e) {
      return e.what();
    }
    return "";
  }
  SmallRun run_;
  std::string dir_;
};

TEST_F(ResumeRefusal, TheSameSettingsResume) { EXPECT_EQ(Refusal(Same()), ""); }

TEST_F(ResumeRefusal, APassCap) {
  OptimizeOptions o = Same();
  o.max_iterations.V = 5;
  o.schedule = o.ScheduleFromNotation("10(VF)");  // its caps from the changed max_iterations
  EXPECT_EQ(Refusal(o),
            "--resume: the checkpoint was written with optimizer.max_iterations.V = 6, this run has 5; rerun "
            "without --resume or with the same settings");
  // A JSON schedule's per-pass cap, the notation unchanged.
  o = Same();
  o.schedule.levels[0].passes[1].max_iterations = 13;
  EXPECT_NE(Refusal(o).find("optimizer.schedule.levels[0].passes[1].max_iterations = 12, this run has 13"),
            std::string::npos);
  o = Same();
  o.schedule = o.ScheduleFromNotation("10(VFR)");
  EXPECT_NE(Refusal(o).find("optimizer.schedule.notation = \"10(VF)\", this run has \"10(VFR)\""), std::string::npos);
  o = Same();
  o.schedule.levels[0].passes[0].tolerance = 1e-3;
  EXPECT_NE(Refusal(o).find("passes[0].tolerance"), std::string::npos);
}

TEST_F(ResumeRefusal, TheEvaluatorOrBackEnd) {
  OptimizeOptions o = Same();
  o.evaluator = "dense";
  EXPECT_NE(Refusal(o).find("optimizer.evaluator = \"auto\", this run has \"dense\""), std::string::npos);
  o = Same();
  o.backend = "ceres";
  EXPECT_NE(Refusal(o).find("optimizer.backend = \"lbfgspp\", this run has \"ceres\""), std::string::npos);
  o = Same();
  o.memory = 4;
  EXPECT_NE(Refusal(o).find("optimizer.memory = 5, this run has 4"), std::string::npos);
}

TEST_F(ResumeRefusal, AlphaWeightsOrLevelWeights) {
  OptimizeOptions o = Same();
  o.energy.alpha = 11;
  EXPECT_NE(Refusal(o).find("optimizer.alpha = 10.0, this run has 11.0"), std::string::npos);
  o = Same();
  o.weights = WeightField::kBalanced;
  EXPECT_NE(Refusal(o).find("optimizer.weights = \"layer\", this run has \"balanced\""), std::string::npos);
  o = Same();
  o.level_weights = LevelWeights::kRecompute;
  EXPECT_NE(Refusal(o).find("optimizer.level_weights = \"sample\", this run has \"recompute\""), std::string::npos);
  o = Same();
  o.level_start = OptimizeOptions::LevelStart::kBest;
  EXPECT_NE(Refusal(o).find("optimizer.level_start"), std::string::npos);
}

TEST_F(ResumeRefusal, Storage) {
  OptimizeOptions o = Same();
  o.storage = LogLinearOptions::Storage::kOnTheFly;
  EXPECT_NE(Refusal(o).find("optimizer.storage = \"auto\", this run has \"on-the-fly\""), std::string::npos);
  o = Same();
  o.memory_budget_gb = 1;
  EXPECT_NE(Refusal(o).find("optimizer.memory_budget_gb = 6.0, this run has 1.0"), std::string::npos);
}

TEST_F(ResumeRefusal, TheTarget) {
  ScalarGrid other = run_.sdf;
  other.values[other.values.size() / 2] += 1e-9;
  EXPECT_EQ(Refusal(Same(), &other),
            "--resume: the target differs from the one the checkpoint was written with; rerun without --resume or "
            "with the same settings");
}

TEST_F(ResumeRefusal, TheInitialMap) {
  RationalMap other = run_.map;
  other.top_exponents[3] *= 1 + 1e-12;
  EXPECT_EQ(Refusal(Same(), nullptr, &other),
            "--resume: the initial map differs from the one the checkpoint was written with; rerun without --resume "
            "or with the same settings");
  // Its provenance does not count.
  other = run_.map;
  other.provenance["note"] = "copied";
  EXPECT_EQ(Refusal(Same(), nullptr, &other), "");
}

}  // namespace
}  // namespace quijibo::optim
