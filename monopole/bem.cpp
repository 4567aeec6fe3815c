#include "monopole/bem.h"

#include <Eigen/Dense>
#include <unsupported/Eigen/IterativeSolvers>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <numeric>
#include <utility>

#include "monopole/vec3_ops.h"
#include "util/error.h"

namespace quijibo::monopole {

using namespace monopole_detail;

namespace {

constexpr double kFourPi = 4.0 * M_PI;

double Seconds(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

// ln(R + s) for a point at distance R from an edge end whose offset along the edge is s, with
// R^2 = s^2 + r0sq. For s < 0, R + s cancels; R + s = r0sq / (R - s) is exact.
double LogRPlusS(double R, double s, double r0sq) {
  return s >= 0.0 ? std::log(R + s) : std::log(r0sq / (R - s));
}

// Dunavant's symmetric 6-point rule (degree 4) on a triangle: barycentric points and weights
// (weights sum to 1; multiply by the area).
constexpr double kGaussA1 = 0.445948490915965, kGaussB1 = 1.0 - 2.0 * kGaussA1;
constexpr double kGaussA2 = 0.091576213509771, kGaussB2 = 1.0 - 2.0 * kGaussA2;
constexpr double kGaussW1 = 0.223381589678011, kGaussW2 = 0.109951743655322;

double GaussInverseDistance(const Vec3& x, const std::array<Vec3, 3>& p, double area) {
  auto f = [&](double l0, double l1, double l2) {
    const Vec3 y{l0 * p[0][0] + l1 * p[1][0] + l2 * p[2][0],
                 l0 * p[0][1] + l1 * p[1][1] + l2 * p[2][1],
                 l0 * p[0][2] + l1 * p[1][2] + l2 * p[2][2]};
    return 1.0 / Distance(x, y);
  };
  const double s1 = f(kGaussA1, kGaussA1, kGaussB1) + f(kGaussA1, kGaussB1, kGaussA1) +
                    f(kGaussB1, kGaussA1, kGaussA1);
  const double s2 = f(kGaussA2, kGaussA2, kGaussB2) + f(kGaussA2, kGaussB2, kGaussA2) +
                    f(kGaussB2, kGaussA2, kGaussA2);
  return area * (kGaussW1 * s1 + kGaussW2 * s2);
}

// Small union-find; the root of a set is its smallest member, so results do not depend on the
// order of unions.
struct DisjointSets {
  std::vector<int> parent;
  explicit DisjointSets(int n) : parent(n) { std::iota(parent.begin(), parent.end(), 0); }
  int find(int a) {
    while (parent[a] != a) a = parent[a] = parent[parent[a]];
    return a;
  }
  void unite(int a, int b) {
    a = find(a), b = find(b);
    if (a == b) return;
    if (a < b) std::swap(a, b);
    parent[a] = b;
  }
};

// Triangles sharing an edge (all pairs on a non-manifold edge), as a CSR list.
void EdgeAdjacency(const std::vector<std::array<int, 3>>& tris, std::vector<int>& start,
                   std::vector<int>& adj) {
  std::vector<std::pair<std::int64_t, int>> edges;
  edges.reserve(tris.size() * 3);
  for (int t = 0; t < int(tris.size()); ++t)
    for (int e = 0; e < 3; ++e) {
      const std::int64_t a = tris[t][e], b = tris[t][(e + 1) % 3];
      edges.push_back({std::min(a, b) * (std::int64_t(1) << 32) + std::max(a, b), t});
    }
  std::sort(edges.begin(), edges.end());
  std::vector<std::pair<int, int>> pairs;
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i;
    while (j < edges.size() && edges[j].first == edges[i].first) ++j;
    for (std::size_t a = i; a < j; ++a)
      for (std::size_t b = a + 1; b < j; ++b)
        if (edges[a].second != edges[b].second) {
          pairs.push_back({edges[a].second, edges[b].second});
          pairs.push_back({edges[b].second, edges[a].second});
        }
    i = j;
  }
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
  start.assign(tris.size() + 1, 0);
  for (auto& [a, b] : pairs) ++start[a + 1];
  for (std::size_t t = 0; t < tris.size(); ++t) start[t + 1] += start[t];
  adj.resize(pairs.size());
  for (std::size_t i = 0; i < pairs.size(); ++i) adj[i] = pairs[i].second;  // sorted by first
}

// Groups triangles into connected patches of about `cell` size: the triangles whose centroids
// share a voxel, split into edge-connected pieces; pieces smaller than 30 % of the mean area are
// merged into their smallest neighbouring piece (slivers cut off by voxel faces would otherwise
// each cost an unknown). Returns the patch label of every triangle, labels 0..count-1.
std::vector<int> ClusterTriangles(const std::vector<Vec3>& centroids,
                                  const std::vector<double>& areas, const std::vector<int>& start,
                                  const std::vector<int>& adj, double cell, int* count) {
  const int n = int(centroids.size());
  Vec3 lo = centroids[0];
  for (const Vec3& c : centroids)
    for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], c[a]);
  std::vector<std::int64_t> key(n);
  for (int t = 0; t < n; ++t) {
    std::int64_t k = 0;
    for (int a = 0; a < 3; ++a)
      k = k * (std::int64_t(1) << 20) + std::int64_t((centroids[t][a] - lo[a]) / cell);
    key[t] = k;
  }
  DisjointSets sets(n);
  for (int t = 0; t < n; ++t)
    for (int i = start[t]; i < start[t + 1]; ++i)
      if (key[adj[i]] == key[t]) sets.unite(t, adj[i]);

