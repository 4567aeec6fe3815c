#include "optim/pass_weights.h"

#include "optim/reweight.h"
#include "quijibo/iou.h"

namespace quijibo::optim {

namespace {
// Fitting between the nodes doubles the evaluators of the same size, which then split the budget.
LogLinearOptions Shared(LogLinearOptions l, bool between_nodes) {
  if (between_nodes) l.sharing *= 2;
  return l;
}
}  // namespace

PassWeights::PassWeights(const ScalarGrid& sdf, WeightField field, const RationalMap& map,
                         const EnergyOptions& energy, const LogLinearOptions& loglinear, bool between_nodes)
    : sdf_(sdf),
      field_(field),
      loglinear_(Shared(loglinear, between_nodes)),
      finest_w_(ComputeWeights(sdf, field)),
      finest_(MakeEnergyGrid(sdf, finest_w_, field, 0, LevelWeights::kSampleFinest, 0.0)),
      absolute_(map, finest_, energy, loglinear_) {
  if (absolute_.storage() == LogLinearOptions::Storage::kOnTheFly) absolute_band_ = std::make_unique<BandEnergy>(&absolute_);
  if (between_nodes) {
    finest_corners_ = CornerGrid(sdf, field, finest_);
    corners_absolute_ = std::make_unique<LogLinearEnergy>(map, finest_corners_, energy, loglinear_);
    if (corners_absolute_->storage() == LogLinearOptions::Storage::kOnTheFly)
      corners_band_ = std::make_unique<BandEnergy>(corners_absolute_.get());
  }
  trivial_ = between_nodes ? TrivialSetEnergy({&finest_, &finest_corners_}) : TrivialSetEnergy({&finest_});
}

EnergyGrid PassWeights::Level(int resolution, LevelWeights level_weights) const {
  return MakeEnergyGrid(sdf_, finest_w_, field_, resolution, level_weights, 0.0);
}

void PassWeights::BeginPass(PassKind kind, int resolution, const EnergyGrid& level, const Eigen::VectorXd& start,
                            SetWeights set, bool shared, const EnergyGrid* level_corners, SetWeights set_corners) {
  pass_ = &level;
  pass_corners_ = between_nodes() ? level_corners : nullptr;
  if (kind == PassKind::kReweighted) {
    // The rule reads only the sign of L, which the band's blocks give without a dense sweep.
    const std::vector<double> rw = ReweightedWeights(
        sdf_, finest_w_, absolute_band_ ? absolute_band_->LogModulus(start) : absolute_.LogModulus(start));
    reweighted_ = MakeEnergyGrid(sdf_, rw, field_, resolution, LevelWeights::kSampleFinest, 0.0);
    pass_ = &reweighted_;
  }
  set_ = std::move(set);
  set_corners_ = std::move(set_corners);
  shared_ = shared;
  GiveBack();
}

void PassWeights::GiveBack() {
  const double eta = pass_->eta + (pass_corners_ ? pass_corners_->eta : 0.0);
  set_(pass_->weight, eta);
  if (pass_corners_ && set_corners_) set_corners_(pass_corners_->weight, eta);
}

double PassWeights::Absolute(const Eigen::VectorXd& x) {
  const double eta = finest_.eta + (corners_absolute_ ? finest_corners_.eta : 0.0);
  absolute_.SetWeights(finest_.weight, eta);
  double psi = absolute_band_ ? absolute_band_->EvaluateOnce(x).energy
                              : absolute_.Evaluate(x, EnergyMode::kFull, false).energy;
  if (corners_absolute_) {
    corners_absolute_->SetWeights(finest_corners_.weight, eta);
    psi += corners_band_ ? corners_band_->EvaluateOnce(x).energy
                         : corners_absolute_->Evaluate(x, EnergyMode::kFull, false).energy;
  }
  if (shared_ && pass_ && set_) GiveBack();
  return psi - trivial_;
}

double PassWeights::TargetIou(const Eigen::VectorXd& x) const {
  const std::vector<double> L = absolute_band_ ? absolute_band_->LogModulus(x) : absolute_.LogModulus(x);
  std::int64_t both = 0, either = 0;
  for (std::size_t c = 0; c < L.size(); ++c) {
    const bool in_set = L[c] < 0, in_shape = sdf_.values[c] < 0;
    both += in_set && in_shape;
    either += in_set || in_shape;
  }
  return IntersectionOverUnion(both, either);
}

}  // namespace quijibo::optim
