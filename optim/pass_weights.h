// The weights each pass optimizes against and the absolute energy (2015 §4.5): a pass uses its
// level's weights, an R pass the reweighted field of its start map (reweight.h); the absolute
// energy is psi on the finest grid with the original weights, by the exact log-linear evaluator,
// which the finest level's log-linear passes share: after an absolute evaluation the pass's
// weights are given back. When the finest grid's log-distances are not stored (on-the-fly: grids
// beyond ~100^3), the absolute energy goes through a narrow band over blocks (band_energy.h): exact,
// without a dense sweep. With `between_nodes` every grid has a twin of its interior cell corners
// (CornerGrid, quijibo/target.h) and psi is the sum over both, each term divided by the sum of the
// two grids' eta; an R pass reweights the nodes only (the rule reads L on the finest grid's
// nodes), the corners keep their weights. Internal to optim/.
#pragma once

#include <Eigen/Core>
#include <functional>
#include <memory>
#include <vector>

#include "optim/schedule.h"
#include "quijibo/band_energy.h"
#include "quijibo/energy.h"
#include "quijibo/loglinear_energy.h"
#include "quijibo/rational_map.h"
#include "quijibo/target.h"

namespace quijibo::optim {

class PassWeights {
 public:
  using SetWeights = std::function<void(const std::vector<double>& weight, double eta)>;
  // `between_nodes`: the corner twins are fitted too, and the nodes' and the corners' evaluators
  // (here and at every level) share `loglinear`'s budget (loglinear() has the sharing).
  PassWeights(const ScalarGrid& sdf, WeightField field, const RationalMap& map, const EnergyOptions& energy,
              const LogLinearOptions& loglinear, bool between_nodes = false);

  // The log-linear options of every evaluator of the run (the budget shared when between_nodes()).
  const LogLinearOptions& loglinear() const { return loglinear_; }

  const EnergyGrid& finest() const { return finest_; }
  const std::vector<double>& finest_weight() const { return finest_w_; }
  LogLinearEnergy& absolute_evaluator() { return absolute_; }
  // The absolute evaluator's band blocks (null when its matrix is stored), for a band that shares it.
  std::shared_ptr<const BandBlocks> absolute_blocks() const {
    return absolute_band_ ? absolute_band_->blocks() : nullptr;
  }
  bool between_nodes() const { return corners_absolute_ != nullptr; }
  // The finest grid's corner twin and its absolute evaluator and blocks (between_nodes() only).
  const EnergyGrid& finest_corners() const { return finest_corners_; }
  LogLinearEnergy& absolute_corners_evaluator() { return *corners_absolute_; }
  std::shared_ptr<const BandBlocks> absolute_corners_blocks() const {
    return corners_band_ ? corners_band_->blocks() : nullptr;
  }
  // The corner twin of a level's grid.
  EnergyGrid Corners(const EnergyGrid& level) const { return CornerGrid(sdf_, field_, level); }
  // A level's grid and weights (coarse levels sample or recompute the finest W).
  EnergyGrid Level(int resolution, LevelWeights level_weights) const;

  // Starts a pass of `kind` at `resolution` from `start`: hands its weights to `set` now, and
  // again after each Absolute when `shared` (the pass evaluates with absolute_evaluator()). With
  // between_nodes(), `level_corners` is the level's corner twin and `set_corners` takes its weights
  // (the absolute's corner evaluator is shared when `shared`).
  void BeginPass(PassKind kind, int resolution, const EnergyGrid& level, const Eigen::VectorXd& start,
                 SetWeights set, bool shared, const EnergyGrid* level_corners = nullptr, SetWeights set_corners = nullptr);
  // The pass's minimization is over: Absolute no longer hands its weights back.
  void EndPass() {
    shared_ = false;
    set_ = nullptr;
    set_corners_ = nullptr;
  }
  // psi of x on the finest grid with the original weights, counted from the better trivial set
  // (TrivialSetEnergy, quijibo/energy.h): the empty set and the full box score >= 0.
  double Absolute(const Eigen::VectorXd& x);
  // The constant Absolute subtracts from the sum over the grids: TrivialSetEnergy of the finest grid
  // (and its corners). A pass minimizes the sum without it (a constant has no gradient).
  double trivial_set_energy() const { return trivial_; }
  // The one-step IoU of x on the target grid: {L < 0} against {phi < 0} at the finest grid's nodes.
  double TargetIou(const Eigen::VectorXd& x) const;

 private:
  const ScalarGrid& sdf_;
  WeightField field_;
  LogLinearOptions loglinear_;
  std::vector<double> finest_w_;
  double trivial_ = 0;
  EnergyGrid finest_;
  LogLinearEnergy absolute_;
  std::unique_ptr<BandEnergy> absolute_band_;
  EnergyGrid reweighted_;
  const EnergyGrid* pass_ = nullptr;
  SetWeights set_;
  bool shared_ = false;
  // between_nodes: the corner twins of the finest grid and of the pass's grid.
  EnergyGrid finest_corners_;
  std::unique_ptr<LogLinearEnergy> corners_absolute_;
  std::unique_ptr<BandEnergy> corners_band_;
  const EnergyGrid* pass_corners_ = nullptr;
  SetWeights set_corners_;
  // Hands the pass's weights to its evaluators, each divided by both grids' eta.
  void GiveBack();
};

}  // namespace quijibo::optim