  std::vector<double> area(n, 0.0);
  double total = 0.0;
  int pieces = 0;
  for (int t = 0; t < n; ++t) {
    area[sets.find(t)] += areas[t];
    total += areas[t];
    if (sets.find(t) == t) ++pieces;
  }
  // Members of each initial piece (CSR by root), to find a piece's neighbours quickly.
  std::vector<int> first(n + 1, 0), members(n);
  for (int t = 0; t < n; ++t) ++first[sets.find(t) + 1];
  for (int t = 0; t < n; ++t) first[t + 1] += first[t];
  {
    std::vector<int> fill(first.begin(), first.end() - 1);
    for (int t = 0; t < n; ++t) members[fill[sets.find(t)]++] = t;
  }
  const double small = 0.3 * total / pieces;
  for (int t = 0; t < n; ++t) {
    if (sets.find(t) != t || area[t] >= small) continue;
    int best = -1;  // smallest neighbouring piece
    for (int m = first[t]; m < first[t + 1]; ++m) {
      const int u = members[m];
      for (int i = start[u]; i < start[u + 1]; ++i) {
        const int r = sets.find(adj[i]);
        if (r != t && (best < 0 || area[r] < area[best] || (area[r] == area[best] && r < best)))
          best = r;
      }
    }
    if (best < 0) continue;  // an isolated small component keeps its own unknown
    const double merged = area[t] + area[best];
    sets.unite(t, best);
    area[sets.find(t)] = merged;
  }
  std::vector<int> label(n, -1), root_label(n, -1);
  int next = 0;
  for (int t = 0; t < n; ++t) {
    const int r = sets.find(t);
    if (root_label[r] < 0) root_label[r] = next++;
    label[t] = root_label[r];
  }
  *count = next;
  return label;
}

// The patch of each triangle: its own when the mesh has at most max_elements triangles, else
// clusters of neighbours grown until there are at most max_elements; `count` gets their number.
std::vector<int> PatchLabels(const std::vector<std::array<int, 3>>& triangles, const std::vector<Vec3>& centroids,
                             const std::vector<double>& areas, double total_area, const BemOptions& options,
                             int* count) {
  const int nt = int(triangles.size());
  std::vector<int> label(nt);
  *count = nt;
  if (nt <= options.max_elements) {
    std::iota(label.begin(), label.end(), 0);
    return label;
  }
  std::vector<int> start, adj;
  EdgeAdjacency(triangles, start, adj);
  double cell = std::sqrt(total_area / options.max_elements);
  for (int iter = 0; iter < 60; ++iter) {
    label = ClusterTriangles(centroids, areas, start, adj, cell, count);
    if (*count <= options.max_elements) break;
    cell *= std::max(1.02, std::sqrt(double(*count) / options.max_elements));
  }
  if (*count > options.max_elements)
    throw Error("BEM: could not group the mesh into at most " + std::to_string(options.max_elements) +
                " patches (it has " + std::to_string(*count) + " disconnected pieces)");
  return label;
}

