// The reweighted pass's weight field (2015 paper §4.5 "Reweighting"; the reference code's rule,
// quijibo-code.md §5.2 item 6), on the finest grid:
//   outside the target (phi >= 0):                     W' = 0.5 / #outside    (flat, totals +0.5)
//   inside, outside the one-step Julia set (L >= 0):   W' = W * 0.25 / |sum|  (totals -0.25)
//   inside and inside the Julia set (L < 0):           W' = W * 0.25 / |sum|  (totals -0.25)
// so the optimizer spends half its inside effort on the poorly captured cells.
// The reference meshes the one-step set and runs an SDF generator on it, but its rule only reads
// the sign of that SDF at the cell centres, which is the sign of L = log|R(q_c)| there: we take
// it directly, exactly, at no cost. If one inside group is empty the other totals -0.5.
#pragma once

#include <vector>

#include "quijibo/grid.h"

namespace quijibo::optim {

struct ReweightCounts {
  long long outside = 0, poorly_captured = 0, well_captured = 0;
};

// sdf: the target (negative inside); weight: W on the same grid; log_modulus: L at each cell
// (NaN for cells left out, which keep weight 0 inside; only its sign is read, so +-infinity
// stands for a cell known to be saturated). Returns W'.
std::vector<double> ReweightedWeights(const ScalarGrid& sdf, const std::vector<double>& weight,
                                      const std::vector<double>& log_modulus,
                                      ReweightCounts* counts = nullptr);

}  // namespace quijibo::optim
