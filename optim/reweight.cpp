#include "optim/reweight.h"

#include <cmath>

#include "util/error.h"

namespace quijibo::optim {

std::vector<double> ReweightedWeights(const ScalarGrid& sdf, const std::vector<double>& weight,
                                      const std::vector<double>& log_modulus, ReweightCounts* counts) {
  const std::size_t n = sdf.values.size();
  if (weight.size() != n || log_modulus.size() != n) throw Error("reweighting: fields differ in size");
  ReweightCounts c;
  double poor = 0, well = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (sdf.values[i] >= 0) {
      ++c.outside;
    } else if (std::isnan(log_modulus[i])) {
      continue;
    } else if (log_modulus[i] >= 0) {
      ++c.poorly_captured;
      poor += std::abs(weight[i]);
    } else {
      ++c.well_captured;
      well += std::abs(weight[i]);
    }
  }
  if (c.outside == 0 || poor + well == 0) throw Error("reweighting: the target has no inside or no outside");
  const double poor_total = well == 0 ? 0.5 : (poor == 0 ? 0.0 : 0.25);
  const double well_total = poor == 0 ? 0.5 : (well == 0 ? 0.0 : 0.25);
  std::vector<double> w(n, 0.0);
  for (std::size_t i = 0; i < n; ++i) {
    if (sdf.values[i] >= 0) w[i] = 0.5 / double(c.outside);
    else if (std::isnan(log_modulus[i])) w[i] = 0.0;
    else if (log_modulus[i] >= 0) w[i] = -std::abs(weight[i]) * poor_total / poor;
    else w[i] = -std::abs(weight[i]) * well_total / well;
  }
  if (counts) *counts = c;
  return w;
}

}  // namespace quijibo::optim
