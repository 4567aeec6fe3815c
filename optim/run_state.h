// The state of an optimization run that its observers read (optim/optimizer.cpp writes it): where
// the run is, the iterate, the best map so far and the passes done. Internal to optim/.
#pragma once

#include <Eigen/Core>
#include <chrono>

#include "optim/optimizer.h"

namespace quijibo::optim {

template <class Scalar>
struct RunState {
  using Vector = Eigen::Matrix<Scalar, -1, 1>;
  OptimizeSummary summary;  // the passes done, absolute_start, best_pass
  long long step = 0;       // iterations of the whole run
  Vector x;                 // all variables at the last pass end (or the start)
  Vector pass_start_x;      // where the pass in progress began
  Vector best_x;            // the map of the lowest absolute energy so far (see optimizer.h)
  double best_absolute = 0;
  // The pass in progress: its start energy and evaluations so far, so that a resumed pass
  // reports what the uninterrupted one does.
  double pass_energy_start = 0;
  int pass_evaluations = 0;
  // During a pass, the minimizer's iterate is the first `active` entries of *live.
  const Vector* live = nullptr;
  int active = 0;
  std::chrono::steady_clock::time_point t0 = std::chrono::steady_clock::now();
  double elapsed_before = 0;  // seconds of the run before a resume

  // x with the pass's iterate in place.
  Vector Current() const {
    Vector c = x;
    if (live) c.head(active) = live->head(active);
    return c;
  }
  double Elapsed() const {
    return elapsed_before + std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }
};

}  // namespace quijibo::optim