// A sigma = 1 by restarted GMRES (diagonal preconditioner), or LU when chosen or when GMRES does
// not converge; `iterations` and `used_lu` say how.
Eigen::VectorXd SolveCollocation(const Eigen::MatrixXd& A, const BemOptions& options, int* iterations, bool* used_lu) {
  const int ne = int(A.rows());
  const Eigen::VectorXd ones = Eigen::VectorXd::Ones(ne);
  Eigen::VectorXd sigma;
  *iterations = 0;
  *used_lu = options.solver == BemOptions::Solver::kLU;
  if (!*used_lu) {
    Eigen::GMRES<Eigen::MatrixXd, Eigen::DiagonalPreconditioner<double>> gmres;
    gmres.setTolerance(options.solver_tolerance);
    gmres.setMaxIterations(std::max(200, ne / 4));
    gmres.set_restart(50);
    gmres.compute(A);
    sigma = gmres.solve(ones);
    *iterations = int(gmres.iterations());
    *used_lu = gmres.info() != Eigen::Success || !sigma.allFinite() ||
               (A * sigma - ones).norm() > 100.0 * options.solver_tolerance * ones.norm();
  }
  if (*used_lu) sigma = Eigen::PartialPivLU<Eigen::MatrixXd>(A).solve(ones);
  if (!sigma.allFinite()) throw Error("BEM: the collocation system is singular");
  return sigma;
}

}  // namespace

std::string BemOptions::Validate() const {
  if (max_elements < 4)
    return "bem.max_elements must be at least 4, found " + std::to_string(max_elements);
  if (max_elements > 30000)
    return "bem.max_elements must be at most 30000 (a dense system of 8*n^2 bytes), found " +
           std::to_string(max_elements);
  if (!(far_factor >= 1.5) || !std::isfinite(far_factor))
    return "bem.far_factor must be a finite number >= 1.5, found " + std::to_string(far_factor);
  if (!(exact_factor >= 1.0) || !std::isfinite(exact_factor))
    return "bem.exact_factor must be a finite number >= 1, found " + std::to_string(exact_factor);
  if (!(solver_tolerance > 0.0) || !(solver_tolerance < 1e-2))
    return "bem.solver_tolerance must be in (0, 0.01), found " + std::to_string(solver_tolerance);
  if (surface_checks < 0)
    return "bem.surface_checks must be non-negative, found " + std::to_string(surface_checks);
  return {};
}

double TriangleInverseDistanceIntegral(const Vec3& x, const Vec3& a, const Vec3& b,
                                       const Vec3& c) {
  const Vec3 p[3] = {a, b, c};
  Vec3 n = Cross(Sub(b, a), Sub(c, a));
  const double twice_area = Norm(n);
  if (!(twice_area > 0.0)) return 0.0;  // degenerate triangle: no area, no charge
  n = Scale(n, 1.0 / twice_area);
  const double h = std::abs(Dot(Sub(x, a), n));  // height of x above the plane
  double sum = 0.0;
  for (int e = 0; e < 3; ++e) {
    const Vec3& pm = p[e];
    const Vec3& pp = p[(e + 1) % 3];
    const Vec3 d = Sub(pp, pm);
    const double len = Norm(d);
    if (!(len > 0.0)) continue;
    const Vec3 l = Scale(d, 1.0 / len);
    const Vec3 u = Cross(l, n);  // in-plane edge normal pointing out of the triangle
    const double t0 = Dot(Sub(pm, x), u);  // > 0 when x projects on the triangle's side
    const double sm = Dot(Sub(pm, x), l), sp = Dot(Sub(pp, x), l);
    const double Rm = Distance(x, pm), Rp = Distance(x, pp);
    const double r0sq = t0 * t0 + h * h;
    if (t0 != 0.0 && r0sq > 0.0) sum += t0 * (LogRPlusS(Rp, sp, r0sq) - LogRPlusS(Rm, sm, r0sq));
    if (h > 0.0)
      sum -= h * (std::atan(t0 * sp / (r0sq + h * Rp)) - std::atan(t0 * sm / (r0sq + h * Rm)));
  }
  return sum;
}

