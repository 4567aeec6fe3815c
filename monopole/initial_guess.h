// From monopoles to the initial rational map (2015 paper §4.4 "Building the initial guess";
// the reference code's conventions, quijibo-code.md §3.4 and §5.2 item 2):
//   - a monopole of weight w > 0 becomes a top root with T_i = amplitude * w, one with w < 0 a
//     bottom root with B_i = amplitude * |w| (default 50; reference 3000, see below); weights are first put in
//     the normalized frame's units (divided by the fractal radius), as the reference fits there;
//   - optionally the reference's leading zero roots: a root at the origin with exponent 1 first in
//     top and in bottom (not amplified);
//   - tau = beta = 1, and ln C from the reference's one-dimensional scan: with C = 1, F = log|R|
//     on the scan grid (singular values replaced by the mean), minimize
//     sum -tanh(alpha (F - t)) Wu over t (100 samples over [min F, max F], then three refinements of
//     +-5 steps at a tenth of the step); ln C = -t*. Wu is the un-normalized layer weight
//     (-1/k inside, 0.25/k outside).
#pragma once

#include <vector>

#include "monopole/monopole_fit.h"
#include "quijibo/rational_map.h"
#include "util/settings.h"

namespace quijibo::monopole {

struct InitialGuessOptions {
  // The "initial bulk scalar amplitude". The reference runs 3000 (its cfg comments: 50 "reliable",
  // 2000 "best"); with our fit, 1000 and above leave L = log|R| so steep that tanh saturates in
  // nearly every cell and the F pass has no gradient to follow (measured in docs/benchmarks.md),
  // so the default is the reference's "reliable" 50.
  double amplitude = 50.0;
  bool leading_zero_roots = true;  // reference: on
  int scan_resolution = 25;        // grid of the ln C scan (reference: 25)
  static constexpr ValueRange kScanResolutionRange{4, 512};
  double alpha = 10.0;
  std::string Validate() const;
};

struct LnCScan {
  double ln_C = 0;
  double energy = 0;  // the scan's objective at the optimum (un-normalized weights)
  int singular_cells = 0;
};

// The initial map. `monopoles` in the fractal frame of `frame`; `sdf` the target on its grid.
RationalMap InitialMap(const std::vector<Monopole>& monopoles, const FractalFrame& frame,
                       const ScalarGrid& sdf, const InitialGuessOptions& options = {},
                       LnCScan* scan = nullptr);

// The reference's 1-D scan for ln C of `map` (its exponents, tau = beta = 1 as given).
LnCScan ScanLnC(const RationalMap& map, const ScalarGrid& sdf, int resolution, double alpha);

}  // namespace quijibo::monopole
