// The optimize stage: optim::Optimize (optim/optimizer.h) from an initial map on a target grid,
// into its own folder (map.json, log.jsonl, summary.json, checkpoints; --resume continues) or, for
// a caller that keeps the result itself (Python), into none. The faces (`quijibo optimize`,
// `quijibo run`, Python) optimize only through it.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "optim/optimizer.h"
#include "quijibo/grid.h"
#include "util/json_reader.h"
#include "quijibo/rational_map.h"

namespace quijibo::pipeline {

struct OptimizeStageOptions {
  std::string name = "optimized";    // the run's folder (unique among an experiment's optimizers)
  optim::OptimizeOptions optimizer;  // every setting of the optimization (out_dir, resume: the stage's)

  // The experiment's optimizer object at `pointer`; `named`: "name" is required (an array entry).
  static OptimizeStageOptions FromJson(const JsonReader& r, const std::string& pointer,
                                       const std::filesystem::path& base, bool named);
  nlohmann::json ToJson() const;  // with "name"
};

struct OptimizeStageResult {
  RationalMap map;  // the optimized map (provenance "optimized" added)
  optim::OptimizeSummary summary;
};

// Optimizes `initial` on `target`. With an `out_dir`: into it (initial_map.json, map.json,
// log.jsonl, summary.json, checkpoint.json; optim/optimizer.h), and with `resume` continues from
// the checkpoint there, from the initial map it recorded (`initial` is not read). With out_dir "":
// nothing is written and there is nothing to resume. options.optimizer.callbacks get every record
// of the run. A run a callback aborted returns its best map so far with summary.complete false
// (no map.json); an interrupted one (SIGINT/SIGTERM) prints its report and throws
// quijibo::Interrupted, after writing its checkpoint.
OptimizeStageResult OptimizeStage(const ScalarGrid& target, const RationalMap& initial,
                                  const OptimizeStageOptions& options, const std::string& out_dir, bool resume);

}  // namespace quijibo::pipeline
