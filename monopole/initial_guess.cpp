#include "monopole/initial_guess.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "monopole/vec3_ops.h"
#include "util/error.h"
#include "quijibo/iou.h"
#include "quijibo/target.h"

namespace quijibo::monopole {

std::string InitialGuessOptions::Validate() const {
  if (!(amplitude > 0) || !std::isfinite(amplitude)) return "amplitude must be a positive number";
  if (auto why = CheckRange("scan_resolution", SettingType::kInteger, scan_resolution, kScanResolutionRange);
      !why.empty())
    return why;
  if (!(alpha > 0)) return "alpha must be > 0";
  if (auto why = CheckRange("hollow_roots", SettingType::kInteger, hollow_roots, kHollowRootsRange); !why.empty())
    return why;
  if (auto why = CheckRange("hollow_offset_cells", SettingType::kNumber, hollow_offset_cells, kHollowOffsetRange);
      !why.empty())
    return why;
  if (auto why = CheckRange("attract_roots", SettingType::kInteger, attract_roots, kAttractRootsRange); !why.empty())
    return why;
  if (auto why = CheckRange("attract_offset_cells", SettingType::kNumber, attract_offset_cells, kAttractOffsetRange);
      !why.empty())
    return why;
  return {};
}

namespace {

// Roots of exponent 0 at up to `count` points offset from `surface` along the SDF's normal by
// `offset_cells` cells (outward for bottom roots, inward for top roots; inward, halved up to twice
// while the point is not inside), kept where the shape and the start's set disagree there.
int AddOffsetRoots(RationalMap& map, const ScalarGrid& sdf, const std::vector<Vec3>& surface, int count,
                   double offset_cells, bool top) {
  using namespace monopole_detail;
  const double d = offset_cells * sdf.frame.spacing;
  const double sign = top ? -1.0 : 1.0;
  int added = 0;
  for (const Vec3& p : surface) {
    if (added >= count) break;
    const Vec3 n = Gradient(sdf, p);
    const double len = Norm(n);
    if (!(len > 0) || !std::isfinite(len)) continue;
    Vec3 q = Add(p, Scale(n, sign * d / len));
    for (int halving = 0; top && halving < 2 && !(sdf.sample(q) < 0); ++halving)
      q = Add(p, Scale(n, sign * d / len / double(2 << halving)));
    const bool shape_says = top ? sdf.sample(q) < 0 : sdf.sample(q) > 0;
    const double L = OneStepLogModulus(map, q);
    const bool set_disagrees = top ? L > 0 : L < 0;
    if (!shape_says || !set_disagrees) continue;
    auto& roots = top ? map.top_roots : map.bottom_roots;
    auto& exponents = top ? map.top_exponents : map.bottom_exponents;
    roots.push_back({q[0], q[1], q[2], 0.0});
    exponents.push_back(0.0);
    ++added;
  }
  return added;
}

}  // namespace

int AddHollowRoots(RationalMap& map, const ScalarGrid& sdf, const std::vector<Vec3>& surface,
                   const InitialGuessOptions& o) {
  if (auto why = o.Validate(); !why.empty()) throw Error("initial guess: " + why);
  return AddOffsetRoots(map, sdf, surface, o.hollow_roots, o.hollow_offset_cells, false);
}

int AddAttractRoots(RationalMap& map, const ScalarGrid& sdf, const std::vector<Vec3>& surface,
                    const InitialGuessOptions& o) {
  if (auto why = o.Validate(); !why.empty()) throw Error("initial guess: " + why);
  return AddOffsetRoots(map, sdf, surface, o.attract_roots, o.attract_offset_cells, true);
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

namespace {

// ScanLevelByIou on the field F sampled at the cells of `sdf`.
LnCScan LevelByIou(const std::vector<double>& F, const ScalarGrid& sdf, double alpha) {
  const std::int64_t n = sdf.frame.cell_count();
  LnCScan out;
  // Cells on a top root (F = -inf) are in every set; NaN cells (a top and a bottom root) in none.
  std::vector<std::int64_t> order;
  order.reserve(std::size_t(n));
  std::int64_t inside = 0;
  for (std::int64_t c = 0; c < n; ++c) {
    inside += sdf.values[std::size_t(c)] < 0;
    if (std::isnan(F[std::size_t(c)])) ++out.singular_cells;
    else order.push_back(c);
  }
  if (order.empty()) throw Error("start scan: the map is singular everywhere on the target grid");
  std::sort(order.begin(), order.end(), [&](std::int64_t a, std::int64_t b) { return F[std::size_t(a)] < F[std::size_t(b)]; });
  // The set {F < t} for t just above the k-th smallest F: its first k + 1 cells.
  std::int64_t both = 0, best_k = -1;
  double best_iou = -1;
  for (std::size_t k = 0; k < order.size(); ++k) {
    both += sdf.values[std::size_t(order[k])] < 0;
    if (k + 1 < order.size() && F[std::size_t(order[k + 1])] == F[std::size_t(order[k])]) continue;
    const double iou = IntersectionOverUnion(both, inside + std::int64_t(k + 1) - both);
    if (iou > best_iou) best_iou = iou, best_k = std::int64_t(k);
  }
  const double lo = F[std::size_t(order[std::size_t(best_k)])];
  const double hi = std::size_t(best_k + 1) < order.size() ? F[std::size_t(order[std::size_t(best_k + 1)])] : lo + 1.0;
  const double t = std::isfinite(lo) ? 0.5 * (lo + hi) : hi - 1.0;
  // The steepness: |alpha L| = 1 at the band's median (the band: within two cells of the surface).
  std::vector<double> band;
  const double h = sdf.frame.spacing;
  for (std::size_t c = 0; c < F.size(); ++c)
    if (std::abs(sdf.values[c]) <= 2 * h && std::isfinite(F[c])) band.push_back(std::abs(F[c] - t));
  double scale = 1;
  if (!band.empty()) {
    std::nth_element(band.begin(), band.begin() + std::ptrdiff_t(band.size() / 2), band.end());
    const double m = band[band.size() / 2];
    if (m > 0 && std::isfinite(m)) scale = 1.0 / (alpha * m);
  }
  out.iou = best_iou;
  out.steepness = scale;
  out.ln_C = -scale * t;
  return out;
}

// What one unit of the group's common exponent adds to L / tau (tau = beta) at the cells of `sdf`:
// log|q - t| summed over its top roots minus the sum over its bottom roots.
std::vector<double> GroupField(const RationalMap& map, const RootGroup& g, const ScalarGrid& sdf) {
  const std::int64_t n = sdf.frame.cell_count();
  std::vector<double> f(static_cast<std::size_t>(n), 0.0);
#pragma omp parallel for schedule(static)
  for (std::int64_t c = 0; c < n; ++c) {
    const Vec3 p = sdf.frame.cell_center(c);
    double s = 0;
    for (int i = g.top_begin; i < g.top_end; ++i) s += LogDistance(p, map.top_roots[std::size_t(i)]);
    for (int i = g.bottom_begin; i < g.bottom_end; ++i) s -= LogDistance(p, map.bottom_roots[std::size_t(i)]);
    f[std::size_t(c)] = s;
  }
  return f;
}

}  // namespace

LnCScan ScanLevelByIou(const RationalMap& map, const ScalarGrid& sdf, double alpha) {
  const std::int64_t n = sdf.frame.cell_count();
  std::vector<double> F(static_cast<std::size_t>(n));
#pragma omp parallel for schedule(static)
  for (std::int64_t c = 0; c < n; ++c) F[std::size_t(c)] = OneStepLogModulus(map, sdf.frame.cell_center(c));
  return LevelByIou(F, sdf, alpha);
}

OffsetExponentScan ScanOffsetExponents(RationalMap& map, const ScalarGrid& sdf, const RootGroup& hollow,
                                       const RootGroup& attract, double alpha) {
  if (!(map.tau > 0) || map.tau != map.beta) throw Error("offset exponent scan: the start must have tau = beta > 0");
  OffsetExponentScan out;
  out.hollow = hollow.size();
  out.attract = attract.size();
  const std::int64_t n = sdf.frame.cell_count();
  // The start's field in exponent units: F0 = L / tau (the offset roots are at exponent 0 in it).
  std::vector<double> F0(static_cast<std::size_t>(n));
#pragma omp parallel for schedule(static)
  for (std::int64_t c = 0; c < n; ++c) F0[std::size_t(c)] = OneStepLogModulus(map, sdf.frame.cell_center(c)) / map.tau;
  LnCScan best = LevelByIou(F0, sdf, alpha);
  out.iou_before = out.iou = best.iou;
  if (out.hollow == 0 && out.attract == 0) return out;
  // The scale of an exponent: the mean of the start's nonzero ones.
  double sum = 0;
  int count = 0;
  for (double e : map.top_exponents)
    if (e > 0) sum += e, ++count;
  for (double e : map.bottom_exponents)
    if (e > 0) sum += e, ++count;
  const double unit = count > 0 ? sum / count : 1.0;
  // Both groups' fields together: at one exponent the hollow (bottom) and attract (top) roots'
  // far fields, sums of logs of about the same distances with opposite signs, nearly cancel, so
  // the roots reshape the set near the surface and leave the monopoles' field elsewhere as it is.
  std::vector<double> G = GroupField(map, attract, sdf);
  const std::vector<double> H = GroupField(map, hollow, sdf);
  for (std::size_t c = 0; c < G.size(); ++c) G[c] += H[c];
  std::vector<double> F(F0.size());
  for (int k = -10; k <= 6; ++k) {
    const double e = unit * std::ldexp(1.0, k);
    for (std::size_t c = 0; c < F.size(); ++c) F[c] = F0[c] + e * G[c];
    const LnCScan s = LevelByIou(F, sdf, alpha);
    if (s.iou > best.iou) best = s, out.exponent = e;
  }
  out.iou = best.iou;
  for (const RootGroup* g : {&hollow, &attract}) {
    for (int i = g->top_begin; i < g->top_end; ++i) map.top_exponents[std::size_t(i)] = out.exponent;
    for (int i = g->bottom_begin; i < g->bottom_end; ++i) map.bottom_exponents[std::size_t(i)] = out.exponent;
  }
  // The scan's level t is of F, which holds ln C / tau: L = s (F - t) = s (sum ... + ln C / tau - t).
  const double ln_C_over_tau = map.ln_C / map.tau;
  map.tau = map.beta = best.steepness;
  map.ln_C = best.ln_C + best.steepness * ln_C_over_tau;
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
    if (w > 0 || (o.both_signs && w < 0)) {
      m.top_roots.push_back(root);
      m.top_exponents.push_back(std::max(w, 0.0));
    }
    if (w < 0 || (o.both_signs && w > 0)) {
      m.bottom_roots.push_back(root);
      m.bottom_exponents.push_back(std::max(-w, 0.0));
    }
  }
  if (o.scan == StartScan::kReference) {
    const LnCScan s = ScanLnC(m, sdf, o.scan_resolution, o.alpha);
    m.ln_C = s.ln_C;
    if (scan) *scan = s;
    return m;
  }
  // The reference's zero roots cancel only while tau = beta; the V and F passes move tau, beta and
  // their exponents apart, and as a pole the origin throws every orbit out (the n-step set of the
  // paper's bunny schedule was empty: docs/fidelity.md §12). So, as the log-kernel start does, the
  // origin is one top root, its exponent the smallest monopole's, part of the field the scan reads.
  RationalMap f = m;
  if (o.leading_zero_roots) {
    f.leading_zero_roots = false;
    f.top_roots.erase(f.top_roots.begin());
    f.top_exponents.erase(f.top_exponents.begin());
    f.bottom_roots.erase(f.bottom_roots.begin());
    f.bottom_exponents.erase(f.bottom_exponents.begin());
    double smallest = std::numeric_limits<double>::infinity();
    for (double e : f.top_exponents)
      if (e > 0) smallest = std::min(smallest, e);
    for (double e : f.bottom_exponents)
      if (e > 0) smallest = std::min(smallest, e);
    f.top_roots.insert(f.top_roots.begin(), Vec4{0, 0, 0, 0});
    f.top_exponents.insert(f.top_exponents.begin(), std::isfinite(smallest) ? smallest : 1.0);
  }
  const LnCScan s = ScanLevelByIou(f, sdf, o.alpha);
  // The steepness goes into tau and beta, not into the exponents: the same L, but the bottom
  // exponents (the twins and hollow roots at 0) then have the top ones' leverage. With beta left at
  // 1 the V pass scales tau alone (bottom exponents summing to 0 give s_B no gradient) and the F
  // pass moves the bottom roots tau / beta times slower: the tooth, demo schedule, 0.871 against
  // 0.937 (docs/benchmarks.md §22).
  m = f;
  m.tau = m.beta = s.steepness;
  m.ln_C = s.ln_C;
  if (scan) *scan = s;
  return m;
}

}  // namespace quijibo::monopole
