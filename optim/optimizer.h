// The QUIJIBO optimization (2015 paper §4.5, §5.1): a schedule of levels and passes run with
// bound-constrained L-BFGS, with a JSON-lines log, a summary, atomic checkpoints and resumption.
//
// Files written to `out_dir`:
//   log.jsonl          one line per iteration (relative energy: the current level and weights),
//                      "absolute" lines every `absolute_every` iterations and at pass ends (psi on
//                      the finest grid with the original weights, always by the exact log-linear
//                      evaluator so curves of all precisions compare), pass start/end lines
//   checkpoint.json    every `checkpoint_every` iterations, at pass ends and on SIGINT/SIGTERM
//   map_level_<N>.json the map after each level;  map.json  the result (see below)
//   summary.json       each pass's stop reason, iterations, evaluations, time and energies
//
// The result is the map with the lowest absolute energy among the start and every pass end, not
// the last one: an R pass fits the reweighted field and usually ends above the F pass before it.
// A pass that made no iteration is flagged as stalled (with the reason) and the run goes on.
//
// Resumption is exact for checkpoints taken during a run: at every checkpoint the L-BFGS memory
// restarts (in the uninterrupted run too), so the state in the file determines the rest of the
// run. A SIGINT/SIGTERM checkpoint restarts the memory at that iteration, which an uninterrupted
// run would not have done: resuming it continues correctly but not bit for bit.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "optim/schedule.h"
#include "quijibo/energy.h"
#include "quijibo/loglinear_energy.h"
#include "quijibo/real.h"

namespace quijibo {

// The evaluator setting (one definition for the command line and the experiment files):
//   "auto"    the narrow band in double (no evaluation touches more cells than a dense one, and
//             once the fit forms they touch 6-13 % of them: docs/benchmarks.md §8), else cached
//   "band"    log-linear, narrow band (quijibo/band_energy.h): same psi and gradient as dense
//   "dense"   log-linear, every cell ("loglinear" is the older name of the same)
//   "cached"  the paper's product caches, any precision
inline const std::vector<std::string> kEvaluatorNames = {"auto", "band", "dense", "loglinear", "cached"};
// The evaluator a run uses: "band", "dense" or "cached". Throws on an unknown name.
std::string ResolveEvaluator(const std::string& name, Precision precision);

struct OptimizeOptions {
  Schedule schedule;
  std::string evaluator = "auto";  // kEvaluatorNames
  Precision precision = Precision::kDouble;
  std::string backend = "lbfgspp";      // "lbfgspp" (L-BFGS-B) or "ceres" (L-BFGS on x = y^2)
  // Balanced layer weights: a misclassified cell costs the same inside and outside, as in the IoU
  // (quijibo/target.h); kLayer is the reference code's, kInverse the paper's.
  WeightField weights = WeightField::kBalanced;
  LevelWeights level_weights = LevelWeights::kSampleFinest;
  EnergyOptions energy;
  LogLinearOptions loglinear;
  // Where a level after the first starts: kLast, the last pass's map (the paper and reference);
  // kBest, the map with the lowest absolute energy so far (a coarse level whose cells are wider
  // than a thin wall can raise the absolute energy). kLast stays the default: on the spiky star
  // kBest threw away coarse F/R progress the finer level needed (one-step IoU 0.76 vs 0.88).
  enum class LevelStart { kBest, kLast };
  LevelStart level_start = LevelStart::kLast;
  // A level runs at the smallest resolution, from its scheduled one up to the finest, whose grid
  // represents the target with LevelFidelity >= this (quijibo/target.h): a level whose cells are
  // wider than the target's walls or fingers fits another shape, and its passes move the map
  // away from the target (docs/fidelity.md §6). 0.8 is the quality asked of the result (one-step
  // IoU >= 0.8): a level that cannot reach it itself cannot lead there. 0: the schedule as written
  // (the paper, the reference code).
  double min_level_fidelity = 0.8;
  int memory = 5;              // L-BFGS correction pairs (reference: 5)
  int absolute_every = 10;     // iterations between absolute-energy log lines
  int checkpoint_every = 25;   // iterations between checkpoints (and L-BFGS memory restarts)
  std::string out_dir;         // required
  bool resume = false;         // continue from out_dir/checkpoint.json
  std::string validate() const;
};

struct PassSummary {
  int level = 0, level_index = 0, pass_index = 0;
  char kind = 'F';
  std::string stop;
  int iterations = 0, evaluations = 0;
  double seconds = 0, energy_start = 0, energy_end = 0, absolute_end = 0;
  long long overflowed_cells = 0;  // largest count seen in one evaluation (cached evaluator)
  std::string message;
  int line_search_restarts = 0;  // line-search failures recovered by resetting the L-BFGS memory
  bool stalled = false;          // no iteration: the pass could not (or did not need to) move
  // Narrow band passes: cells evaluated, anchors and the energy error against the dense
  // evaluator at the pass's end (null otherwise).
  nlohmann::json band;
  std::string StallReason() const;  // why a stalled pass did not move, in words
  nlohmann::json ToJson() const;
  static PassSummary FromJson(const nlohmann::json& j);
};

struct OptimizeSummary {
  std::vector<PassSummary> passes;
  double seconds = 0;
  double absolute_start = 0;
  double absolute_end = 0;   // of the returned map: the best over the start and the pass ends
  int best_pass = -1;        // index into passes of the returned map; -1: the start
  bool complete = false;     // false when interrupted
  // Each level: its scheduled resolution, the one it ran at (min_level_fidelity) and the
  // LevelFidelity of the latter.
  struct Level {
    int scheduled = 0, resolution = 0;
    double fidelity = 1;
  };
  std::vector<Level> levels;
  nlohmann::json ToJson(const OptimizeOptions& options) const;
  std::string Report() const;  // a readable table
  std::string BestPassName() const;  // "the map after level 25 pass F (pass 2 of 10)" or the start
};

// Runs the schedule from `map` (its exponents, ln C, tau, beta are the start; its roots stay) on
// the target `sdf`; `map` holds the result (the best map, see above) on return. Throws
// quijibo::Error on bad input. When a
// SIGINT/SIGTERM arrives, writes a checkpoint and returns with complete = false.
OptimizeOptions::LevelStart ParseLevelStart(const std::string& name);  // best|last
std::string LevelStartName(OptimizeOptions::LevelStart s);

OptimizeSummary Optimize(const ScalarGrid& sdf, RationalMap& map, const OptimizeOptions& options);

}  // namespace quijibo
