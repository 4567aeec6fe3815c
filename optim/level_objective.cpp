#include "optim/level_objective.h"

#include <algorithm>
#include <cmath>
#include <type_traits>

#include "quijibo/band_energy.h"
#include "quijibo/cached_energy.h"

namespace quijibo::optim {

using nlohmann::json;

namespace {

class DenseEvaluator : public LevelEvaluator<double> {
 public:
  explicit DenseEvaluator(LogLinearEnergy* e) : e_(e) {}
  Evaluation<double> Evaluate(const Eigen::VectorXd& x, EnergyMode mode) override { return e_->Evaluate(x, mode); }
  void BeginVariablePass(const Eigen::VectorXd& x) override { e_->BeginVariablePass(x); }
  void SetWeights(const std::vector<double>& w, double eta) override { e_->SetWeights(w, eta); }

 private:
  LogLinearEnergy* e_;
};

// The narrow band (band_energy.h) over a dense evaluator's matrix; at every pass's end the
// energy is compared with the dense one.
class BandEvaluator : public LevelEvaluator<double> {
 public:
  BandEvaluator(LogLinearEnergy* e, std::shared_ptr<const BandBlocks> blocks) : dense_(e), band_(e, std::move(blocks)) {}
  Evaluation<double> Evaluate(const Eigen::VectorXd& x, EnergyMode mode) override { return band_.Evaluate(x, mode); }
  void BeginVariablePass(const Eigen::VectorXd& x) override { dense_->BeginVariablePass(x); }
  void SetWeights(const std::vector<double>& w, double eta) override { dense_->SetWeights(w, eta); }
  void BeginPass() override {
    band_.Invalidate();
    band_.ResetStats();
  }
  json PassReport(const Eigen::VectorXd& x, EnergyMode mode, double energy) override {
    const double dense = dense_->Evaluate(x, mode, false).energy;
    const BandStats& s = band_.stats();
    return {{"cells", s.cells}, {"band_cells", s.band_cells}, {"mean_fraction", s.mean_fraction()},
            {"work_fraction", s.work_fraction()}, {"max_cells", s.max_exact}, {"evaluations", s.evaluations},
            {"anchors", s.anchors}, {"anchors_reach", s.anchors_reach}, {"anchors_work", s.anchors_work},
            {"far_sweeps", s.far}, {"block_sweeps", s.block_sweeps}, {"blocks", s.blocks},
            {"saturated_blocks", s.saturated_blocks}, {"cached_row_bytes", dense_->cached_row_bytes()},
            {"dense_fallbacks", s.dense_fallbacks}, {"energy_dense", dense},
            {"energy_error", std::fabs(energy - dense) / std::max(1e-300, std::fabs(dense))}};
  }

 private:
  LogLinearEnergy* dense_;
  BandEnergy band_;
};

template <class Scalar>
class CachedEvaluator : public LevelEvaluator<Scalar> {
 public:
  using Vector = Eigen::Matrix<Scalar, -1, 1>;
  CachedEvaluator(const RationalMap& map, const EnergyGrid& grid, const EnergyOptions& o) : e_(map, grid, o) {}
  Evaluation<Scalar> Evaluate(const Vector& x, EnergyMode mode) override { return e_.Evaluate(x, mode); }
  void BeginVariablePass(const Vector&) override {}
  void SetWeights(const std::vector<double>& w, double eta) override { e_.SetWeights(w, eta); }

 private:
  CachedEnergy<Scalar> e_;
};

}  // namespace

template <class Scalar>
LevelObjective<Scalar>::LevelObjective(PassWeights& weights, const RationalMap& map, int resolution,
                                       LevelWeights level_weights, const std::string& evaluator,
                                       const EnergyOptions& energy, const LogLinearOptions& loglinear)
    : weights_(weights), resolution_(resolution), grid_(weights.Level(resolution, level_weights)) {
  if constexpr (std::is_same_v<Scalar, double>) {
    if (evaluator == "band" || evaluator == "dense") {
      share_ = grid_.frame == weights.finest().frame;
      if (!share_) level_energy_ = std::make_unique<LogLinearEnergy>(map, grid_, energy, loglinear);
      LogLinearEnergy* e = share_ ? &weights.absolute_evaluator() : level_energy_.get();
      if (evaluator == "band")
        evaluator_ = std::make_unique<BandEvaluator>(e, share_ ? weights.absolute_blocks() : nullptr);
      else
        evaluator_ = std::make_unique<DenseEvaluator>(e);
    }
  }
  if (!evaluator_) evaluator_ = std::make_unique<CachedEvaluator<Scalar>>(map, grid_, energy);
}

template <class Scalar>
LevelObjective<Scalar>::~LevelObjective() {
  weights_.EndPass();  // PassWeights must not give weights back to an evaluator that is gone
}

template <class Scalar>
void LevelObjective<Scalar>::BeginPass(PassKind kind, const Vector& pass_start, const Vector& x) {
  weights_.BeginPass(kind, resolution_, grid_, pass_start.template cast<double>(),
                     [this](const std::vector<double>& w, double eta) { evaluator_->SetWeights(w, eta); }, share_);
  evaluator_->BeginPass();
  mode_ = kind == PassKind::kVariable ? EnergyMode::kVariable : EnergyMode::kFull;
  if (kind == PassKind::kVariable) evaluator_->BeginVariablePass(x);
}

template class LevelObjective<float>;
template class LevelObjective<double>;
template class LevelObjective<long double>;
template class LevelObjective<float128>;

}  // namespace quijibo::optim
