#include "experiments/pipeline/optimize.h"

#include <cstdio>
#include <filesystem>

#include "util/error.h"
#include "util/io.h"

namespace quijibo::pipeline {

using nlohmann::json;
namespace fs = std::filesystem;

OptimizeStageOptions OptimizeStageOptions::FromJson(const JsonReader& r, const std::string& p, const fs::path& base,
                                                    bool named) {
  OptimizeStageOptions s;
  s.optimizer = optim::OptimizeOptions::FromJson(r, p, base, {"name"});
  if (named) {
    s.name = r.has(p + "/name") ? r.string(p + "/name") : "";
    if (s.name.empty() || s.name.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789-_.") !=
                              std::string::npos)
      r.fail(p + "/name", "expected a non-empty name of letters, digits, '-', '_' or '.' (it names a folder)");
  }
  return s;
}

json OptimizeStageOptions::ToJson() const {
  json j = optimizer.ToJson();
  j["name"] = name;
  return j;
}

OptimizeStageResult OptimizeStage(const ScalarGrid& target, const RationalMap& initial, const OptimizeStageOptions& s,
                                  const std::string& out_dir, bool resume) {
  optim::OptimizeOptions o = s.optimizer;
  o.out_dir = out_dir;
  o.resume = resume;
  if (auto why = o.Validate(); !why.empty()) throw Error("optimize: " + why);
  const bool folder = !out_dir.empty();
  if (resume && !folder) throw Error("optimize: resume needs the folder of the interrupted run");
  // The initial map: given, or on resume the one the run started from.
  const std::string initial_path = out_dir + "/initial_map.json";
  OptimizeStageResult res;
  if (resume) {
    res.map = ReadMap(initial_path);
  } else {
    res.map = initial;
    if (folder) {
      fs::create_directories(out_dir);
      WriteMap(initial_path, res.map);
    }
  }
  res.summary = optim::Optimize(target, res.map, o);
  const optim::OptimizeSummary& sum = res.summary;
  res.map.provenance["optimized"] = {{"schedule", o.schedule.notation()}, {"evaluator", o.evaluator},
                                     {"precision", PrecisionName(o.precision)}, {"backend", o.backend},
                                     {"absolute_energy", sum.absolute_end}, {"best_pass", sum.best_pass},
                                     {"complete", sum.complete}};
  if (!sum.complete && sum.signal) {
    std::fprintf(stderr, "%s", sum.Report().c_str());
    const std::string what = folder ? "checkpoint written to " + out_dir + "/checkpoint.json; continue with --resume"
                                    : "nothing written (no output folder)";
    throw Interrupted("interrupted (" + SignalName(sum.signal) + "); " + what, sum.signal);
  }
  if (sum.complete && folder) WriteMap(out_dir + "/map.json", res.map);
  return res;
}

}  // namespace quijibo::pipeline
