#include "optim/pass_weights.h"

#include "optim/reweight.h"

namespace quijibo::optim {

PassWeights::PassWeights(const ScalarGrid& sdf, WeightField field, const RationalMap& map,
                         const EnergyOptions& energy, const LogLinearOptions& loglinear)
    : sdf_(sdf),
      field_(field),
      finest_w_(ComputeWeights(sdf, field)),
      finest_(MakeEnergyGrid(sdf, finest_w_, field, 0, LevelWeights::kSampleFinest, 0.0)),
      absolute_(map, finest_, energy, loglinear) {
  if (absolute_.storage() == LogLinearOptions::Storage::kOnTheFly) absolute_band_ = std::make_unique<BandEnergy>(&absolute_);
}

EnergyGrid PassWeights::Level(int resolution, LevelWeights level_weights) const {
  return MakeEnergyGrid(sdf_, finest_w_, field_, resolution, level_weights, 0.0);
}

void PassWeights::BeginPass(PassKind kind, int resolution, const EnergyGrid& level, const Eigen::VectorXd& start,
                            SetWeights set, bool shared) {
  pass_ = &level;
  if (kind == PassKind::kReweighted) {
    // The rule reads only the sign of L, which the band's blocks give without a dense sweep.
    const std::vector<double> rw = ReweightedWeights(
        sdf_, finest_w_, absolute_band_ ? absolute_band_->LogModulus(start) : absolute_.LogModulus(start));
    reweighted_ = MakeEnergyGrid(sdf_, rw, field_, resolution, LevelWeights::kSampleFinest, 0.0);
    pass_ = &reweighted_;
  }
  set_ = std::move(set);
  shared_ = shared;
  set_(pass_->weight, pass_->eta);
}

double PassWeights::Absolute(const Eigen::VectorXd& x) {
  absolute_.SetWeights(finest_.weight, finest_.eta);
  const double psi = absolute_band_ ? absolute_band_->EvaluateOnce(x).energy
                                    : absolute_.Evaluate(x, EnergyMode::kFull, false).energy;
  if (shared_ && pass_) set_(pass_->weight, pass_->eta);
  return psi;
}

}  // namespace quijibo::optim
