// `quijibo optimize`: a target and an initial map in, an optimized map, log and summary out, through
// the optimize stage (experiments/pipeline/optimize.h) as `quijibo run`. The options are
// OptimizeOptions' schema entries (optim/optimizer.h), which own every default and range.
#include <cstdio>
#include <filesystem>

#include "experiments/cli/bind.h"
#include "experiments/cli/cli.h"
#include "mesh/frame_file.h"
#include "experiments/pipeline/optimize.h"
#include "optim/optimizer.h"
#include "util/error.h"
#include "util/io.h"
#include "util/json_reader.h"

namespace quijibo::cli {

void AddOptimizeCommand(CLI::App& app) {
  struct Args {
    optim::OptimizeOptions o;  // every setting with its default
    std::string target, map_path, out_dir, schedule = optim::OptimizeOptions::kDefaultSchedule;
    int target_resolution = kDefaultTargetResolution;
    bool resume = false;
  };
  auto a = std::make_shared<Args>();
  CLI::App* c = app.add_subcommand(
      "optimize",
      "Optimize a map's exponents, ln C, tau and beta on a target over a multi-level schedule of V/F/R "
      "passes (bound-constrained L-BFGS); writes map.json, log.jsonl, summary.json and checkpoints");
  c->add_option("-t,--target", a->target, "Target: a .qgrid signed distance file or an analytic shape")->required();
  c->add_option("-m,--map", a->map_path, "Initial map (map.json); not needed with --resume");
  c->add_option("-s,--schedule", a->schedule,
                "Schedule in the paper's notation (passes take --max-v/f/r and --tolerance), or a JSON file with "
                "the per-pass form (which sets its own caps)")
      ->capture_default_str();
  c->add_option("-o,--out", a->out_dir, "Output folder")->required();
  c->add_flag("--resume", a->resume,
              "Continue from OUT/checkpoint.json; refused unless every setting, the target and the initial map "
              "are the ones it was written with");
  // The experiment's "optimizer" settings, from the same schema entries `quijibo run` reads.
  BindSettings(c, a->o);
  AddTargetResolution(c, a->target_resolution, "--target-resolution", "Grid of an analytic target");
  // The settings a JSON schedule sets itself.
  std::vector<CLI::Option*> notation_only;
  for (const char* flag : {"--max-v", "--max-f", "--max-r", "--tolerance"}) notation_only.push_back(c->get_option(flag));
  c->callback([a, notation_only] {
    optim::OptimizeOptions& o = a->o;
    if (a->schedule.ends_with(".json"))
      for (const CLI::Option* opt : notation_only)
        if (opt->count() > 0)
          throw Error(opt->get_name() + " does not apply to the JSON schedule " + a->schedule +
                      ": put the caps and tolerances in the file (\"defaults\": {\"V\": {\"max_iterations\": 100}} "
                      "or on each pass)");
    o.schedule = o.ScheduleFromString(a->schedule, std::filesystem::current_path());
    const ScalarGrid sdf = LoadTarget(a->target, a->target_resolution);
    // The initial map: given, or on resume the one the run started from (the stage reads it again).
    if (!a->resume && a->map_path.empty()) throw Error("--map is required (unless --resume)");
    const std::string initial_path = a->resume ? a->out_dir + "/initial_map.json" : a->map_path;
    const RationalMap initial = ReadMap(initial_path);
    mesh::CheckSameFrame(initial.frame, initial_path, a->target);
    pipeline::OptimizeStageOptions stage;
    stage.optimizer = o;
    const pipeline::OptimizeStageResult r = pipeline::OptimizeStage(sdf, initial, stage, a->out_dir, a->resume);
    std::fprintf(stderr, "%s", r.summary.Report().c_str());
    std::fprintf(stderr, "quijibo: optimized map in %s/map.json, log in %s/log.jsonl, summary in %s/summary.json\n",
                 a->out_dir.c_str(), a->out_dir.c_str(), a->out_dir.c_str());
  });
}

}  // namespace quijibo::cli