double ExteriorPotential::PatchIntegral(int j, const Vec3& x) const {
  const Patch& P = patches_[j];
  const Vec3 d = Sub(x, P.centroid);
  const double d2 = Dot(d, d);
  const double far = options_.far_factor * P.radius;
  if (d2 > far * far) {
    // Multipole expansion about the centroid: the dipole term vanishes there.
    const double r = std::sqrt(d2);
    const auto& M = P.moment;
    const double dMd = M[0] * d[0] * d[0] + M[1] * d[1] * d[1] + M[2] * d[2] * d[2] +
                       2.0 * (M[3] * d[0] * d[1] + M[4] * d[0] * d[2] + M[5] * d[1] * d[2]);
    const double trace = M[0] + M[1] + M[2];
    return P.area / r + (3.0 * dMd - d2 * trace) / (2.0 * d2 * d2 * r);
  }
  double sum = 0.0;
  for (int t = P.first; t < P.first + P.count; ++t) {
    const Triangle& T = triangles_[t];
    const double dt = Distance(x, T.centroid);
    if (dt < options_.exact_factor * T.radius)
      sum += TriangleInverseDistanceIntegral(x, T.p[0], T.p[1], T.p[2]);
    else
      sum += GaussInverseDistance(x, T.p, T.area);
  }
  return sum;
}

double ExteriorPotential::operator()(const Vec3& x) const {
  double sum = 0.0;
  for (int j = 0; j < int(patches_.size()); ++j) sum += sigma_[j] * PatchIntegral(j, x);
  return sum / kFourPi;
}

std::vector<double> ExteriorPotential::Evaluate(const std::vector<Vec3>& points) const {
  std::vector<double> out(points.size());
  const std::int64_t n = std::int64_t(points.size());
#pragma omp parallel for schedule(dynamic, 32)
  for (std::int64_t i = 0; i < n; ++i) out[i] = (*this)(points[i]);
  return out;
}

double ExteriorPotential::total_charge() const {
  double q = 0.0;
  for (std::size_t j = 0; j < patches_.size(); ++j) q += sigma_[j] * patches_[j].area;
  return q;
}

void ExteriorPotential::SetPatches(const std::vector<Triangle>& tris, const std::vector<int>& label, int count) {
  // Sort triangles by patch (stable: deterministic), then the patch moments.
  const int nt = int(tris.size());
  std::vector<int> order(nt);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return label[a] < label[b]; });
  triangles_.resize(nt);
  for (int i = 0; i < nt; ++i) triangles_[i] = tris[order[i]];
  patches_.assign(count, {});
  for (int i = 0; i < nt;) {
    int j = i;
    while (j < nt && label[order[j]] == label[order[i]]) ++j;
    auto& P = patches_[label[order[i]]];
    P.first = i;
    P.count = j - i;
    Vec3 c{0, 0, 0};
    for (int t = i; t < j; ++t) {
      P.area += triangles_[t].area;
      c = Add(c, Scale(triangles_[t].centroid, triangles_[t].area));
    }
    P.centroid = P.area > 0.0 ? Scale(c, 1.0 / P.area) : triangles_[i].centroid;
    double best = HUGE_VAL;
    for (int t = i; t < j; ++t) {
      const auto& T = triangles_[t];
      // Exact second moment of a triangle about the patch centroid:
      // integral of y y^T = area/12 * (sum_k v_k v_k^T + s s^T), v_k the corners, s their sum.
      Vec3 v[3], s{0, 0, 0};
      for (int k = 0; k < 3; ++k) {
        v[k] = Sub(T.p[k], P.centroid);
        s = Add(s, v[k]);
        P.radius = std::max(P.radius, Norm(v[k]));
      }
      auto m = [&](int a, int b) {
        return T.area / 12.0 * (v[0][a] * v[0][b] + v[1][a] * v[1][b] + v[2][a] * v[2][b] + s[a] * s[b]);
      };
      P.moment[0] += m(0, 0), P.moment[1] += m(1, 1), P.moment[2] += m(2, 2);
      P.moment[3] += m(0, 1), P.moment[4] += m(0, 2), P.moment[5] += m(1, 2);
      const double dc = Distance(T.centroid, P.centroid);
      if (dc < best) best = dc, P.collocation = T.centroid;
    }
    i = j;
  }
}

