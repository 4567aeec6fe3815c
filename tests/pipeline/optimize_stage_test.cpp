// The optimize stage (what `quijibo optimize`, `quijibo run` and Python call): without a folder
// it writes nothing and returns the map it writes with one.
#include <gtest/gtest.h>

#include <filesystem>

#include "experiments/pipeline/optimize.h"
#include "optim/small_run.h"
#include "util/error.h"

namespace quijibo::pipeline {
namespace {

namespace fs = std::filesystem;

TEST(OptimizeStageTest, WithoutAFolderWritesNothingAndReturnsTheSameMap) {
  const SmallRun run;
  OptimizeStageOptions o;
  o.optimizer.max_iterations = {5, 10, 8};
  o.optimizer.schedule = o.optimizer.ScheduleFromNotation("8(VF)20(VF)");
  const fs::path dir = fs::temp_directory_path() / "quijibo_optimize_stage_with";
  fs::remove_all(dir);
  const OptimizeStageResult with = OptimizeStage(run.sdf, run.map, o, dir.string(), false);
  for (const char* file : {"initial_map.json", "map.json", "log.jsonl", "summary.json", "checkpoint.json"})
    EXPECT_TRUE(fs::exists(dir / file)) << file;

  const fs::path cwd = fs::temp_directory_path() / "quijibo_optimize_stage_cwd";
  fs::remove_all(cwd);
  fs::create_directories(cwd);
  const fs::path before = fs::current_path();
  fs::current_path(cwd);
  const OptimizeStageResult without = OptimizeStage(run.sdf, run.map, o, "", false);
  fs::current_path(before);
  EXPECT_TRUE(fs::is_empty(cwd));
  EXPECT_TRUE(without.summary.complete);
  EXPECT_EQ(without.map.variables(), with.map.variables());
  EXPECT_EQ(ReadMap((dir / "map.json").string()).variables(), without.map.variables());
  EXPECT_EQ(without.map.provenance["optimized"], with.map.provenance["optimized"]);
  EXPECT_THROW(OptimizeStage(run.sdf, run.map, o, "", true), Error);
  fs::remove_all(dir);
  fs::remove_all(cwd);
}

}  // namespace
}  // namespace quijibo::pipeline
