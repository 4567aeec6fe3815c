// `quijibo optimize`: a target and an initial map in, an optimized map, log and summary out. The
// options bind to OptimizeOptions (optim/optimizer.h), which owns every default and range.
#include <cstdio>
#include <filesystem>

#include "experiments/cli.h"
#include "mesh/sdf_command.h"
#include "optim/optimizer.h"
#include "quijibo/error.h"
#include "quijibo/io.h"
#include "quijibo/json_reader.h"

namespace quijibo::cli {

namespace {

// The command line's check of a setting's range (the same table FromJson and Validate read).
CLI::Validator InRange(const optim::SettingRange& range) {
  return CLI::Validator(
      [range](std::string& text) -> std::string {
        double v = 0;
        try {
          std::size_t used = 0;
          v = std::stod(text, &used);
          if (used != text.size()) throw std::invalid_argument(text);
        } catch (const std::exception&) {
          return "expected a number, found " + text;
        }
        return range.contains(v) ? std::string() : "expected a value in " + range.interval() + ", found " + text;
      },
      "in " + range.interval());
}

}  // namespace

void AddOptimizeCommand(CLI::App& app) {
  struct Args {
    optim::OptimizeOptions o;  // every setting with its default
    std::string target, map_path, out_dir, schedule = optim::OptimizeOptions::kDefaultSchedule;
    // Choices by name, starting from the defaults' names.
    std::string precision = PrecisionName(o.precision), weights = WeightFieldName(o.weights),
                level_weights = optim::LevelWeightsName(o.level_weights),
                level_start = optim::LevelStartName(o.level_start), storage = StorageName(o.storage);
    int target_resolution = 97;
    bool resume = false;
  };
  auto a = std::make_shared<Args>();
  optim::OptimizeOptions& o = a->o;
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
  std::vector<CLI::Option*> notation_only = {
      c->add_option("--max-v", o.max_iterations.V, "Iteration cap of V passes (notation form)")
          ->capture_default_str()->check(InRange(optim::kMaxIterationsRange)),
      c->add_option("--max-f", o.max_iterations.F, "Iteration cap of F passes (notation form)")
          ->capture_default_str()->check(InRange(optim::kMaxIterationsRange)),
      c->add_option("--max-r", o.max_iterations.R, "Iteration cap of R passes (notation form)")
          ->capture_default_str()->check(InRange(optim::kMaxIterationsRange)),
      c->add_option("--tolerance", o.tolerance,
                    "Projected-gradient tolerance (infinity norm) of every pass (notation form)")
          ->capture_default_str()->check(InRange(optim::OptimizeOptions::kToleranceRange))};
  c->add_option("-e,--evaluator", o.evaluator,
                "auto (band in double, else cached), band (log-linear, narrow band), dense (log-linear, every "
                "cell; also: loglinear) or cached (the paper's)")
      ->capture_default_str()
      ->check(CLI::IsMember(optim::kEvaluatorNames));
  c->add_option("-p,--precision", a->precision, "float, double, long-double, float128 (cached)")
      ->capture_default_str()
      ->check(CLI::IsMember(optim::OptimizeOptions::kPrecisionNames));
  c->add_option("--backend", o.backend, "lbfgspp (bound-constrained L-BFGS-B) or ceres (L-BFGS on x = y^2)")
      ->capture_default_str()
      ->check(CLI::IsMember(optim::OptimizeOptions::kBackendNames));
  c->add_option("-w,--weights", a->weights, "layer (reference), inverse (paper) or balanced (quijibo/target.h)")
      ->capture_default_str()
      ->check(CLI::IsMember(optim::OptimizeOptions::kWeightNames));
  c->add_option("--level-weights", a->level_weights, "sample or recompute")->capture_default_str()
      ->check(CLI::IsMember(optim::OptimizeOptions::kLevelWeightNames));
  c->add_option("--level-start", a->level_start,
                "best: each level after the first starts from the map with the lowest absolute energy so far; "
                "last: from the last pass's map (the paper, the reference code)")
      ->capture_default_str()
      ->check(CLI::IsMember(optim::OptimizeOptions::kLevelStartNames));
  c->add_option("--min-level-fidelity", o.min_level_fidelity,
                "A level runs at the smallest resolution (up to the finest) whose grid represents the target with "
                "at least this IoU (0: the schedule as written)")
      ->capture_default_str()->check(InRange(optim::OptimizeOptions::kMinLevelFidelityRange));
  c->add_option("--target-resolution", a->target_resolution, "Grid of an analytic target")->capture_default_str();
  c->add_option("--alpha", o.energy.alpha, "Sharpness of tanh")->capture_default_str()
      ->check(InRange(optim::OptimizeOptions::kAlphaRange));
  c->add_option("--memory", o.memory, "L-BFGS correction pairs")->capture_default_str()
      ->check(InRange(optim::OptimizeOptions::kMemoryRange));
  c->add_option("--absolute-every", o.absolute_every, "Iterations between absolute energies in the log")
      ->capture_default_str()->check(InRange(optim::OptimizeOptions::kAbsoluteEveryRange));
  c->add_option("--checkpoint-every", o.checkpoint_every, "Iterations between checkpoints")
      ->capture_default_str()->check(InRange(optim::OptimizeOptions::kCheckpointEveryRange));
  c->add_option("--storage", a->storage, "loglinear log-distance storage: auto, double, float, on-the-fly")
      ->capture_default_str()
      ->check(CLI::IsMember(optim::OptimizeOptions::kStorageNames));
  c->add_option("--memory-budget", o.memory_budget_gb,
                "GB the finest level's log-distance matrix may take with --storage auto (else on the fly, ~5x slower)")
      ->capture_default_str()->check(InRange(optim::OptimizeOptions::kMemoryBudgetRange));
  c->callback([a, notation_only] {
    optim::OptimizeOptions& o = a->o;
    if (a->schedule.ends_with(".json")) {
      for (const CLI::Option* opt : notation_only)
        if (opt->count() > 0)
          throw Error(opt->get_name() + " does not apply to the JSON schedule " + a->schedule +
                      ": put the caps and tolerances in the file (\"defaults\": {\"V\": {\"max_iterations\": 100}} "
                      "or on each pass)");
      const nlohmann::json j = ParseJson(ReadFile(a->schedule), a->schedule);
      o.schedule = optim::Schedule::FromJson(JsonReader(j, a->schedule), "");
    } else {
      o.schedule = o.ScheduleFromNotation(a->schedule);
    }
    o.out_dir = a->out_dir;
    o.resume = a->resume;
    o.precision = ParsePrecision(a->precision);
    o.weights = ParseWeightField(a->weights);
    o.level_weights = optim::ParseLevelWeights(a->level_weights);
    o.level_start = optim::ParseLevelStart(a->level_start);
    o.storage = ParseStorage(a->storage);
    const ScalarGrid sdf = LoadTarget(a->target, a->target_resolution);
    // The initial map: given, or on resume the one the run started from.
    const std::string initial = a->out_dir + "/initial_map.json";
    RationalMap map;
    if (a->resume) {
      map = ReadMap(initial);
      mesh::CheckSameFrame(map.frame, initial, a->target);
    } else {
      if (a->map_path.empty()) throw Error("--map is required (unless --resume)");
      map = ReadMap(a->map_path);
      mesh::CheckSameFrame(map.frame, a->map_path, a->target);
      std::filesystem::create_directories(a->out_dir);
      WriteMap(initial, map);
    }
    const optim::OptimizeSummary s = optim::Optimize(sdf, map, o);
    map.provenance["optimized"] = {{"schedule", o.schedule.notation()}, {"evaluator", o.evaluator},
                                   {"precision", a->precision}, {"backend", o.backend},
                                   {"absolute_energy", s.absolute_end}, {"best_pass", s.best_pass},
                                   {"complete", s.complete}};
    if (!s.complete) {
      std::fprintf(stderr, "%s", s.Report().c_str());
      throw Error("interrupted; checkpoint written to " + a->out_dir +
                  "/checkpoint.json; continue with the same command and --resume");
    }
    WriteMap(a->out_dir + "/map.json", map);
    std::fprintf(stderr, "%s", s.Report().c_str());
    std::fprintf(stderr, "quijibo: optimized map in %s/map.json, log in %s/log.jsonl, summary in %s/summary.json\n",
                 a->out_dir.c_str(), a->out_dir.c_str(), a->out_dir.c_str());
  });
}

}  // namespace quijibo::cli
