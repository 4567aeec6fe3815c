// report.md: one page with the key figures of a run, read from its stages' files.
#pragma once

#include <string>
#include <vector>

#include "experiments/pipeline/experiment.h"
#include "experiments/pipeline/stage_cache.h"

namespace quijibo::pipeline {

// How a run ended, for report.md: complete, or where and why it stopped.
struct RunState {
  std::string stopped_in;  // the stage; empty: the run is complete
  std::string reason;      // why it stopped (or that it is still running)
  std::string resume;      // the command that continues it
};

// report.md of a run in `results`.
std::string RunReport(const Experiment& experiment, const std::vector<StageRecord>& stages, const std::string& results,
                      double total_seconds, const RunState& state = {});

}  // namespace quijibo::pipeline
