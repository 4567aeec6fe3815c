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

// The evaluator of `grid` by `evaluator`: over `shared` (the absolute energy's, with its band
// `blocks`) when not null, else over a log-linear energy of its own kept in `own`.
template <class Scalar>
std::unique_ptr<LevelEvaluator<Scalar>> MakeEvaluator(const RationalMap& map, const EnergyGrid& grid,
                                                      const std::string& evaluator, const EnergyOptions& energy,
                                                      const LogLinearOptions& loglinear, LogLinearEnergy* shared,
                                                      std::shared_ptr<const BandBlocks> blocks,
                                                      std::unique_ptr<LogLinearEnergy>& own) {
  if constexpr (std::is_same_v<Scalar, double>) {
    if (evaluator == "band" || evaluator == "dense") {
      if (!shared) own = std::make_unique<LogLinearEnergy>(map, grid, energy, loglinear);
      LogLinearEnergy* e = shared ? shared : own.get();
      if (evaluator == "band") return std::make_unique<BandEvaluator>(e, shared ? std::move(blocks) : nullptr);
      return std::make_unique<DenseEvaluator>(e);
    }
  }
  return std::make_unique<CachedEvaluator<Scalar>>(map, grid, energy);
}

template <class Scalar>
LevelObjective<Scalar>::LevelObjective(PassWeights& weights, const RationalMap& map, int resolution,
                                       LevelWeights level_weights, const std::string& evaluator,
                                       const EnergyOptions& energy)
    : weights_(weights),
      resolution_(resolution),
      grid_(weights.Level(resolution, level_weights)),
      corners_(weights.between_nodes() ? weights.Corners(grid_) : EnergyGrid{}) {
  const bool loglinear_evaluator = std::is_same_v<Scalar, double> && (evaluator == "band" || evaluator == "dense");
  share_ = loglinear_evaluator && grid_.frame == weights.finest().frame;
  const LogLinearOptions& loglinear = weights.loglinear();
  evaluator_ = MakeEvaluator<Scalar>(map, grid_, evaluator, energy, loglinear,
                                     share_ ? &weights.absolute_evaluator() : nullptr,
                                     share_ ? weights.absolute_blocks() : nullptr, level_energy_);
  if (weights.between_nodes())
    corner_evaluator_ = MakeEvaluator<Scalar>(map, corners_, evaluator, energy, loglinear,
                                              share_ ? &weights.absolute_corners_evaluator() : nullptr,
                                              share_ ? weights.absolute_corners_blocks() : nullptr, corner_energy_);
}

template <class Scalar>
Evaluation<Scalar> LevelObjective<Scalar>::Evaluate(const Vector& x) {
  Evaluation<Scalar> e = evaluator_->Evaluate(x, mode_);
  if (!corner_evaluator_) return e;
  const Evaluation<Scalar> c = corner_evaluator_->Evaluate(x, mode_);
  e.energy += c.energy;
  if (e.gradient.size() == c.gradient.size()) e.gradient += c.gradient;
  e.counts.cells += c.counts.cells;
  e.counts.singular += c.counts.singular;
  e.counts.overflowed += c.counts.overflowed;
  e.seconds += c.seconds;
  return e;
}

template <class Scalar>
nlohmann::json LevelObjective<Scalar>::PassReport(const Vector& x, Scalar energy) {
  if (!corner_evaluator_) return evaluator_->PassReport(x, mode_, energy);
  const Scalar nodes = evaluator_->Evaluate(x, mode_).energy, corners = corner_evaluator_->Evaluate(x, mode_).energy;
  nlohmann::json r = evaluator_->PassReport(x, mode_, nodes);
  const nlohmann::json c = corner_evaluator_->PassReport(x, mode_, corners);
  if (r.is_object() && c.is_object()) {
    r["energy_error"] = std::max(r["energy_error"].get<double>(), c["energy_error"].get<double>());
    r["corners"] = c;
  }
  return r;
}

template <class Scalar>
LevelObjective<Scalar>::~LevelObjective() {
  weights_.EndPass();  // PassWeights must not give weights back to an evaluator that is gone
}

template <class Scalar>
void LevelObjective<Scalar>::BeginPass(PassKind kind, const Vector& pass_start, const Vector& x) {
  PassWeights::SetWeights set_corners;
  if (corner_evaluator_)
    set_corners = [this](const std::vector<double>& w, double eta) { corner_evaluator_->SetWeights(w, eta); };
  weights_.BeginPass(kind, resolution_, grid_, pass_start.template cast<double>(),
                     [this](const std::vector<double>& w, double eta) { evaluator_->SetWeights(w, eta); }, share_,
                     corner_evaluator_ ? &corners_ : nullptr, std::move(set_corners));
  mode_ = kind == PassKind::kVariable ? EnergyMode::kVariable : EnergyMode::kFull;
  for (LevelEvaluator<Scalar>* e : {evaluator_.get(), corner_evaluator_.get()}) {
    if (!e) continue;
    e->BeginPass();
    if (kind == PassKind::kVariable) e->BeginVariablePass(x);
  }
}

template class LevelObjective<float>;
template class LevelObjective<double>;
template class LevelObjective<long double>;
template class LevelObjective<float128>;

}  // namespace quijibo::optim
