// The weights each pass optimizes against and the absolute energy (2015 §4.5): a pass uses its
// level's weights, an R pass the reweighted field of its start map (reweight.h); the absolute
// energy is psi on the finest grid with the original weights, by the exact log-linear evaluator,
// which the finest level's log-linear passes share: after an absolute evaluation the pass's
// weights are given back. When the finest grid's log-distances are not stored (on-the-fly: grids
// beyond ~100^3), the absolute energy goes through a narrow band over blocks (band_energy.h): exact,
// without a dense sweep. Internal to optim/.
#pragma once

#include <Eigen/Core>
#include <functional>
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
  PassWeights(const ScalarGrid& sdf, WeightField field, const RationalMap& map, const EnergyOptions& energy,
              const LogLinearOptions& loglinear);

  const EnergyGrid& finest() const { return finest_; }
  const std::vector<double>& finest_weight() const { return finest_w_; }
  LogLinearEnergy& absolute_evaluator() { return absolute_; }
  // The absolute evaluator's band blocks (null when its matrix is stored), for a band that shares it.
  std::shared_ptr<const BandBlocks> absolute_blocks() const {
    return absolute_band_ ? absolute_band_->blocks() : nullptr;
  }
  // A level's grid and weights (coarse levels sample or recompute the finest W).
  EnergyGrid Level(int resolution, LevelWeights level_weights) const;

  // Starts a pass of `kind` at `resolution` from `start`: hands its weights to `set` now, and
  // again after each Absolute when `shared` (the pass evaluates with absolute_evaluator()).
  void BeginPass(PassKind kind, int resolution, const EnergyGrid& level, const Eigen::VectorXd& start,
                 SetWeights set, bool shared);
  // The pass's minimization is over: Absolute no longer hands its weights back.
  void EndPass() {
    shared_ = false;
    set_ = nullptr;
  }
  // psi of x on the finest grid with the original weights.
  double Absolute(const Eigen::VectorXd& x);

 private:
  const ScalarGrid& sdf_;
  WeightField field_;
  std::vector<double> finest_w_;
  EnergyGrid finest_;
  LogLinearEnergy absolute_;
  std::unique_ptr<BandEnergy> absolute_band_;
  EnergyGrid reweighted_;
  const EnergyGrid* pass_ = nullptr;
  SetWeights set_;
  bool shared_ = false;
};

}  // namespace quijibo::optim
