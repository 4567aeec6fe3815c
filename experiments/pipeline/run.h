// `quijibo run`: an experiment end to end, as a list of stage calls into a results folder with the
// stage cache (experiments/pipeline/stage_cache.h), run.json, experiment.resolved.json and
// report.md (docs/experiments.md).
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "experiments/pipeline/experiment.h"
#include "experiments/pipeline/stage_cache.h"

namespace quijibo::pipeline {

struct RunOptions {
  std::string out_dir;      // the results folder; empty: the experiment's outputs.folder, else results/<name>
  bool resume = false;      // continue an interrupted optimization from its checkpoint
  bool check_only = false;  // validate only: nothing is written (RunSummary::resolved holds the experiment)
  bool quiet = false;       // no progress on stderr
};

struct RunSummary {
  std::string results;  // the results folder, absolute
  std::vector<StageRecord> stages;
  double seconds = 0;
  nlohmann::json resolved;  // the resolved experiment (with "results" when it ran)
};

// Runs (or, with check_only, only resolves) the experiment. A results folder this run created and
// left empty is removed on failure. Throws quijibo::Error.
RunSummary RunExperiment(const Experiment& experiment, const RunOptions& options);

// report.md of a finished run in `results` (experiments/pipeline/report.cpp).
std::string RunReport(const Experiment& experiment, const std::vector<StageRecord>& stages, const std::string& results,
                      double total_seconds);

}  // namespace quijibo::pipeline
