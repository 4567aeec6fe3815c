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
  // SIGINT and SIGTERM end the run with report.md INCOMPLETE, one line on stderr and exit code
  // 128 + signal (the command line; a host such as Python keeps its own handlers).
  bool handle_signals = false;
};

struct RunSummary {
  std::string results;  // the results folder, absolute
  std::vector<StageRecord> stages;
  double seconds = 0;
  nlohmann::json resolved;  // the resolved experiment (with "results" when it ran)
};

// Runs (or, with check_only, only resolves) the experiment. Before a stage computes (is not
// reused), the folders of the stages that read its output are removed and report.md and run.json
// say INCOMPLETE until the run ends, so a run that stops never leaves results of other settings
// beside its own (docs/experiments.md). A results folder this run created is removed when the run
// fails before a stage finished. Throws quijibo::Error (quijibo::Interrupted when the optimization
// stopped on a signal).
RunSummary RunExperiment(const Experiment& experiment, const RunOptions& options);

}  // namespace quijibo::pipeline
