#include "monopole/initial_guess.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "util/error.h"
#include "quijibo/target.h"

namespace quijibo::monopole {

std::string InitialGuessOptions::Validate() const {
  if (!(amplitude > 0) || !std::isfinite(amplitude)) return "amplitude must be a positive number";
  if (auto why = CheckRange("scan_resolution", SettingType::kInteger, scan_resolution, kScanResolutionRange);
      !why.empty())
    return why;
  if (!(alpha > 0)) return "alpha must be > 0";
  return {};
}

LnCScan ScanLnC(const RationalMap& map, const ScalarGrid& sdf, int resolution, double alpha) {
  // The reference's un-normalized layer weights: -1/k inside, 0.25/k outside.
  const std::vector<int> layer = LayerIndex(sdf);
  std::vector<double> w(layer.size());
  for (std::size_t c = 0; c < w.size(); ++c) w[c] = (sdf.values[c] < 0 ? -1.0 : 0.25) / layer[c];
  const EnergyGrid grid = MakeEnergyGrid(sdf, w, WeightField::kLayer, resolution, LevelWeights::kSampleFinest, 0.0);
  const std::int64_t n = grid.frame.cell_count();
  std::vector<double> F(static_cast<std::size_t>(n));
  LnCScan out;
  auto log_dist = [&](const Vec4& r, const Vec3& p) { return LogDistance(p, r); };
  double sum = 0;
  std::int64_t finite = 0;
  for (std::int64_t c = 0; c < n; ++c) {
    const Vec3 p = grid.frame.cell_center(c);
    double s = 0;
    for (int i = 0; i < map.top_count(); ++i) s += map.top_exponents[i] * log_dist(map.top_roots[i], p);
    for (int i = 0; i < map.bottom_count(); ++i) s -= map.bottom_exponents[i] * log_dist(map.bottom_roots[i], p);
    F[c] = s;
    if (std::isfinite(s)) sum += s, ++finite;
  }
  if (finite == 0) throw Error("ln C scan: the map is singular everywhere on the scan grid");
  const double mean = sum / double(finite);
  for (double& v : F)
    if (!std::isfinite(v)) v = mean, ++out.singular_cells;
  auto objective = [&](double t) {
    double e = 0;
    for (std::int64_t c = 0; c < n; ++c) e -= std::tanh(alpha * (F[c] - t)) * grid.weight[c];
    return e;
  };
  double lo = *std::min_element(F.begin(), F.end()), hi = *std::max_element(F.begin(), F.end());
  double step = (hi - lo) / 100.0;
  double best = lo, best_e = objective(lo);
  for (int k = 1; k <= 100; ++k) {
    const double t = lo + k * step;
    const double e = objective(t);
    if (e < best_e) best = t, best_e = e;
  }
  for (int refine = 0; refine < 3; ++refine) {
    const double center = best;
    const double fine = step / 10.0;
    for (int k = -50; k <= 50; ++k) {
      const double t = center + k * fine;
      const double e = objective(t);
      if (e < best_e) best = t, best_e = e;
    }
    step = fine;
  }
  out.ln_C = -best;
  out.energy = best_e;
  return out;
}

RationalMap InitialMap(const std::vector<Monopole>& monopoles, const FractalFrame& frame, const ScalarGrid& sdf,
                       const InitialGuessOptions& o, LnCScan* scan) {
  if (auto why = o.Validate(); !why.empty()) throw Error("initial guess: " + why);
  if (monopoles.empty()) throw Error("initial guess: no monopoles");
  RationalMap m;
  m.frame = frame;
  m.leading_zero_roots = o.leading_zero_roots;
  if (o.leading_zero_roots) {
    m.top_roots.push_back({0, 0, 0, 0});
    m.top_exponents.push_back(1.0);
    m.bottom_roots.push_back({0, 0, 0, 0});
    m.bottom_exponents.push_back(1.0);
  }
  for (const Monopole& p : monopoles) {
    const double w = p.weight / frame.fractal_radius * o.amplitude;
    const Vec4 root{p.position[0], p.position[1], p.position[2], 0.0};
    if (w > 0) {
      m.top_roots.push_back(root);
      m.top_exponents.push_back(w);
    } else if (w < 0) {
      m.bottom_roots.push_back(root);
      m.bottom_exponents.push_back(-w);
    }
  }
  const LnCScan s = ScanLnC(m, sdf, o.scan_resolution, o.alpha);
  m.ln_C = s.ln_C;
  if (scan) *scan = s;
  return m;
}

}  // namespace quijibo::monopole
