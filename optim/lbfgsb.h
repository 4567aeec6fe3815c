// Bound-constrained L-BFGS (L-BFGS-B), templated on the scalar type, built from LBFGSpp's pieces
// (Debian liblbfgspp-dev 0.1.0: BFGSMat, Cauchy point, subspace minimization) and our own
// Moré–Thuente line search (line_search.h: LBFGSpp 0.1.0's misplaces its bracket). We drive the
// iteration ourselves rather than call LBFGSBSolver::minimize because the optimizer needs what
// minimize does not give: a callback after every iteration (logs, checkpoints, interruption), the
// reason it stopped, and a recovery from line-search failures: as TAO's BLMVM in the reference
// code, the memory is reset and the step retried once along the projected gradient; a second
// failure, or a failure along the projected gradient already, ends the pass.
#pragma once

#include "quijibo/real.h"

#include <Eigen/Core>
#include <functional>
#include <stdexcept>
#include <string>

namespace quijibo::optim {

enum class StopReason { kTolerance, kLineSearch, kMaxIterations, kInterrupted, kNonFinite };
std::string StopReasonName(StopReason r);  // "tolerance", "line-search", ...

template <class Scalar>
struct LbfgsbOptions {
  int memory = 5;              // correction pairs (reference: lm = 5)
  int max_iterations = 2000;   // iteration cap (reference: 2000)
  Scalar tolerance = Scalar(1e-5);  // on the infinity norm of the projected gradient
  int max_linesearch = 30;     // evaluations per line search (reference: 30)
};

// After iteration `iteration` (1-based) with value f and projected gradient norm pg:
enum class IterationAction { kContinue, kStop, kRestartMemory };

template <class Scalar>
struct LbfgsbResult {
  StopReason stop = StopReason::kMaxIterations;
  int iterations = 0;
  int evaluations = 0;
  Scalar f = 0;
  Scalar projected_gradient = 0;
  std::string message;  // the line search's complaint when it stopped the pass
  int line_search_restarts = 0;  // failures recovered by resetting the memory
};

// The function to minimize: returns f(x) and writes its gradient.
template <class Scalar>
using BoundedObjective =
    std::function<Scalar(const Eigen::Matrix<Scalar, -1, 1>& x, Eigen::Matrix<Scalar, -1, 1>& gradient)>;
template <class Scalar>
using LbfgsbCallback =
    std::function<IterationAction(int iteration, int evaluations, const Scalar& f, const Scalar& pg)>;

// Minimizes f over lb <= x <= ub starting from x (projected onto the box first).
// `first_iteration` lets a resumed pass keep counting (the cap applies to the total).
// Defined in lbfgsb.cpp for float, double, long double and float128 only: LBFGSpp's templates are
// instantiated there once rather than in every file that minimizes something.
template <class Scalar>
LbfgsbResult<Scalar> MinimizeBounded(const BoundedObjective<Scalar>& f, Eigen::Matrix<Scalar, -1, 1>& x,
                                     const Eigen::Matrix<Scalar, -1, 1>& lb, const Eigen::Matrix<Scalar, -1, 1>& ub,
                                     const LbfgsbOptions<Scalar>& options, const LbfgsbCallback<Scalar>& callback,
                                     int first_iteration = 0);

#define QUIJIBO_LBFGSB_EXTERN(Scalar)                                                                      \
  extern template LbfgsbResult<Scalar> MinimizeBounded<Scalar>(                                            \
      const BoundedObjective<Scalar>&, Eigen::Matrix<Scalar, -1, 1>&, const Eigen::Matrix<Scalar, -1, 1>&, \
      const Eigen::Matrix<Scalar, -1, 1>&, const LbfgsbOptions<Scalar>&, const LbfgsbCallback<Scalar>&, int);
QUIJIBO_LBFGSB_EXTERN(float)
QUIJIBO_LBFGSB_EXTERN(double)
QUIJIBO_LBFGSB_EXTERN(long double)
QUIJIBO_LBFGSB_EXTERN(float128)
#undef QUIJIBO_LBFGSB_EXTERN

}  // namespace quijibo::optim
