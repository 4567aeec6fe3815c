// The QUIJIBO optimization (2015 paper §4.5, §5.1): a schedule of levels and passes run with
// bound-constrained L-BFGS, with a JSON-lines log, a summary, atomic checkpoints and resumption.
//
// Files written to `out_dir` (none without one: the run is the same, its records go only to the
// progress line and the callbacks, and it cannot be resumed):
//   log.jsonl          one line per iteration (relative energy: the current level and weights),
//                      "absolute" lines every `absolute_every` iterations and at pass ends (psi on
//                      the finest grid with the original weights, always by the exact log-linear
//                      evaluator so curves of all precisions compare), pass start/end lines
//   checkpoint.json    every `checkpoint_every` iterations, at pass ends, on SIGINT/SIGTERM and when
//                      a callback aborts; with the fingerprint of the settings, the target and the
//                      initial map that --resume must match (optim/checkpoint.h)
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

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "optim/iteration_callback.h"
#include "optim/schedule.h"
#include "util/json_reader.h"
#include "quijibo/energy.h"
#include "quijibo/loglinear_energy.h"
#include "quijibo/real.h"
#include "quijibo/target.h"
#include "util/settings.h"
#include "quijibo/target.h"

namespace quijibo::optim {

// The evaluator setting (one definition for the command line and the experiment files):
//   "auto"    the narrow band in double (no evaluation touches more cells than a dense one, and
//             once the fit forms they touch 6-13 % of them: docs/benchmarks.md §8), else cached
//   "band"    log-linear, narrow band (quijibo/band_energy.h): same psi and gradient as dense
//   "dense"   log-linear, every cell ("loglinear" is the older name of the same)
//   "cached"  the paper's product caches, any precision
inline const std::vector<std::string> kEvaluatorNames = {"auto", "band", "dense", "loglinear", "cached"};
// The evaluator a run uses: "band", "dense" or "cached". Throws on an unknown name.
std::string ResolveEvaluator(const std::string& name, Precision precision);

// Every optimizer setting, once: its default here, its JSON key, flag, help and range in Settings()
// (util/settings.h); FromJson, ToJson and Validate read those entries, `quijibo optimize` binds
// them as its options and `quijibo run` and Python read the experiment's "optimizer" object with
// FromJson. The schedule is read by hand (a notation, an object or a file).
struct OptimizeOptions {
  inline static const std::string kDefaultSchedule = "25(VFRF)50(VFRF)97(VF)";
  // Passes the schedule's notation leaves open get these (kDefaultMaxIterations, kDefaultTolerance;
  // a JSON schedule has its own "defaults"); ScheduleFromNotation applies them.
  struct MaxIterations {
    int V = kDefaultMaxIterations[0], F = kDefaultMaxIterations[1], R = kDefaultMaxIterations[2];
  } max_iterations;
  double tolerance = kDefaultTolerance;
  Schedule schedule = Schedule::Parse(kDefaultSchedule);
  std::string evaluator = "auto";  // kEvaluatorNames
  Precision precision = Precision::kDouble;
  std::string backend = "lbfgspp";      // "lbfgspp" (L-BFGS-B) or "ceres" (L-BFGS on x = y^2)
  // Balanced layer weights: a misclassified cell costs the same inside and outside, as in the IoU
  // (quijibo/target.h); kLayer is the reference code's, kInverse the paper's.
  WeightField weights = kDefaultWeightField;
  LevelWeights level_weights = LevelWeights::kSampleFinest;
  EnergyOptions energy;  // alpha
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
  // The energy also on every level's interior cell corners (CornerGrid): a fit whose thin walls
  // pass through the grid's nodes and narrow between them (docs/fidelity.md) pays for it, and on
  // thick shapes a fit of the nodes alone can leave the volume between them as it was or worse
  // (fidelity.md §11). About twice the work of a pass and of the absolute energy; kAuto: only on
  // a thin-walled target (quijibo/target.h); kOff: the paper's energy, on the nodes.
  AutoSwitch between_nodes = AutoSwitch::kOn;
  // Which map the run returns. kIou: the lowest absolute energy among the start and the pass ends
  // whose one-step IoU on the target grid is at least the start's, so the result never fits the
  // target worse than the start by that measure (a poor start can slide towards an empty set while
  // the energy falls: docs/fidelity.md §12). kLowestPsi: the lowest absolute energy, whatever its IoU.
  enum class Keep { kIou, kLowestPsi };
  Keep keep = Keep::kIou;
  // A pass whose one-step IoU on the target grid ends more than this below its start's is
  // reported as making the set worse (pass table, summary.json, log): the report's own bar
  // (QualityThresholds::max_iou_loss).
  double iou_tolerance = 0.002;
  // Every pass starts with tau = beta (their geometric mean) and the exponents rescaled so that each
  // root's power tau*a_i (beta*b_j) is unchanged, where tau and beta differ by more than a factor 2
  // (BalanceScales, quijibo/rational_map.h): the same map, a better-conditioned problem. The
  // gradient in a top exponent is tau times its log-distance sum, in a bottom one beta times it; a
  // V pass that raises tau and lowers beta (717 and 0.07 on tooth-paper from the monopole start)
  // leaves the bottom roots 10^4 times slower for L-BFGS, and the concavities they carve out stay
  // filled (docs/fidelity.md §12). false: the variables as the previous pass left them (the paper).
  bool balance_scales = true;
  // The log-linear evaluator's log-distance storage and, for kAuto, the finest level's budget
  // (kept in GB, the setting's unit, so that the JSON value reads back exactly).
  LogLinearOptions::Storage storage = LogLinearOptions{}.storage;
  double memory_budget_gb = LogLinearOptions{}.memory_budget_bytes / 1e9;
  int memory = 5;              // L-BFGS correction pairs (reference: 5)
  int absolute_every = 10;     // iterations between absolute-energy log lines
  int checkpoint_every = 25;   // iterations between checkpoints (and L-BFGS memory restarts)

