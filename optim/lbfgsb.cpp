// The L-BFGS-B iteration of lbfgsb.h, instantiated for the four precisions.
#include "quijibo/real.h"

// LBFGSpp's headers call std::abs by qualified name; Boost's float128 only
// provides abs by argument-dependent lookup. This overload (declared before LBFGSpp is included)
// is what lets the optimizer run in float128.
namespace std {
inline quijibo::float128 abs(const quijibo::float128& x) { return boost::multiprecision::abs(x); }
}  // namespace std

#include <LBFGSB.h>

#include "optim/lbfgsb.h"
#include "optim/line_search.h"

namespace quijibo::optim {

std::string StopReasonName(StopReason r) {
  switch (r) {
    case StopReason::kTolerance: return "tolerance";
    case StopReason::kLineSearch: return "line-search";
    case StopReason::kMaxIterations: return "max-iterations";
    case StopReason::kInterrupted: return "interrupted";
    case StopReason::kNonFinite: return "non-finite";
  }
  return "?";
}

template <class Scalar>
LbfgsbResult<Scalar> MinimizeBounded(const BoundedObjective<Scalar>& f, Eigen::Matrix<Scalar, -1, 1>& x,
                                     const Eigen::Matrix<Scalar, -1, 1>& lb, const Eigen::Matrix<Scalar, -1, 1>& ub,
                                     const LbfgsbOptions<Scalar>& options, const LbfgsbCallback<Scalar>& callback,
                                     int first_iteration) {
  using Vector = Eigen::Matrix<Scalar, -1, 1>;
  using std::isfinite;
  const int n = int(x.size());
  LBFGSpp::LBFGSBParam<Scalar> param;
  param.m = options.memory;
  param.max_linesearch = options.max_linesearch;
  param.epsilon = options.tolerance;
  param.epsilon_rel = Scalar(0);
  LineSearchOptions<Scalar> line_search;
  line_search.ftol = param.ftol;
  line_search.gtol = param.wolfe;
  line_search.min_step = param.min_step;
  line_search.max_evaluations = options.max_linesearch;

  LbfgsbResult<Scalar> result;
  int evaluations = 0;
  auto counted = [&](const Vector& y, Vector& g) {
    ++evaluations;
    return f(y, g);
  };
  auto project = [&](Vector& y) { y = y.cwiseMax(lb).cwiseMin(ub); };
  auto projected_norm = [&](const Vector& y, const Vector& g) {
    return ((y - g).cwiseMax(lb).cwiseMin(ub) - y).cwiseAbs().maxCoeff();
  };
  auto finite = [](const Scalar& v) { return v == v && v - v == Scalar(0); };
  auto max_step = [&](const Vector& x0, const Vector& d) {
    Scalar step = std::numeric_limits<Scalar>::infinity();
    for (int i = 0; i < n; ++i) {
      if (d[i] > Scalar(0)) step = std::min(step, Scalar((ub[i] - x0[i]) / d[i]));
      else if (d[i] < Scalar(0)) step = std::min(step, Scalar((lb[i] - x0[i]) / d[i]));
    }
    return step;
  };

  project(x);
  LBFGSpp::BFGSMat<Scalar, true> bfgs;
  bfgs.reset(n, options.memory);
  Vector grad(n), xp(n), gradp(n), drt(n), xcp(n), vecc, s(n), y(n);
  std::vector<int> newact, fv;
  Scalar fx = counted(x, grad);
  Scalar pg = projected_norm(x, grad);
  auto finish = [&](StopReason why) {
    result.stop = why;
    result.evaluations = evaluations;
    result.f = fx;
    result.projected_gradient = pg;
    return result;
  };
  result.iterations = first_iteration;
  if (!finite(fx) || !grad.allFinite()) return finish(StopReason::kNonFinite);
  if (pg <= options.tolerance) return finish(StopReason::kTolerance);
  if (first_iteration >= options.max_iterations) return finish(StopReason::kMaxIterations);

  // The direction from the generalized Cauchy point and the subspace minimization.
  bool fresh = true;  // the direction is the projected steepest descent of an empty memory
  auto direction = [&](bool first) {
    fresh = first;
    LBFGSpp::Cauchy<Scalar>::get_cauchy_point(bfgs, x, grad, lb, ub, xcp, vecc, newact, fv);
    if (first) {
      drt = xcp - x;
      drt.normalize();
    } else {
      LBFGSpp::SubspaceMin<Scalar>::subspace_minimize(bfgs, x, xcp, grad, lb, ub, vecc, newact, fv,
                                                      param.max_submin, drt);
    }
  };
  direction(true);
  const Scalar eps = std::numeric_limits<Scalar>::epsilon();
  bool retried = false;
  for (;;) {
    xp = x;
    gradp = grad;
    const Scalar fp = fx;
    Scalar step_max = std::min(param.max_step, max_step(x, drt));
    Scalar step = std::min(Scalar(1), step_max);
    try {
      MoreThuente(counted, fx, x, grad, step, step_max, drt, xp, line_search);
    } catch (const std::exception& e) {
      // The line search found no decrease: restore the point and retry once from an empty memory.
      // From a direction that already came from an empty memory the retry would repeat the same
      // trials, so the pass ends at once.
      x = xp;
      grad = gradp;
      fx = fp;
      result.message = e.what();
      if (retried || fresh) return finish(StopReason::kLineSearch);
      retried = true;
      ++result.line_search_restarts;
      bfgs.reset(n, options.memory);
      direction(true);
      continue;
    }
    retried = false;
    result.message.clear();  // recovered: only a failure that stops the pass is reported
    ++result.iterations;
    pg = projected_norm(x, grad);
    if (!finite(fx) || !grad.allFinite()) return finish(StopReason::kNonFinite);
    const IterationAction action = callback(result.iterations, evaluations, fx, pg);
    if (action == IterationAction::kStop) return finish(StopReason::kInterrupted);
    if (pg <= options.tolerance) return finish(StopReason::kTolerance);
    if (result.iterations >= options.max_iterations) return finish(StopReason::kMaxIterations);
    s = x - xp;
    y = grad - gradp;
    bool fresh = false;
    if (action == IterationAction::kRestartMemory) {
      bfgs.reset(n, options.memory);
      fresh = true;
    } else if (s.dot(y) > eps * y.squaredNorm()) {
      bfgs.add_correction(s, y);
    }
    project(x);
    direction(fresh);
  }
}

#define QUIJIBO_LBFGSB_INSTANTIATE(Scalar)                                                                 \
  template LbfgsbResult<Scalar> MinimizeBounded<Scalar>(                                                   \
      const BoundedObjective<Scalar>&, Eigen::Matrix<Scalar, -1, 1>&, const Eigen::Matrix<Scalar, -1, 1>&, \
      const Eigen::Matrix<Scalar, -1, 1>&, const LbfgsbOptions<Scalar>&, const LbfgsbCallback<Scalar>&, int);
QUIJIBO_LBFGSB_INSTANTIATE(float)
QUIJIBO_LBFGSB_INSTANTIATE(double)
QUIJIBO_LBFGSB_INSTANTIATE(long double)
QUIJIBO_LBFGSB_INSTANTIATE(float128)

}  // namespace quijibo::optim
