#include "quijibo/energy.h"

#include <algorithm>
#include <cmath>

namespace quijibo {

std::string EnergyOptions::Validate() const {
  return CheckRange("alpha", SettingType::kNumber, alpha, kAlphaRange);
}

std::vector<char> SingularCells(const RationalMap& map, const EnergyGrid& grid,
                                std::int64_t* count) {
  const std::int64_t n = grid.frame.cell_count();
  std::vector<char> singular(std::size_t(n), 0);
  std::int64_t total = 0;
  // A root can only coincide with the cell centres next to it: look at those, O(R).
  auto check = [&](const std::vector<Vec4>& roots) {
    for (const Vec4& r : roots) {
      if (r[3] != grid.slice) continue;
      int lo[3], hi[3];
      for (int a = 0; a < 3; ++a) {
        const double u = (r[a] - grid.frame.min_corner[a]) / grid.frame.spacing - 0.5;
        if (!(u > -1.0 && u < grid.frame.dims[a])) { lo[a] = 1; hi[a] = 0; continue; }
        lo[a] = std::max(0, int(std::floor(u)) - 1);
        hi[a] = std::min(grid.frame.dims[a] - 1, int(std::floor(u)) + 2);
      }
      for (int k = lo[2]; k <= hi[2]; ++k)
        for (int j = lo[1]; j <= hi[1]; ++j)
          for (int i = lo[0]; i <= hi[0]; ++i) {
            const Vec3 p = grid.frame.cell_center(i, j, k);
            const std::int64_t c = grid.frame.index(i, j, k);
            if (p[0] == r[0] && p[1] == r[1] && p[2] == r[2] && !singular[c]) {
              singular[c] = 1;
              ++total;
            }
          }
    }
  };
  check(map.top_roots);
  check(map.bottom_roots);
  if (count) *count = total;
  return singular;
}

double MedianLogModulus(const RationalMap& map, const EnergyGrid& grid) {
  const std::int64_t n = grid.frame.cell_count();
  std::vector<double> L(static_cast<std::size_t>(n));
  auto term = [&](const Vec4& r, const Vec3& p) { return LogDistance(p, r, grid.slice); };
#pragma omp parallel for schedule(static)
  for (std::int64_t c = 0; c < n; ++c) {
    const Vec3 p = grid.frame.cell_center(c);
    double s = 0;
    for (int i = 0; i < map.top_count(); ++i) s += map.tau * map.top_exponents[i] * term(map.top_roots[i], p);
    for (int i = 0; i < map.bottom_count(); ++i)
      s -= map.beta * map.bottom_exponents[i] * term(map.bottom_roots[i], p);
    L[c] = s;
  }
  std::erase_if(L, [](double v) { return !std::isfinite(v); });
  if (L.empty()) return 0.0;
  std::nth_element(L.begin(), L.begin() + L.size() / 2, L.end());
  return L[L.size() / 2];
}

double TrivialSetEnergy(std::initializer_list<const EnergyGrid*> grids) {
  double sum = 0, sum_abs = 0, eta = 0;
  for (const EnergyGrid* g : grids) {
    for (double w : g->weight) sum += w, sum_abs += std::abs(w);
    eta += g->eta;
  }
  // The halves-normalized fields sum to 0 up to rounding; leave them exactly as they were.
  if (!(eta > 0) || std::abs(sum) <= 1e-9 * sum_abs) return 0.0;
  return -std::abs(sum) / eta;
}

double EnergyOfField(const EnergyGrid& g, const std::vector<double>& L, double a) {
  double s = 0;
  for (std::size_t c = 0; c < L.size(); ++c)
    if (std::isfinite(L[c])) s += -std::tanh(a * L[c]) * g.weight[c];
  return s / g.eta - TrivialSetEnergy({&g});
}

}  // namespace quijibo