  // Not settings of the optimization (not in ToJson, not in the checkpoint's fingerprint):
  std::string out_dir;         // "": nothing is written (no log, checkpoint, maps or summary)
  bool resume = false;         // continue from out_dir/checkpoint.json (needs out_dir)
  // Called with every record of the run (IterationSummary), in order, after the optimizer's own
  // observers; kAbort stops the run as an interrupt does. Not owned.
  std::vector<IterationCallback*> callbacks;

  // The names each choice accepts, in the order messages list them.
  inline static const std::vector<std::string> kBackendNames = {"lbfgspp", "ceres"};

  static const Schema<OptimizeOptions>& Settings();
  // "" or the first problem, naming the setting and its range.
  std::string Validate() const;
  // The per-kind caps and tolerance as the notation's pass defaults (V, F, R).
  std::vector<PassSpec> PassDefaults() const;
  // `notation` ("25(VFRF)50(VF)") with PassDefaults(); throws quijibo::Error on bad notation.
  Schedule ScheduleFromNotation(const std::string& notation) const;
  // A schedule given as a string, as `"schedule"` and `quijibo optimize --schedule` take it: the path
  // of a .json schedule file (relative to `base`; it sets its own caps) or the notation (with this
  // struct's caps and tolerance). Throws quijibo::Error naming the file or the notation's problem.
  Schedule ScheduleFromString(const std::string& notation_or_file, const std::filesystem::path& base) const;
  // The log-linear evaluators' options for a run with `evaluator` (read through a band unless
  // "dense"): the storage and the budget in bytes (which PassWeights shares between the nodes' and
  // the corners' evaluators when it fits between the nodes).
  LogLinearOptions loglinear(const std::string& evaluator = "band") const;
  // Every setting, resolved: the schedule in its JSON form, enums by name. out_dir, resume and
  // callbacks are not settings and are left out.
  nlohmann::json ToJson() const;
  // The experiment's "optimizer" object at `pointer` of a document read by `reader`: missing keys
  // take the defaults; errors are "<file>: <pointer>: <what>" (JsonReader::fail); a relative
  // schedule file resolves against `base`; `extra_keys` are allowed and ignored (a run's "name").
  // The schedule is a notation string (passes take max_iterations and tolerance), a JSON object
  // (optim/schedule.h) or the path of a .json file holding one.
  static OptimizeOptions FromJson(const JsonReader& reader, const std::string& pointer,
                                  const std::filesystem::path& base, const std::vector<std::string>& extra_keys = {});
};

inline const EnumNames<OptimizeOptions::LevelStart> kLevelStarts("level start",
                                                                 {{OptimizeOptions::LevelStart::kBest, "best"},
                                                                  {OptimizeOptions::LevelStart::kLast, "last"}});
inline const EnumNames<OptimizeOptions::Keep> kKeeps("keep", {{OptimizeOptions::Keep::kIou, "iou"},
                                                             {OptimizeOptions::Keep::kLowestPsi, "lowest-psi"}});
inline OptimizeOptions::LevelStart ParseLevelStart(const std::string& name) { return kLevelStarts.Parse(name); }
inline OptimizeOptions::Keep ParseKeep(const std::string& name) { return kKeeps.Parse(name); }
inline std::string KeepName(OptimizeOptions::Keep k) { return kKeeps.Name(k); }
inline std::string LevelStartName(OptimizeOptions::LevelStart s) { return kLevelStarts.Name(s); }

// The evaluator's settings, which the optimizer and the energy stage (`quijibo energy`) share: each
// defined once here, bound to a member of the struct that holds it, as
// Schema<O>().With(optim::PrecisionSetting([](auto& o) -> Precision& { return o.precision; })).
template <class Ref>
auto AlphaSetting(Ref ref) {
  return [ref]<class O>(Schema<O>& s) { s.Number("alpha", "--alpha", "Sharpness of tanh", ref, EnergyOptions::kAlphaRange); };
}
template <class Ref>
auto PrecisionSetting(Ref ref) {
  return [ref]<class O>(Schema<O>& s) {
    s.Enum(
         "precision", "-p,--precision", "float, double, long-double or float128 (the cached evaluator)",
         kPrecisionNames, [ref](const O& o) { return PrecisionName(ref(const_cast<O&>(o))); },
         [ref](O& o, const std::string& v) { ref(o) = ParsePrecision(v); })
        .Doc("evaluator precision (`cached` for anything but double)");
  };
}
template <class Ref>
auto WeightsSetting(Ref ref) {
  return [ref]<class O>(Schema<O>& s) {
    s.Enum(
         "weights", "-w,--weights", "Weight field: balanced (the default), layer (reference code) or inverse (paper, 1/phi)",
         kWeightFieldNames, [ref](const O& o) { return WeightFieldName(ref(const_cast<O&>(o))); },
         [ref](O& o, const std::string& v) { ref(o) = ParseWeightField(v); })
        .Doc("weight field: layer weights where a misclassified cell costs the same inside and outside (as the "
             "IoU counts it; `balanced`), the reference code's layer weights (inside and outside each normalized "
             "to 0.5; `layer`), or the paper's 1/phi (`inverse`) ([fidelity.md](fidelity.md))");
  };
}
template <class Ref>
auto LevelWeightsSetting(Ref ref) {
  return [ref]<class O>(Schema<O>& s) {
    s.Enum(
         "level_weights", "--level-weights", "Coarse-level weights: sample (the finest W, as the reference) or recompute",
         kLevelWeightNames, [ref](const O& o) { return LevelWeightsName(ref(const_cast<O&>(o))); },
         [ref](O& o, const std::string& v) { ref(o) = ParseLevelWeights(v); })
        .Doc("coarse-level weights: the finest level's sampled (the reference), or recomputed on the level");
  };
}
template <class Ref>
auto StorageSetting(Ref ref) {
  return [ref]<class O>(Schema<O>& s) {
    s.Enum(
         "storage", "--storage", "loglinear log-distance storage: auto, double, float, on-the-fly", kStorageNames,
         [ref](const O& o) { return StorageName(ref(const_cast<O&>(o))); },
         [ref](O& o, const std::string& v) { ref(o) = ParseStorage(v); })
        .Doc("log-linear log-distance storage; `on-the-fly` (what `auto` picks when the matrix exceeds the "
             "budget) keeps the rows of the cells near the surface in a cache of up to half the budget, and the "
             "band anchors on blocks");
  };
}

struct OptimizeSummary {
  std::vector<PassSummary> passes;
  double seconds = 0;
  double absolute_start = 0;
  double absolute_end = 0;   // of the returned map: the best over the start and the pass ends
  int best_pass = -1;        // index into passes of the returned map; -1: the start
  double iou_start = 0;      // the start map's one-step IoU on the target grid
  double iou_end = 0;        // the returned map's
  // The pass with the lowest absolute energy when it is not the returned one (keep iou: its set
  // fits the target worse than the start's); -1 otherwise.
  int lowest_psi_pass = -1;
  double lowest_psi = 0;
  // Each level: its scheduled resolution, the one it ran at (min_level_fidelity) and the
  // LevelFidelity of the latter.
  struct Level {
    int scheduled = 0, resolution = 0;
    double fidelity = 1;
  };
  std::vector<Level> levels;
  bool between_nodes = false;  // OptimizeOptions::between_nodes as resolved on the target
  bool complete = false;     // false when interrupted or aborted
  // Why an incomplete run stopped: "interrupted" (SIGINT/SIGTERM) or "aborted by a callback".
  std::string stop_reason;
  int signal = 0;  // the SIGINT or SIGTERM that interrupted it; 0 otherwise
  nlohmann::json ToJson(const OptimizeOptions& options) const;
  std::string Report() const;  // a readable table
  std::string BestPassName() const;  // "the map after level 25 pass F (pass 2 of 10)" or the start
};

// Runs the schedule from `map` (its exponents, ln C, tau, beta are the start; its roots stay) on
// the target `sdf`; `map` holds the result (the best map, see above) on return. Throws
// quijibo::Error on bad input, and with options.resume on a checkpoint written with other settings,
// another target or another initial map. When a SIGINT/SIGTERM arrives or a callback aborts,
// writes a checkpoint (with an output folder) and returns with complete = false. The energy it
// minimizes, on its own: optim::Objective (objective.h). Callers outside the libraries go through
// the pipeline's optimize stage (experiments/pipeline/optimize.h).
OptimizeSummary Optimize(const ScalarGrid& sdf, RationalMap& map, const OptimizeOptions& options);

// For kill-and-resume tests that do not depend on timing: with QUIJIBO_TEST_EXIT_AFTER_STEP=k in
// the environment, Optimize ends the process at once with this exit code (_exit, as a crash: no
// summary, no destructors) right after step k is logged and, when k is a checkpoint,
// checkpointed. Steps count iterations over the whole run from 1.
constexpr int kTestExitCode = 86;
// Likewise QUIJIBO_TEST_SIGNAL_AFTER_STEP=k sends the process SIGINT right after step k is logged:
// an interrupt at a known step, without timing.

}  // namespace quijibo::optim