ExteriorPotential SolveExteriorPotential(const std::vector<Vec3>& vertices,
                                         const std::vector<std::array<int, 3>>& triangles,
                                         const BemOptions& options, BemSummary* summary) {
  if (const std::string why = options.Validate(); !why.empty()) throw Error(why);
  if (triangles.empty()) throw Error("BEM: the mesh has no triangles");
  const auto t_start = std::chrono::steady_clock::now();

  ExteriorPotential pot;
  pot.options_ = options;
  const int nt = int(triangles.size());
  std::vector<ExteriorPotential::Triangle> tris(nt);
  std::vector<Vec3> centroids(nt);
  std::vector<double> areas(nt);
  for (int t = 0; t < nt; ++t) {
    auto& T = tris[t];
    for (int k = 0; k < 3; ++k) {
      const int v = triangles[t][k];
      if (v < 0 || v >= int(vertices.size()))
        throw Error("BEM: triangle " + std::to_string(t) + " refers to vertex " +
                    std::to_string(v) + ", but the mesh has " + std::to_string(vertices.size()) +
                    " vertices");
      T.p[k] = vertices[v];
    }
    T.centroid = Scale(Add(Add(T.p[0], T.p[1]), T.p[2]), 1.0 / 3.0);
    T.area = 0.5 * Norm(Cross(Sub(T.p[1], T.p[0]), Sub(T.p[2], T.p[0])));
    for (int k = 0; k < 3; ++k) T.radius = std::max(T.radius, Distance(T.centroid, T.p[k]));
    centroids[t] = T.centroid;
    areas[t] = T.area;
  }
  const double total_area = std::accumulate(areas.begin(), areas.end(), 0.0);
  if (!(total_area > 0.0) || !std::isfinite(total_area))
    throw Error("BEM: the mesh has no area (or non-finite coordinates)");

  int count = 0;
  const std::vector<int> label = PatchLabels(triangles, centroids, areas, total_area, options, &count);
  pot.SetPatches(tris, label, count);

  // Collocation matrix, one column per patch (contiguous writes).
  const int ne = count;
  Eigen::MatrixXd A(ne, ne);
#pragma omp parallel for schedule(dynamic, 8)
  for (int j = 0; j < ne; ++j)
    for (int i = 0; i < ne; ++i) A(i, j) = pot.PatchIntegral(j, pot.patches_[i].collocation) / kFourPi;
  const double assembly_seconds = Seconds(t_start);

  const auto t_solve = std::chrono::steady_clock::now();
  int iterations = 0;
  bool used_lu = false;
  const Eigen::VectorXd sigma = SolveCollocation(A, options, &iterations, &used_lu);
  const Eigen::VectorXd ones = Eigen::VectorXd::Ones(ne);
  const double residual = (A * sigma - ones).norm() / ones.norm();
  pot.sigma_.assign(sigma.data(), sigma.data() + ne);
  const double solve_seconds = Seconds(t_solve);

  if (summary) {
    *summary = {};
    summary->input_triangles = nt;
    summary->elements = ne;
    summary->assembly_seconds = assembly_seconds;
    summary->solve_seconds = solve_seconds;
    summary->relative_residual = residual;
    summary->solver_iterations = iterations;
    summary->used_lu = used_lu;
    summary->total_charge = pot.total_charge();
    const int checks = std::min(options.surface_checks, nt);
    if (checks > 0) {
      std::vector<Vec3> pts(checks);
      for (int k = 0; k < checks; ++k) pts[k] = centroids[std::int64_t(k) * nt / checks];
      const std::vector<double> p = pot.Evaluate(pts);
      double mx = 0.0, ss = 0.0;
      for (double v : p) mx = std::max(mx, std::abs(v - 1.0)), ss += (v - 1.0) * (v - 1.0);
      summary->surface_max_deviation = mx;
      summary->surface_rms_deviation = std::sqrt(ss / checks);
    }
  }
  return pot;
}

}  // namespace quijibo::monopole
