// The alternative back end: Ceres Solver's line-search L-BFGS (unconstrained) on reparameterized
// variables, for comparison with the bound-constrained L-BFGS-B of lbfgsb.h. A variable with
// lower bound 0 is written x = y^2 (df/dy = 2 y df/dx); a free one (ln C) is used as is. The
// reparameterization keeps x >= 0 without a projection, but a variable that reaches 0 has a zero
// gradient in y and stays there: the known price of this approach. Double only (Ceres).
//
// Same contract as MinimizeBounded: the callback runs after every iteration with the value and the
// projected gradient norm in x (as L-BFGS-B measures it), the pass stops on that tolerance, an
// iteration cap or a line-search failure, and kRestartMemory restarts the solve from the current
// point (Ceres keeps its L-BFGS memory inside one Solve call).
#pragma once

#include <Eigen/Core>
#include <functional>

#include "optim/lbfgsb.h"

namespace quijibo::optim {

LbfgsbResult<double> MinimizeCeres(const BoundedObjective<double>& f, Eigen::VectorXd& x, const Eigen::VectorXd& lb,
                                   const LbfgsbOptions<double>& options, const LbfgsbCallback<double>& callback,
                                   int first_iteration = 0);

}  // namespace quijibo::optim
