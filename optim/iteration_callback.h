// Observers of an optimization run (as Ceres' IterationCallback): Optimize hands every record of
// the run to its own observers (the JSON-lines log, the progress line, checkpoints: optim/
// jsonl_log.h, progress_line.h, checkpoint.h), then OptimizeOptions::callbacks: one log.jsonl line each.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

namespace quijibo::optim {

// What one pass reports at its end (summary.json's "passes", the log's "pass_end" lines).
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
  // The one-step IoU on the target grid ({L < 0} against {phi < 0}) of the pass's start and end
  // maps, and whether it fell by more than the optimizer's iou_tolerance (the pass made the set worse).
  double iou_start = 0, iou_end = 0;
  bool iou_loss = false;
  // Whether the map may be kept: its IoU is at least the run's start's (or keep is lowest-psi).
  bool eligible = true;
  // Narrow band passes: cells evaluated, anchors and the energy error against the dense
  // evaluator at the pass's end (null otherwise).
  nlohmann::json band;
  std::string StallReason() const;  // why a stalled pass did not move, in words
  nlohmann::json ToJson() const;
  static PassSummary FromJson(const nlohmann::json& j);
};

// One record of the run, in the order they happen:
//   kRun         the first record of a fresh run (not repeated on resume): the settings in
//                `run`, the start map's absolute energy in `absolute`
//   kLevelStart  a level after the first starting from the best map (level_start best):
//                `from_pass` (index into the passes, -1 the start map) and its `absolute`
//   kLevelRaised a level runs finer than scheduled (min_level_fidelity): `level` is the resolution
//                it runs at, `scheduled` the schedule's, `fidelity` the LevelFidelity of the former
//   kPassStart   a pass begins
//   kIteration   after every L-BFGS iteration: the pass's (relative) energy and projected gradient
//   kAbsolute    every absolute_every iterations: psi on the finest grid with the original
//                weights (`energy`), by the exact log-linear evaluator
//   kPassEnd     a pass ended: `pass`
struct IterationSummary {
  enum class Type { kRun, kLevelStart, kLevelRaised, kPassStart, kIteration, kAbsolute, kPassEnd };
  Type type = Type::kIteration;
  long long step = 0;   // iterations of the whole run so far, from 1
  double seconds = 0;   // since the run began (a resumed run adds the time before)
  int level = 0;        // the level's resolution
  int level_index = 0, pass_index = 0;
  char kind = 'F';      // V, F or R
  int iteration = 0;    // in the pass, from 1 (kIteration, kAbsolute)
  int evaluations = 0;  // energy evaluations of the pass so far (kIteration)
  double energy = 0;    // kIteration: the pass's energy; kAbsolute: psi on the finest grid
  double projected_gradient_norm = 0;  // infinity norm (kIteration)
  double absolute = 0;  // kRun, kLevelStart
  int from_pass = -1;   // kLevelStart
  int scheduled = 0;    // kLevelRaised
  double fidelity = 1;  // kLevelRaised
  // kPassStart: tau and beta of the pass's start map, and whether the pass began by balancing them
  // (OptimizeOptions::balance_scales; not repeated for a pass resumed mid-way).
  double tau = 0, beta = 0;
  bool balanced = false;
  nlohmann::json run;   // kRun: schedule, evaluator (resolved), precision, backend, weights, roots
  PassSummary pass;     // kPassEnd

  std::string TypeName() const;  // "iteration", "pass_end", ... as in the log
  nlohmann::json ToJson() const;  // exactly the log.jsonl line
};

enum class CallbackReturnType { kContinue, kAbort };

class IterationCallback {
 public:
  virtual ~IterationCallback() = default;
  // kAbort ends the run as an interrupt does: a checkpoint is written (so --resume continues
  // from it) and Optimize returns with complete = false, stop reason "aborted by a callback".
  // An abort on an iteration record stops after that iteration; on another record, before the
  // next pass or iteration (after the run's last pass there is nothing left to stop).
  virtual CallbackReturnType operator()(const IterationSummary& summary) = 0;
};

}  // namespace quijibo::optim
