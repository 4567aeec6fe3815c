// The energy the optimizer minimizes (2015 paper §4.5, Eqns 5-8), outside a run: psi and its
// gradient of a map's variables on a target at one level of a schedule, with the evaluator,
// precision, weights and alpha of an OptimizeOptions, as the optimizer's passes evaluate it, and
// the absolute energy (psi on the finest grid with the original weights) its log reports.
// Nothing is written; OptimizeOptions::out_dir, resume and callbacks are not read.
//
//   optim::Objective objective(target, map, options, 25);   // level 25 of a schedule
//   const Evaluation<double> e = objective.Evaluate(map.variables());
//   objective.BeginPass(optim::PassKind::kReweighted, x);    // an R pass's weights, from x
//
// A pass sets what the evaluation means: F (the default until BeginPass) every variable under the
// level's weights; V only ln C, tau and beta (the gradient has those 3 entries; the exponents stay
// at the pass's start); R every variable under the weights reweighted at the pass's start
// (reweight.h). The figures are the optimizer's bit for bit: its log's pass energies and absolute
// lines come from the same code (LevelObjective, optim/level_objective.h).
#pragma once

#include <Eigen/Core>
#include <memory>
#include <string>

#include "optim/optimizer.h"
#include "optim/schedule.h"
#include "quijibo/energy.h"
#include "quijibo/grid.h"
#include "quijibo/rational_map.h"

namespace quijibo::optim {

class Objective {
 public:
  // The energy of `map`'s roots (they stay fixed; the variables are what Evaluate takes) on the
  // signed distance grid `target` at the level a schedule writes as `resolution` (0: the target's
  // own grid). The level runs where the optimizer would run it (options.min_level_fidelity may
  // raise it: resolution()). Throws quijibo::Error on invalid options or map.
  Objective(const ScalarGrid& target, const RationalMap& map, const OptimizeOptions& options, int resolution = 0);
  ~Objective();
  Objective(const Objective&) = delete;
  Objective& operator=(const Objective&) = delete;

  int resolution() const;         // the level's resolution as run (0: the target's own grid)
  const std::string& evaluator() const;  // "band", "dense" or "cached" (ResolveEvaluator)

  // Starts a pass of `kind` from the variables `start` (see above).
  void BeginPass(PassKind kind, const Eigen::VectorXd& start);
  // psi and its gradient at the variables `x` (map.variables()' layout), in the options'
  // precision, rounded to double.
  Evaluation<double> Evaluate(const Eigen::VectorXd& x);
  // psi of `x` on the finest grid with the original weights: the log's "absolute" energy.
  double Absolute(const Eigen::VectorXd& x);

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace quijibo::optim
