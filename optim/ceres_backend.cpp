#include "optim/ceres_backend.h"

#include <ceres/ceres.h>

#include <cmath>

namespace quijibo::optim {

namespace {

using Vec = Eigen::VectorXd;

struct Reparameterized {
  const Vec& lb;
  bool bounded(int i) const { return lb[i] == 0.0; }
  Vec to_x(const double* y, int n) const {
    Vec x(n);
    for (int i = 0; i < n; ++i) x[i] = bounded(i) ? y[i] * y[i] : y[i];
    return x;
  }
};

class Function : public ceres::FirstOrderFunction {
 public:
  Function(const std::function<double(const Vec&, Vec&)>& f, const Reparameterized& r, int n, int& evaluations,
           Vec& last_x, Vec& last_g, double& last_f)
      : f_(f), r_(r), n_(n), evaluations_(evaluations), last_x_(last_x), last_g_(last_g), last_f_(last_f) {}
  bool Evaluate(const double* y, double* cost, double* gradient) const override {
    const Vec x = r_.to_x(y, n_);
    Vec g(n_);
    const double fx = f_(x, g);
    ++evaluations_;
    if (!std::isfinite(fx) || !g.allFinite()) return false;
    *cost = fx;
    last_x_ = x;
    last_g_ = g;
    last_f_ = fx;
    if (gradient)
      for (int i = 0; i < n_; ++i) gradient[i] = r_.bounded(i) ? 2.0 * y[i] * g[i] : g[i];
    return true;
  }
  int NumParameters() const override { return n_; }

 private:
  const std::function<double(const Vec&, Vec&)>& f_;
  const Reparameterized& r_;
  int n_;
  int& evaluations_;
  Vec& last_x_;
  Vec& last_g_;
  double& last_f_;
};

}  // namespace

LbfgsbResult<double> MinimizeCeres(const BoundedObjective<double>& f, Vec& x, const Vec& lb,
                                   const LbfgsbOptions<double>& options, const LbfgsbCallback<double>& callback,
                                   int first_iteration) {
  const int n = int(x.size());
  Reparameterized rep{lb};
  x = x.cwiseMax(lb);
  auto projected = [&](const Vec& xs, const Vec& g) { return ((xs - g).cwiseMax(lb) - xs).cwiseAbs().maxCoeff(); };
  LbfgsbResult<double> result;
  result.iterations = first_iteration;
  int evaluations = 0;
  Vec last_x = x, last_g(n);
  double last_f = 0;
  {
    Vec g(n);
    last_f = f(x, g);
    ++evaluations;
    last_g = g;
    result.f = last_f;
    result.projected_gradient = projected(x, g);
    if (!std::isfinite(last_f) || !g.allFinite()) {
      result.stop = StopReason::kNonFinite;
      result.evaluations = evaluations;
      return result;
    }
    if (result.projected_gradient <= options.tolerance || first_iteration >= options.max_iterations) {
      result.stop = result.projected_gradient <= options.tolerance ? StopReason::kTolerance : StopReason::kMaxIterations;
      result.evaluations = evaluations;
      return result;
    }
  }
  // Each Solve runs until our test stops it or asks for a memory restart.
  for (;;) {
    std::vector<double> y(n);
    for (int i = 0; i < n; ++i) y[i] = rep.bounded(i) ? std::sqrt(std::max(x[i], 0.0)) : x[i];
    enum class Why { kNone, kStop, kTolerance, kCap, kRestart } why = Why::kNone;
    struct Callback : ceres::IterationCallback {
      std::function<ceres::CallbackReturnType(const ceres::IterationSummary&)> fn;
      ceres::CallbackReturnType operator()(const ceres::IterationSummary& s) override { return fn(s); }
    } cb;
    cb.fn = [&](const ceres::IterationSummary& s) {
      if (s.iteration == 0 || !s.step_is_successful) return ceres::SOLVER_CONTINUE;
      ++result.iterations;
      // The parameters hold the new point (update_state_every_iteration); the last evaluation
      // may have been a trial, so evaluate the accepted point's x from y.
      const Vec xs = rep.to_x(y.data(), n);
      Vec g = last_g;
      double fx = last_f;
      if (xs != last_x) {  // the last evaluation was a rejected trial
        fx = f(xs, g);
        ++evaluations;
      }
      x = xs;
      result.f = fx;
      result.projected_gradient = projected(xs, g);
      const IterationAction a = callback(result.iterations, evaluations, fx, result.projected_gradient);
      if (a == IterationAction::kStop) return why = Why::kStop, ceres::SOLVER_TERMINATE_SUCCESSFULLY;
      if (result.projected_gradient <= options.tolerance) return why = Why::kTolerance, ceres::SOLVER_TERMINATE_SUCCESSFULLY;
      if (result.iterations >= options.max_iterations) return why = Why::kCap, ceres::SOLVER_TERMINATE_SUCCESSFULLY;
      if (a == IterationAction::kRestartMemory) return why = Why::kRestart, ceres::SOLVER_TERMINATE_SUCCESSFULLY;
      return ceres::SOLVER_CONTINUE;
    };
    ceres::GradientProblemSolver::Options so;
    so.line_search_direction_type = ceres::LBFGS;
    so.max_lbfgs_rank = options.memory;
    so.max_num_iterations = 1000000;
    so.function_tolerance = 0;
    so.gradient_tolerance = 0;
    so.parameter_tolerance = 0;
    so.logging_type = ceres::SILENT;
    so.update_state_every_iteration = true;
    so.callbacks.push_back(&cb);
    ceres::GradientProblem problem(new Function(f, rep, n, evaluations, last_x, last_g, last_f));
    ceres::GradientProblemSolver::Summary summary;
    ceres::Solve(so, problem, y.data(), &summary);
    result.evaluations = evaluations;
    switch (why) {
      case Why::kRestart: continue;
      case Why::kStop: result.stop = StopReason::kInterrupted; return result;
      case Why::kTolerance: result.stop = StopReason::kTolerance; return result;
      case Why::kCap: result.stop = StopReason::kMaxIterations; return result;
      case Why::kNone: break;
    }
    // Ceres stopped on its own: a line-search failure or a numerical problem.
    result.stop = summary.termination_type == ceres::FAILURE ? StopReason::kLineSearch : StopReason::kTolerance;
    result.message = summary.message;
    return result;
  }
}

}  // namespace quijibo::optim
