// One level's energy in the precision Scalar, by the run's evaluator (band, dense or cached): what
// the optimizer's passes minimize and what optim::Objective (objective.h) hands to callers.
// Internal to optim/.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "optim/pass_weights.h"
#include "optim/schedule.h"
#include "quijibo/energy.h"
#include "quijibo/loglinear_energy.h"
#include "quijibo/rational_map.h"
#include "quijibo/target.h"

namespace quijibo::optim {

// The energy over all R + 3 variables, whichever evaluator computes it.
template <class Scalar>
class LevelEvaluator {
 public:
  using Vector = Eigen::Matrix<Scalar, -1, 1>;
  virtual ~LevelEvaluator() = default;
  virtual Evaluation<Scalar> Evaluate(const Vector& x, EnergyMode mode) = 0;
  virtual void BeginVariablePass(const Vector& x) = 0;
  virtual void SetWeights(const std::vector<double>& w, double eta) = 0;
  virtual void BeginPass() {}
  // What the pass's end adds to its summary (the band's statistics), given x and the energy the
  // pass ended with.
  virtual nlohmann::json PassReport(const Vector&, EnergyMode, Scalar) { return nullptr; }
};

template <class Scalar>
class LevelObjective {
 public:
  using Vector = Eigen::Matrix<Scalar, -1, 1>;
  // The level at `resolution` (as run) of the run whose finest grid and absolute energy are
  // `weights`, whose log-linear options it takes; `evaluator` is resolved (ResolveEvaluator). At
  // the finest level a log-linear evaluator shares the absolute energy's matrix.
  LevelObjective(PassWeights& weights, const RationalMap& map, int resolution, LevelWeights level_weights,
                 const std::string& evaluator, const EnergyOptions& energy);
  ~LevelObjective();
  LevelObjective(const LevelObjective&) = delete;
  LevelObjective& operator=(const LevelObjective&) = delete;

  int resolution() const { return resolution_; }
  // A pass of `kind`: its weights from `pass_start` (R: reweighted there), for V the exponents
  // of `x` held fixed. A resumed pass has x != pass_start.
  void BeginPass(PassKind kind, const Vector& pass_start, const Vector& x);
  // The pass's minimization is over (the absolute energy no longer gives its weights back).
  void EndPass() { weights_.EndPass(); }
  EnergyMode mode() const { return mode_; }
  // psi on the level's grid (and, with between_nodes, on its corner twin: the sum).
  Evaluation<Scalar> Evaluate(const Vector& x);
  // The evaluator's report at a pass's end (the band's: its check against the dense energy);
  // `energy` is the objective's, with between_nodes the sum over both grids, so each grid's
  // evaluator checks its own share (the corners' report under "corners").
  nlohmann::json PassReport(const Vector& x, Scalar energy);

 private:
  PassWeights& weights_;
  int resolution_;
  const EnergyGrid grid_;  // its address is the pass's (PassWeights keeps a pointer)
  const EnergyGrid corners_;  // between_nodes: the corner twin of grid_ (else empty)
  bool share_ = false;
  std::unique_ptr<LogLinearEnergy> level_energy_, corner_energy_;
  std::unique_ptr<LevelEvaluator<Scalar>> evaluator_, corner_evaluator_;
  EnergyMode mode_ = EnergyMode::kFull;
};

// Instantiated for float, double, long double and float128 in level_objective.cpp.

}  // namespace quijibo::optim
