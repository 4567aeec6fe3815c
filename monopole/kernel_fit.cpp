#include "monopole/kernel_fit.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <unordered_map>
#include <utility>

#include <Eigen/Dense>

#include "monopole/sampling.h"
#include "monopole/vec3_ops.h"
#include "util/error.h"
#include "quijibo/energy.h"
#include "quijibo/iou.h"

namespace quijibo::monopole {

std::string KernelFitOptions::Validate() const {
  if (roots < 8 || roots > 4000) return "roots must be in [8, 4000]";
  if (max_roots < 8 || max_roots > 4000) return "max roots must be in [8, 4000]";
  if (!(spacing >= 1 && spacing <= 100)) return "root spacing must be in [1, 100] pair sizes";
  if (!(offset_cells > 0) || offset_cells > 50) return "offset must be in (0, 50] cells";
  if (!(band_cells > 0) || band_cells > 50) return "band must be in (0, 50] cells";
  if (!(amplitude > 0) || amplitude > 100) return "amplitude must be in (0, 100]";
  if (!(ridge >= 0) || ridge > 1) return "ridge must be in [0, 1]";
  if (max_band_rows < 1000) return "max band rows must be >= 1000";
  if (coarse_stride < 1 || coarse_stride > 16) return "coarse stride must be in [1, 16]";
  if (active_set_iterations < 1 || active_set_iterations > 50) return "active-set iterations must be in [1, 50]";
  if (refine_rounds < 0 || refine_rounds > 10) return "refine rounds must be in [0, 10]";
  if (!(refine_above >= 0 && refine_above <= 1)) return "refine threshold must be in [0, 1]";
  return {};
}

namespace {

using monopole_detail::Gradient;

// Points spread evenly on a sphere (Fibonacci lattice).
std::vector<Vec3> SpherePoints(const Vec3& c, double radius, int count) {
  std::vector<Vec3> p;
  const double golden = M_PI * (3.0 - std::sqrt(5.0));
  for (int k = 0; k < count; ++k) {
    const double z = 1.0 - 2.0 * (k + 0.5) / count, r = std::sqrt(1 - z * z), t = golden * k;
    p.push_back({c[0] + radius * r * std::cos(t), c[1] + radius * r * std::sin(t), c[2] + radius * z});
  }
  return p;
}

// A surface point p with one root `offset` inside and one outside along its normal, each offset
// shortened until the root is still about as far from the surface as it was moved: past the
// medial axis (the middle of a thin wall, a narrow gap) it would sit nearer the other side.
struct RootPair {
  Vec3 p;
  Vec4 inside, outside;
  double size = 0;  // the shorter of the two offsets: the width of the bump the pair can shape
};

// Sizes below a cell describe detail the target grid cannot show (at a sharp edge the offsets
// shorten to almost nothing); they would crowd pairs onto the edges.
constexpr double kMinSizeCells = 1.0;

bool MakePair(const ScalarGrid& sdf, const Vec3& p, double offset, RootPair& out) {
  Vec3 n = Gradient(sdf, p);
  const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  if (!(len > 1e-12)) return false;
  for (double& c : n) c /= len;
  out.p = p;
  out.size = offset;
  for (int side : {-1, 1}) {
    double d = offset;
    Vec3 q;
    for (int k = 0; k < 12; ++k) {
      q = {p[0] + side * d * n[0], p[1] + side * d * n[1], p[2] + side * d * n[2]};
      if (side * sdf.sample(q) > 0.6 * d) break;
      d *= 0.75;
    }
    (side < 0 ? out.inside : out.outside) = {q[0], q[1], q[2], 0.0};
    out.size = std::min(out.size, d);
  }
  out.size = std::max(out.size, std::min(offset, kMinSizeCells * sdf.frame.spacing));
  return true;
}

// Many blue-noise surface points with their pairs, in a seeded random order: the candidates
// SpacePairs chooses from.
std::vector<RootPair> CandidatePairs(const std::vector<Vec3>& vertices, const std::vector<std::array<int, 3>>& triangles,
                                     const ScalarGrid& sdf, const KernelFitOptions& o) {
  SamplingOptions so;
  so.count = std::clamp(8 * std::max(o.roots, o.max_roots), 2000, 40000);
  so.seed = o.seed;
  const std::vector<Vec3> p = PoissonDiskSample(vertices, triangles, so);
  std::vector<RootPair> pairs(p.size());
  std::vector<char> ok(p.size());
  const double offset = o.offset_cells * sdf.frame.spacing;
#pragma omp parallel for schedule(static)
  for (std::size_t k = 0; k < p.size(); ++k) ok[k] = MakePair(sdf, p[k], offset, pairs[k]);
  std::vector<RootPair> kept;
  for (std::size_t k = 0; k < p.size(); ++k)
    if (ok[k]) kept.push_back(pairs[k]);
  return kept;
}

// Greedy dart throwing in the candidates' order with a radius proportional to each pair's size:
// r_k = r0 * size_k / size_max; two pairs conflict when nearer than the mean of their radii.
std::vector<int> ThrowDarts(const std::vector<RootPair>& pairs, double r0, double size_max) {
  std::unordered_map<std::int64_t, std::vector<int>> hash;
  auto key = [&](std::int64_t i, std::int64_t j, std::int64_t k) { return (i * 73856093) ^ (j * 19349663) ^ (k * 83492791); };
  std::vector<int> chosen;
  for (int c = 0; c < int(pairs.size()); ++c) {
    const Vec3& p = pairs[c].p;
    const double rc = r0 * pairs[c].size / size_max;
    const std::int64_t ci = std::int64_t(std::floor(p[0] / r0)), cj = std::int64_t(std::floor(p[1] / r0)),
                       ck = std::int64_t(std::floor(p[2] / r0));
    bool free = true;
    for (std::int64_t i = ci - 1; i <= ci + 1 && free; ++i)
      for (std::int64_t j = cj - 1; j <= cj + 1 && free; ++j)
        for (std::int64_t k = ck - 1; k <= ck + 1 && free; ++k) {
          auto it = hash.find(key(i, j, k));
          if (it == hash.end()) continue;
          for (int o : it->second) {
            const Vec3& q = pairs[o].p;
            const double r = 0.5 * (rc + r0 * pairs[o].size / size_max);
            if ((p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) + (p[2] - q[2]) * (p[2] - q[2]) < r * r) {
              free = false;
              break;
            }
          }
        }
    if (!free) continue;
    chosen.push_back(c);
    hash[key(ci, cj, ck)].push_back(c);
  }
  return chosen;
}

// Chooses the root pairs: spaced at most `spacing` times their size apart (the sampling rule),
// which sets their number, kept within [roots, max_roots] / 2 by scaling the spacing. Returns the
// chosen candidates and the spacing ratio used.
std::pair<std::vector<int>, double> SpacePairs(const std::vector<RootPair>& pairs, const KernelFitOptions& o, double h) {
  const double size_max = o.offset_cells * h;
  const int lo = o.roots / 2, hi = std::max(o.roots, o.max_roots) / 2;
  double ratio = o.spacing;
  std::vector<int> chosen = ThrowDarts(pairs, ratio * size_max, size_max);
  const int n = int(chosen.size());
  if (n >= lo && n <= hi) return {chosen, ratio};
  // Bisect the ratio (the count falls as it grows) for the smallest count >= the bound, then
  // drop the last-thrown extras.
  const int target = std::clamp(n, lo, hi);
  double small = ratio, large = ratio;
  if (n > hi)
    while (int(ThrowDarts(pairs, large * size_max, size_max).size()) > hi && large < 1e3) large *= 2;
  else
    while (int(ThrowDarts(pairs, small * size_max, size_max).size()) < lo && small > 1e-3) small /= 2;
  for (int it = 0; it < 30; ++it) {
    const double mid = std::sqrt(small * large);
    (int(ThrowDarts(pairs, mid * size_max, size_max).size()) >= target ? small : large) = mid;
  }
  chosen = ThrowDarts(pairs, small * size_max, size_max);
  if (int(chosen.size()) > target) chosen.resize(target);
  return {chosen, small};
}

// The root positions and the surface points that have them.
struct FitRoots {
  std::vector<Vec4> roots;
  std::vector<Vec3> points;
  void Add(const RootPair& pair) {
    points.push_back(pair.p);
    roots.push_back(pair.inside), roots.push_back(pair.outside);
  }
};

// A row of the least-squares fit: L at x should follow the clamped signed distance phi (two-sided
// rows, the inner band) or only lie beyond the band's amplitude on phi's side (one-sided rows).
struct FitRow {
  Vec3 x;
  double phi, weight;
  bool two_sided;
};

struct FitRows {
  std::vector<FitRow> rows;  // the band's, then the coarse lattice's, then the far spheres'
  int band = 0, far = 0;     // how many band and far rows
};

// The rows: the band (|phi| <= 2 delta) at full resolution, a coarse lattice beyond it, and two
// far spheres; inside and outside carry equal total weight, as the energy's normalization gives them.
FitRows MakeFitRows(const ScalarGrid& sdf, const KernelFitOptions& o) {
  const double h = sdf.frame.spacing, delta = o.band_cells * h;
  FitRows out;
  std::vector<FitRow>& rows = out.rows;
  const auto& d = sdf.frame.dims;
  std::vector<std::int64_t> band;
  for (std::int64_t c = 0; c < sdf.frame.cell_count(); ++c)
    if (std::abs(sdf.values[c]) <= 2 * delta) band.push_back(c);
  const double band_stride = std::max(1.0, double(band.size()) / o.max_band_rows);
  for (double f = 0; f < double(band.size()); f += band_stride) {
    const std::int64_t c = band[std::size_t(f)];
    const double phi = sdf.values[c];
    rows.push_back({sdf.frame.cell_center(c), phi, band_stride / std::max(h, std::abs(phi)), std::abs(phi) < delta});
  }
  out.band = int(rows.size());
  const int st = o.coarse_stride;
  const double coarse_volume = double(st) * st * st;
  double outside_coarse_weight = 0;
  int outside_coarse = 0;
  for (int k = st / 2; k < d[2]; k += st)
    for (int j = st / 2; j < d[1]; j += st)
      for (int i = st / 2; i < d[0]; i += st) {
        const double phi = sdf.at(i, j, k);
        if (std::abs(phi) <= 2 * delta) continue;
        const double w = coarse_volume / std::abs(phi);
        rows.push_back({sdf.frame.cell_center(i, j, k), phi, w, false});
        if (phi > 0) outside_coarse_weight += w, ++outside_coarse;
      }
  const Vec3 ext = sdf.frame.extent();
  const Vec3 center{sdf.frame.min_corner[0] + ext[0] / 2, sdf.frame.min_corner[1] + ext[1] / 2,
                    sdf.frame.min_corner[2] + ext[2] / 2};
  const double half_diagonal = 0.5 * std::sqrt(ext[0] * ext[0] + ext[1] * ext[1] + ext[2] * ext[2]);
  const double far_weight = outside_coarse ? outside_coarse_weight / outside_coarse : 1.0 / h;
  for (double radius : {1.1 * half_diagonal, 3.0 * half_diagonal})
    for (const Vec3& x : SpherePoints(center, radius, 256)) rows.push_back({x, radius, far_weight, false}), ++out.far;
  double w_in = 0, w_out = 0;
  for (const FitRow& r : rows) (r.phi < 0 ? w_in : w_out) += r.weight;
  if (!(w_in > 0)) throw Error("log-kernel fit: the target has no inside cells");
  for (FitRow& r : rows)
    if (r.phi < 0) r.weight *= w_out / w_in;
  return out;
}

// One round's fit: e (ln C, then one exponent per root), L at the rows, the rows' goals g and
// weights w (0 for a row on a root).
struct FitSolution {
  Eigen::VectorXd e, L, g, w;
  int iterations = 0;  // active-set iterations
};

// Weighted least squares of L = ln C + sum e_i log|x - root_i| (+ log|x| with the origin root)
// against the goals, by an active set: one-sided rows leave while satisfied and come back when
// violated; the normal matrix is updated by rank updates as rows move.
FitSolution SolveExponents(const FitRows& fit_rows, const std::vector<Vec4>& roots, const KernelFitOptions& o,
                           double delta) {
  const std::vector<FitRow>& rows = fit_rows.rows;
  const int M = int(rows.size()), R = int(roots.size()), cols = R + 1;
  const double s = o.amplitude;
  FitSolution out;
  Eigen::VectorXd& g = out.g;
  Eigen::VectorXd& w = out.w;
  Eigen::VectorXd fixed(M);
  g.resize(M), w.resize(M);
  // The design matrix: a column of ones (ln C) and the log-distances to every root.
  Eigen::MatrixXd A(M, cols);
#pragma omp parallel for schedule(static)
  for (int r = 0; r < M; ++r) {
    A(r, 0) = 1.0;
    for (int i = 0; i < R; ++i) A(r, i + 1) = LogDistance(rows[r].x, roots[i], 0.0);
    g[r] = s * std::clamp(rows[r].phi / delta, -1.0, 1.0);
    fixed[r] = o.origin_root ? LogDistance(rows[r].x, Vec4{0, 0, 0, 0}) : 0.0;
    w[r] = rows[r].weight;
  }
  for (int r = 0; r < M; ++r)
    if (!A.row(r).allFinite() || !std::isfinite(fixed[r])) w[r] = 0, A.row(r).setZero(), fixed[r] = 0;  // on a root

  std::vector<char> active(M, 1);
  Eigen::MatrixXd N = Eigen::MatrixXd::Zero(cols, cols);
  auto add_rows = [&](const std::vector<int>& which, double sign) {
    if (which.empty()) return;
    Eigen::MatrixXd B(Eigen::Index(which.size()), cols);
    for (std::size_t k = 0; k < which.size(); ++k) B.row(Eigen::Index(k)) = std::sqrt(w[which[k]]) * A.row(which[k]);
    N.selfadjointView<Eigen::Lower>().rankUpdate(B.transpose(), sign);
  };
  std::vector<int> all(M);
  for (int r = 0; r < M; ++r) all[r] = r;
  add_rows(all, 1.0);
  out.e = Eigen::VectorXd::Zero(cols);
  for (int it = 0; it < o.active_set_iterations; ++it) {
    ++out.iterations;
    Eigen::MatrixXd Nr = N.selfadjointView<Eigen::Lower>();
    const double mean_diag = Nr.diagonal().tail(R).mean();
    for (int i = 1; i < cols; ++i) Nr(i, i) += o.ridge * mean_diag;
    Eigen::VectorXd v(M);
    for (int r = 0; r < M; ++r) v[r] = active[r] ? w[r] * (g[r] - fixed[r]) : 0.0;
    const Eigen::VectorXd rhs = A.transpose() * v;
    out.e = Nr.ldlt().solve(rhs);
    if (!out.e.allFinite()) throw Error("log-kernel fit: the least-squares system is singular");
    out.L = A * out.e + fixed;
    std::vector<int> leave, enter;
    for (int r = 0; r < M; ++r) {
      if (rows[r].two_sided) continue;
      const bool satisfied = rows[r].phi > 0 ? out.L[r] >= s : out.L[r] <= -s;
      if (satisfied && active[r]) leave.push_back(r), active[r] = 0;
      else if (!satisfied && !active[r]) enter.push_back(r), active[r] = 1;
    }
    if (leave.empty() && enter.empty()) break;
    add_rows(leave, -1.0);
    add_rows(enter, 1.0);
  }
  return out;
}

// More roots where the fit is poor: rows on the wrong side, heaviest first, projected onto the
// surface, each at least a pair's width (twice the offset) from every point that already has
// roots, at most base_pairs / 2 a round. Returns whether it added any.
bool RefineRoots(const ScalarGrid& sdf, const FitRows& fit_rows, const FitSolution& fit, int base_pairs,
                 const KernelFitOptions& o, FitRoots& roots) {
  const std::vector<FitRow>& rows = fit_rows.rows;
  const Eigen::VectorXd &w = fit.w, &L = fit.L;
  const int M = int(rows.size());
  const double h = sdf.frame.spacing;
  std::vector<int> wrong;
  double wrong_weight[2] = {0, 0}, side_weight[2] = {0, 0};  // inside, outside
  for (int r = 0; r < M - fit_rows.far; ++r) {
    const int side = rows[r].phi < 0 ? 0 : 1;
    side_weight[side] += w[r];
    if (w[r] > 0 && (L[r] < 0) != (rows[r].phi < 0)) wrong.push_back(r), wrong_weight[side] += w[r];
  }
  // Per side, so that a thin part (few inside cells) is not outvoted by the outside.
  if (wrong_weight[0] <= o.refine_above * side_weight[0] && wrong_weight[1] <= o.refine_above * side_weight[1])
    return false;
  std::stable_sort(wrong.begin(), wrong.end(), [&](int x, int y) { return w[x] > w[y]; });
  const std::size_t before = roots.points.size();
  const double min_gap2 = std::pow(2 * o.offset_cells * h, 2);  // the pairs' own spacing
  for (int r : wrong) {
    if (int(roots.points.size() - before) >= base_pairs / 2) break;
    const Vec3& x = rows[r].x;
    Vec3 n = Gradient(sdf, x);
    const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (!(len > 1e-12)) continue;
    const Vec3 p{x[0] - rows[r].phi * n[0] / len, x[1] - rows[r].phi * n[1] / len, x[2] - rows[r].phi * n[2] / len};
    bool near = false;
    for (const Vec3& q : roots.points)
      if ((p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) + (p[2] - q[2]) * (p[2] - q[2]) < min_gap2) {
        near = true;
        break;
      }
    RootPair rp;
    if (!near && MakePair(sdf, p, o.offset_cells * h, rp)) roots.Add(rp);
  }
  return roots.points.size() != before;
}

// The map of the fitted exponents: positive ones top roots, negative ones bottom roots; counts
// and the exponents' sum into `out`.
RationalMap FittedMap(const std::vector<Vec4>& roots, const Eigen::VectorXd& e, const FractalFrame& frame,
                      bool origin_root, KernelFitSummary& out) {
  RationalMap m;
  m.frame = frame;
  if (origin_root) {
    m.top_roots.push_back({0, 0, 0, 0});
    m.top_exponents.push_back(1.0);
  }
  for (int i = 0; i < int(roots.size()); ++i) {
    const double ei = e[i + 1];
    out.exponent_sum += ei;
    if (ei > 0) m.top_roots.push_back(roots[i]), m.top_exponents.push_back(ei), ++out.top;
    else if (ei < 0) m.bottom_roots.push_back(roots[i]), m.bottom_exponents.push_back(-ei), ++out.bottom;
  }
  m.ln_C = e[0];
  m.tau = m.beta = 1.0;
  return m;
}

// The fit's residual on the band and its sign agreement, into `out`.
void SummarizeFit(const FitRows& fit_rows, const FitSolution& fit, KernelFitSummary& out) {
  const Eigen::VectorXd &w = fit.w, &L = fit.L, &g = fit.g;
  const int M = int(fit_rows.rows.size());
  double band_sq = 0, band_w = 0, agree = 0, total = 0;
  for (int r = 0; r < M; ++r) {
    if (!(w[r] > 0)) continue;
    if (r < fit_rows.band) band_sq += w[r] * (L[r] - g[r]) * (L[r] - g[r]), band_w += w[r];
    total += w[r];
    if ((L[r] < 0) == (fit_rows.rows[r].phi < 0)) agree += w[r];
  }
  out.rows = M, out.band_rows = fit_rows.band, out.far_rows = fit_rows.far;
  out.rms_band = band_w > 0 ? std::sqrt(band_sq / band_w) : 0;
  out.sign_agreement = total > 0 ? agree / total : 0;
}

}  // namespace

RationalMap KernelFitMap(const std::vector<Vec3>& vertices, const std::vector<std::array<int, 3>>& triangles,
                         const ScalarGrid& sdf, const FractalFrame& frame, const KernelFitOptions& o,
                         KernelFitSummary* summary) {
  if (auto why = o.Validate(); !why.empty()) throw Error("log-kernel fit: " + why);
  const auto t0 = std::chrono::steady_clock::now();
  const double h = sdf.frame.spacing;
  KernelFitSummary out;
  out.wall_depth_cells = WallDepthCells(sdf);
  out.thin_walls = ThinWallsOn(o.thin_walls, sdf);
  KernelFitOptions placement = o;
  if (out.thin_walls) {
    placement.spacing = std::max(1.0, o.spacing * KernelFitOptions::kThinWallSpacing);
    placement.max_roots = std::min(4000, 2 * std::max(o.roots, o.max_roots));
  }

  // Root positions: pairs along the normals of surface points, spaced in proportion to their
  // offset (PlacePairs).
  FitRoots roots;
  const std::vector<RootPair> pairs = CandidatePairs(vertices, triangles, sdf, placement);
  const auto [chosen, spacing] = SpacePairs(pairs, placement, h);
  for (int k : chosen) roots.Add(pairs[k]);
  const int base_pairs = int(chosen.size());
  if (roots.roots.empty()) throw Error("log-kernel fit: no surface normals (is the signed distance field flat?)");

  const FitRows rows = MakeFitRows(sdf, o);
  FitSolution fit;
  for (int round = 0;; ++round) {
    fit = SolveExponents(rows, roots.roots, o, o.band_cells * h);
    out.iterations += fit.iterations;
    if (round == o.refine_rounds || !RefineRoots(sdf, rows, fit, base_pairs, o, roots)) break;
    ++out.refine_rounds;
  }
  RationalMap m = FittedMap(roots.roots, fit.e, frame, o.origin_root, out);
  SummarizeFit(rows, fit, out);
  out.spacing = spacing;
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (summary) *summary = out;
  return m;
}

namespace {

// L of `map` at the cells of `grid` (its slice).
std::vector<double> LogModulusOn(const RationalMap& map, const GridFrame& frame, double slice) {
  const std::int64_t n = frame.cell_count();
  std::vector<double> L(static_cast<std::size_t>(n));
#pragma omp parallel for schedule(static)
  for (std::int64_t c = 0; c < n; ++c) L[std::size_t(c)] = OneStepLogModulus(map, frame.cell_center(c), slice);
  return L;
}

// sum_c -tanh(alpha L_c) W_c over the finite L, in cell order (the same sum on any thread count).
double WeightedTanhSum(const EnergyGrid& g, const std::vector<double>& L, double alpha) {
  double s = 0;
  for (std::size_t c = 0; c < L.size(); ++c)
    if (std::isfinite(L[c])) s += -std::tanh(alpha * L[c]) * g.weight[c];
  return s;
}

}  // namespace

StartCheck CheckStart(const RationalMap& map, const ScalarGrid& sdf, double alpha, bool between_nodes) {
  const std::int64_t n = sdf.frame.cell_count();
  const std::vector<double> L = LogModulusOn(map, sdf.frame, 0.0);
  std::vector<double> in, out;
  std::int64_t inter = 0, uni = 0, saturated = 0;
  for (std::int64_t c = 0; c < n; ++c) {
    const bool inside = sdf.values[c] < 0, set = L[c] < 0;  // -inf (on a top root) counts as in the set
    if (std::isnan(L[c])) continue;
    (inside ? in : out).push_back(L[c]);
    inter += inside && set;
    uni += inside || set;
    saturated += std::abs(alpha * L[c]) > 18;
  }
  auto median = [](std::vector<double>& v) {
    if (v.empty()) return std::numeric_limits<double>::quiet_NaN();
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    return v[v.size() / 2];
  };
  StartCheck check;
  check.median_inside = median(in);
  check.median_outside = median(out);
  check.iou = IntersectionOverUnion(inter, uni);
  check.saturated = n ? double(saturated) / double(n) : 0;
  check.inverted = !(check.median_inside < check.median_outside);
  const EnergyGrid nodes = MakeEnergyGrid(sdf, kDefaultWeightField);
  check.psi = EnergyOfField(nodes, L, alpha);
  if (between_nodes) {
    const EnergyGrid corners = CornerGrid(sdf, kDefaultWeightField, nodes);
    const std::vector<double> Lc = LogModulusOn(map, corners.frame, corners.slice);
    check.psi_between_nodes = (WeightedTanhSum(nodes, L, alpha) + WeightedTanhSum(corners, Lc, alpha)) /
                                  (nodes.eta + corners.eta) -
                              TrivialSetEnergy({&nodes, &corners});
  }
  return check;
}

}  // namespace quijibo::monopole
