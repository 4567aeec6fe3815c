// `quijibo optimize`: a target and an initial map in, an optimized map, log and summary out.
#include <cstdio>
#include <filesystem>

#include "experiments/cli.h"
#include "optim/optimizer.h"
#include "quijibo/error.h"
#include "quijibo/io.h"
#include "quijibo/json_reader.h"

namespace quijibo::cli {

void AddOptimizeCommand(CLI::App& app) {
  struct Args {
    std::string target, map_path, schedule = "25(VFRF)50(VFRF)97(VF)", out_dir, weights = WeightFieldName(OptimizeOptions{}.weights),
                level_weights = "sample", evaluator = OptimizeOptions{}.evaluator, precision = "double", backend = "lbfgspp",
                storage = "auto", level_start = LevelStartName(OptimizeOptions{}.level_start);
    double memory_budget_gb = 8.0;
    int target_resolution = 97, memory = 5, absolute_every = 10, checkpoint_every = 25;
    int max_v = 200, max_f = 2000, max_r = 2000;
    double tolerance = 1e-5, alpha = 10, min_level_fidelity = OptimizeOptions{}.min_level_fidelity;
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
                "Schedule in the paper's notation, or a JSON file with the per-pass form")
      ->capture_default_str();
  c->add_option("-o,--out", a->out_dir, "Output folder")->required();
  c->add_flag("--resume", a->resume, "Continue from OUT/checkpoint.json");
  c->add_option("--max-v", a->max_v, "Iteration cap of V passes (notation form)")->capture_default_str()->check(CLI::Range(1, 10000000));
  c->add_option("--max-f", a->max_f, "Iteration cap of F passes")->capture_default_str()->check(CLI::Range(1, 10000000));
  c->add_option("--max-r", a->max_r, "Iteration cap of R passes")->capture_default_str()->check(CLI::Range(1, 10000000));
  c->add_option("--tolerance", a->tolerance, "Projected-gradient tolerance (infinity norm) of every pass")
      ->capture_default_str();
  c->add_option("-e,--evaluator", a->evaluator,
                "auto (band in double, else cached), band (log-linear, narrow band), dense (log-linear, every "
                "cell; also: loglinear) or cached (the paper's)")
      ->capture_default_str()
      ->check(CLI::IsMember(kEvaluatorNames));
  c->add_option("-p,--precision", a->precision, "float, double, long-double, float128 (cached)")
      ->capture_default_str()
      ->check(CLI::IsMember({"float", "double", "long-double", "float128"}));
  c->add_option("--backend", a->backend, "lbfgspp (bound-constrained L-BFGS-B) or ceres (L-BFGS on x = y^2)")
      ->capture_default_str()
      ->check(CLI::IsMember({"lbfgspp", "ceres"}));
  c->add_option("-w,--weights", a->weights, "layer (reference), inverse (paper) or balanced (quijibo/target.h)")->capture_default_str()
      ->check(CLI::IsMember({"layer", "inverse", "balanced"}));
  c->add_option("--level-weights", a->level_weights, "sample or recompute")->capture_default_str()
      ->check(CLI::IsMember({"sample", "recompute"}));
  c->add_option("--level-start", a->level_start,
                "best: each level after the first starts from the map with the lowest absolute energy so far; "
                "last: from the last pass's map (the paper, the reference code)")
      ->capture_default_str()
      ->check(CLI::IsMember({"best", "last"}));
  c->add_option("--min-level-fidelity", a->min_level_fidelity,
                "A level runs at the smallest resolution (up to the finest) whose grid represents the target with "
                "at least this IoU (0: the schedule as written)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  c->add_option("--target-resolution", a->target_resolution, "Grid of an analytic target")->capture_default_str();
  c->add_option("--alpha", a->alpha, "Sharpness of tanh")->capture_default_str();
  c->add_option("--memory", a->memory, "L-BFGS correction pairs")->capture_default_str();
  c->add_option("--absolute-every", a->absolute_every, "Iterations between absolute energies in the log")
      ->capture_default_str()->check(CLI::Range(1, 1000000));
  c->add_option("--checkpoint-every", a->checkpoint_every, "Iterations between checkpoints")
      ->capture_default_str()->check(CLI::Range(1, 1000000));
  c->add_option("--storage", a->storage, "loglinear log-distance storage: auto, double, float, on-the-fly")
      ->capture_default_str()
      ->check(CLI::IsMember({"auto", "double", "float", "on-the-fly"}));
  c->add_option("--memory-budget", a->memory_budget_gb,
                "GB the finest level's log-distance matrix may take with --storage auto (else on the fly, ~5x slower)")
      ->capture_default_str()->check(CLI::Range(0.0, 1.0e6));
  c->callback([a] {
    OptimizeOptions o;
    PassSpec defaults[3] = {DefaultPass(PassKind::kVariable), DefaultPass(PassKind::kFull),
                            DefaultPass(PassKind::kReweighted)};
    defaults[0].max_iterations = a->max_v;
    defaults[1].max_iterations = a->max_f;
    defaults[2].max_iterations = a->max_r;
    for (auto& d : defaults) d.tolerance = a->tolerance;
    if (a->schedule.ends_with(".json")) {
      const nlohmann::json j = ParseJson(ReadFile(a->schedule), a->schedule);
      o.schedule = Schedule::FromJson(JsonReader(j, a->schedule), "");
    } else {
      o.schedule = Schedule::Parse(a->schedule, defaults);
    }
    o.out_dir = a->out_dir;
    o.resume = a->resume;
    o.evaluator = a->evaluator;
    o.precision = ParsePrecision(a->precision);
    o.backend = a->backend;
    o.weights = ParseWeightField(a->weights);
    o.level_weights = a->level_weights == "sample" ? LevelWeights::kSampleFinest : LevelWeights::kRecompute;
    o.level_start = ParseLevelStart(a->level_start);
    o.min_level_fidelity = a->min_level_fidelity;
    o.energy.alpha = a->alpha;
    o.memory = a->memory;
    o.loglinear.storage = ParseStorage(a->storage);
    o.loglinear.memory_budget_bytes = a->memory_budget_gb * 1e9;
    o.absolute_every = a->absolute_every;
    o.checkpoint_every = a->checkpoint_every;
    const ScalarGrid sdf = LoadTarget(a->target, a->target_resolution);
    // The initial map: given, or on resume the one the run started from.
    const std::string initial = a->out_dir + "/initial_map.json";
    RationalMap map;
    if (a->resume) {
      map = ReadMap(initial);
    } else {
      if (a->map_path.empty()) throw Error("--map is required (unless --resume)");
      map = ReadMap(a->map_path);
      std::filesystem::create_directories(a->out_dir);
      WriteMap(initial, map);
    }
    const OptimizeSummary s = Optimize(sdf, map, o);
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
