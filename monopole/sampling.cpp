#include "monopole/sampling.h"

#include <algorithm>
#include <cmath>
#include <queue>
#include <random>
#include <unordered_map>

#include "monopole/vec3_ops.h"
#include "util/error.h"

namespace quijibo::monopole {

using namespace monopole_detail;

double UniformDouble(std::uint64_t bits) { return double(bits >> 11) * 0x1.0p-53; }

std::string SamplingOptions::Validate() const {
  if (count < 1) return "sampling.count must be positive, found " + std::to_string(count);
  if (count > 50000000)
    return "sampling.count must be at most 50000000, found " + std::to_string(count);
  if (!(oversampling >= 1.0) || !(oversampling <= 100.0))
    return "sampling.oversampling must be in [1, 100], found " + std::to_string(oversampling);
  return {};
}

std::vector<Vec3> PoissonDiskSample(const std::vector<Vec3>& vertices,
                                    const std::vector<std::array<int, 3>>& triangles,
                                    const SamplingOptions& options) {
  if (const std::string why = options.Validate(); !why.empty()) throw Error(why);
  if (triangles.empty()) throw Error("sampling: the mesh has no triangles");
  const int nt = int(triangles.size());
  std::vector<double> cumulative(nt);
  double total = 0.0;
  for (int t = 0; t < nt; ++t) {
    for (int v : triangles[t])
      if (v < 0 || v >= int(vertices.size()))
        throw Error("sampling: triangle " + std::to_string(t) + " refers to vertex " +
                    std::to_string(v) + ", but the mesh has " + std::to_string(vertices.size()) +
                    " vertices");
    const Vec3& a = vertices[triangles[t][0]];
    total += 0.5 * Norm(Cross(Sub(vertices[triangles[t][1]], a), Sub(vertices[triangles[t][2]], a)));
    cumulative[t] = total;
  }
  if (!(total > 0.0) || !std::isfinite(total))
    throw Error("sampling: the mesh has no area (or non-finite coordinates)");

  // 1. Uniform points, area-weighted triangle choice, uniform barycentrics (sqrt trick).
  const int n_out = options.count;
  const std::int64_t n_in = std::max<std::int64_t>(
      n_out, std::int64_t(std::llround(options.oversampling * n_out)));
  std::mt19937_64 rng(options.seed);
  std::vector<Vec3> pts(n_in);
  for (std::int64_t i = 0; i < n_in; ++i) {
    const double pick = UniformDouble(rng()) * total;
    const int t = int(std::min<std::ptrdiff_t>(
        std::upper_bound(cumulative.begin(), cumulative.end(), pick) - cumulative.begin(),
        nt - 1));
    const double r1 = std::sqrt(UniformDouble(rng())), r2 = UniformDouble(rng());
    const Vec3& a = vertices[triangles[t][0]];
    const Vec3& b = vertices[triangles[t][1]];
    const Vec3& c = vertices[triangles[t][2]];
    for (int k = 0; k < 3; ++k)
      pts[i][k] = (1.0 - r1) * a[k] + r1 * (1.0 - r2) * b[k] + r1 * r2 * c[k];
  }
  if (n_in == n_out) return pts;

  // 2. Neighbours within 2 r_max, through a hash grid of cell 2 r_max.
  const double r_max = std::sqrt(total / (2.0 * std::sqrt(3.0) * n_out));
  const double radius = 2.0 * r_max;
  // Yuksel's weight limiting: distances below r_min count as r_min (beta 0.65, gamma 1.5).
  const double r_min =
      radius * (1.0 - std::pow(double(n_out) / double(n_in), 1.5)) * 0.65;
  Vec3 lo = pts[0];
  for (const Vec3& p : pts)
    for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], p[a]);
  auto cell_of = [&](const Vec3& p, int a) { return std::int64_t((p[a] - lo[a]) / radius); };
  auto key_of = [](std::int64_t i, std::int64_t j, std::int64_t k) {
    return (i * (std::int64_t(1) << 21) + j) * (std::int64_t(1) << 21) + k;
  };
  std::vector<std::pair<std::int64_t, std::int64_t>> keyed(n_in);
  for (std::int64_t i = 0; i < n_in; ++i)
    keyed[i] = {key_of(cell_of(pts[i], 0), cell_of(pts[i], 1), cell_of(pts[i], 2)), i};
  std::sort(keyed.begin(), keyed.end());
  std::unordered_map<std::int64_t, std::pair<std::int64_t, std::int64_t>> cells;
  for (std::int64_t i = 0; i < n_in;) {
    std::int64_t j = i;
    while (j < n_in && keyed[j].first == keyed[i].first) ++j;
    cells[keyed[i].first] = {i, j};
    i = j;
  }
  // CSR neighbour lists with each pair's weight (1 - d / radius)^8.
  std::vector<std::vector<std::pair<int, float>>> nbr(n_in);
#pragma omp parallel for schedule(dynamic, 1024)
  for (std::int64_t i = 0; i < n_in; ++i) {
    const std::int64_t ci = cell_of(pts[i], 0), cj = cell_of(pts[i], 1), ck = cell_of(pts[i], 2);
    auto& list = nbr[i];
    for (std::int64_t di = -1; di <= 1; ++di)
      for (std::int64_t dj = -1; dj <= 1; ++dj)
        for (std::int64_t dk = -1; dk <= 1; ++dk) {
          if (ci + di < 0 || cj + dj < 0 || ck + dk < 0) continue;
          const auto it = cells.find(key_of(ci + di, cj + dj, ck + dk));
          if (it == cells.end()) continue;
          for (std::int64_t m = it->second.first; m < it->second.second; ++m) {
            const std::int64_t j = keyed[m].second;
            if (j == i) continue;
            const double d = Distance(pts[i], pts[j]);
            if (d >= radius) continue;
            const double u = 1.0 - std::max(d, r_min) / radius, u2 = u * u, u4 = u2 * u2;
            const double w = u4 * u4;  // (1 - d / radius)^8
            list.push_back({int(j), float(w)});
          }
        }
    std::sort(list.begin(), list.end(), [](auto& x, auto& y) { return x.first < y.first; });
  }

  // 3. Eliminate the most crowded point until n_out remain (lazy max-heap; ties -> larger index
  //    leaves first, a fixed rule).
  std::vector<double> weight(n_in, 0.0);
  for (std::int64_t i = 0; i < n_in; ++i)
    for (auto& [j, w] : nbr[i]) weight[i] += w;
  std::priority_queue<std::pair<double, std::int64_t>> heap;
  for (std::int64_t i = 0; i < n_in; ++i) heap.push({weight[i], i});
  std::vector<char> removed(n_in, 0);
  for (std::int64_t left = n_in; left > n_out;) {
    const auto [w, i] = heap.top();
    heap.pop();
    if (removed[i] || w != weight[i]) continue;  // stale entry
    removed[i] = 1;
    --left;
    for (auto& [j, wj] : nbr[i]) {
      if (removed[j]) continue;
      weight[j] -= wj;
      heap.push({weight[j], j});
    }
  }
  std::vector<Vec3> out;
  out.reserve(n_out);
  for (std::int64_t i = 0; i < n_in; ++i)
    if (!removed[i]) out.push_back(pts[i]);
  return out;
}

}  // namespace quijibo::monopole
