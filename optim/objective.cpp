#include "optim/objective.h"

#include "optim/level_objective.h"
#include "optim/pass_weights.h"
#include "util/error.h"
#include "quijibo/real.h"

namespace quijibo::optim {

// The precision is chosen at run time; the level's objective is a template.
struct Objective::Impl {
  virtual ~Impl() = default;
  virtual void BeginPass(PassKind kind, const Eigen::VectorXd& start) = 0;
  virtual Evaluation<double> Evaluate(const Eigen::VectorXd& x) = 0;
  virtual double Absolute(const Eigen::VectorXd& x) = 0;
  int resolution = 0;
  std::string evaluator;
};

namespace {

template <class Scalar>
struct ObjectiveIn : Objective::Impl {
  using Vector = Eigen::Matrix<Scalar, -1, 1>;
  // As Optimize sets the run up (optimizer.cpp): whether the corners are fitted, the target's wall
  // depth measured once.
  ObjectiveIn(const ScalarGrid& target, const RationalMap& map, const OptimizeOptions& o, int scheduled,
              const std::string& name)
      : weights(target, o.weights, map, o.energy, o.loglinear(name), ThinWallsOn(o.between_nodes, target)),
        level(weights, map,
              scheduled <= 0 ? 0
                             : ResolvedLevelResolution(target, weights.finest_weight(), o.weights, scheduled,
                                                       o.level_weights, o.min_level_fidelity),
              o.level_weights, name, o.energy) {
    resolution = level.resolution();
    evaluator = name;
    const Vector x = map.variables().cast<Scalar>();
    level.BeginPass(PassKind::kFull, x, x);
  }
  void BeginPass(PassKind kind, const Eigen::VectorXd& start) override {
    const Vector x = start.cast<Scalar>();
    level.BeginPass(kind, x, x);
  }
  Evaluation<double> Evaluate(const Eigen::VectorXd& x) override {
    const Evaluation<Scalar> e = level.Evaluate(x.cast<Scalar>());
    Evaluation<double> d;
    d.energy = ToDouble(e.energy);
    d.gradient = e.gradient.template cast<double>();
    d.counts = e.counts;
    d.seconds = e.seconds;
    return d;
  }
  double Absolute(const Eigen::VectorXd& x) override { return weights.Absolute(x); }

  PassWeights weights;
  LevelObjective<Scalar> level;
};

}  // namespace

Objective::Objective(const ScalarGrid& target, const RationalMap& map, const OptimizeOptions& options,
                     int resolution) {
  if (auto why = options.Validate(); !why.empty()) throw Error("objective: " + why);
  if (auto why = map.Validate(); !why.empty()) throw Error("objective: map: " + why);
  if (resolution < 0) throw Error("objective: the level's resolution must be >= 0 (0: the target's grid)");
  const std::string evaluator = ResolveEvaluator(options.evaluator, options.precision);
  impl_ = DispatchPrecision(options.precision, [&]<class Real>() -> std::unique_ptr<Impl> {
    return std::make_unique<ObjectiveIn<Real>>(target, map, options, resolution, evaluator);
  });
}

Objective::~Objective() = default;

int Objective::resolution() const { return impl_->resolution; }
const std::string& Objective::evaluator() const { return impl_->evaluator; }
void Objective::BeginPass(PassKind kind, const Eigen::VectorXd& start) { impl_->BeginPass(kind, start); }
Evaluation<double> Objective::Evaluate(const Eigen::VectorXd& x) { return impl_->Evaluate(x); }
double Objective::Absolute(const Eigen::VectorXd& x) { return impl_->Absolute(x); }

}  // namespace quijibo::optim
