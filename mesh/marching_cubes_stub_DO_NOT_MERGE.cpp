// TEMPORARY STAND-IN for mesh/marching_cubes.cpp (issue 5), so that issue 6 can be tested before
// the real mesher is merged. DO NOT MERGE: built only with -DQUIJIBO_MC_STUB=ON and only when
// mesh/marching_cubes.cpp does not exist. Dense evaluation of every node (slab by slab), marching
// TETRAHEDRA (6 per cube around the main diagonal; no tables), bisection on edges, vertices shared
// through an edge map. Slow and simple; the real mesher replaces all of it.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>
#include <unordered_map>

#include "mesh/marching_cubes.h"
#include "quijibo/error.h"

namespace quijibo {

std::string MeshingOptions::validate() const {
  for (int a = 0; a < 3; ++a)
    if (!(max_corner[a] > min_corner[a])) return "the meshing box must have max_corner > min_corner";
  if (resolution < 2 || resolution > 8192) return "resolution must be in [2, 8192]";
  if (bisection_steps < 0 || bisection_steps > 64) return "bisection_steps must be in [0, 64]";
  return {};
}

std::string MeshingSummary::report() const {
  std::ostringstream s;
  s << "nodes evaluated " << nodes_evaluated << ", bisection evaluations " << bisection_evaluations
    << ", non-finite " << non_finite_values << ", " << seconds << " s (STUB mesher)";
  return s.str();
}

TriangleMesh MeshField(const BatchField& field, const MeshingOptions& o, MeshingSummary* summary) {
  if (auto why = o.validate(); !why.empty()) throw Error("meshing: " + why);
  const auto t0 = std::chrono::steady_clock::now();
  double longest = 0;
  for (int a = 0; a < 3; ++a) longest = std::max(longest, o.max_corner[a] - o.min_corner[a]);
  const double h = longest / o.resolution;
  int n[3];
  for (int a = 0; a < 3; ++a) n[a] = std::max(2, int(std::lround((o.max_corner[a] - o.min_corner[a]) / h)) + 1);
  auto node = [&](int i, int j, int k) {
    return Vec3{o.min_corner[0] + h * i, o.min_corner[1] + h * j, o.min_corner[2] + h * k};
  };
  MeshingSummary sum;
  const std::size_t slab = std::size_t(n[0]) * n[1];
  auto eval_slab = [&](int k, std::vector<double>& v) {
    v.resize(slab);
#pragma omp parallel for schedule(dynamic, 1)
    for (int j = 0; j < n[1]; ++j) {
      std::vector<Vec3> pts(n[0]);
      for (int i = 0; i < n[0]; ++i) pts[i] = node(i, j, k);
      field.evaluate(pts.data(), pts.size(), v.data() + std::size_t(j) * n[0]);
    }
    for (double& x : v)
      if (!std::isfinite(x)) {
        x = std::numeric_limits<double>::infinity();
        ++sum.non_finite_values;
      }
    sum.nodes_evaluated += std::int64_t(slab);
  };
  TriangleMesh mesh;
  std::unordered_map<std::uint64_t, int> edge_vertex;
  auto vertex_on_edge = [&](std::int64_t ga, std::int64_t gb, Vec3 pa, Vec3 pb, double fa, double fb) {
    if (ga > gb) {
      std::swap(ga, gb);
      std::swap(pa, pb);
      std::swap(fa, fb);
    }
    const std::uint64_t key = std::uint64_t(ga) * 0x9E3779B97F4A7C15ULL ^ std::uint64_t(gb);
    auto it = edge_vertex.find(key);
    if (it != edge_vertex.end()) return it->second;
    Vec3 lo = pa, hi = pb;  // lo inside (f < iso)
    if (!(fa < field.iso)) std::swap(lo, hi);
    Vec3 mid{0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), 0.5 * (lo[2] + hi[2])};
    for (int s = 0; s < o.bisection_steps; ++s) {
      double v;
      field.evaluate(&mid, 1, &v);
      ++sum.bisection_evaluations;
      if (std::abs(v - field.iso) < o.bisection_tolerance) break;
      (v < field.iso ? lo : hi) = mid;
      mid = {0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), 0.5 * (lo[2] + hi[2])};
    }
    const int id = int(mesh.vertices.size());
    mesh.vertices.push_back(mid);
    edge_vertex.emplace(key, id);
    return id;
  };
  static const int kTets[6][4] = {{0, 1, 3, 7}, {0, 1, 5, 7}, {0, 2, 3, 7}, {0, 2, 6, 7}, {0, 4, 5, 7}, {0, 4, 6, 7}};
  std::vector<double> below, above;
  eval_slab(0, below);
  for (int k = 0; k + 1 < n[2]; ++k) {
    eval_slab(k + 1, above);
    for (int j = 0; j + 1 < n[1]; ++j)
      for (int i = 0; i + 1 < n[0]; ++i) {
        double f[8];
        Vec3 p[8];
        std::int64_t g[8];
        bool any_in = false, any_out = false;
        for (int c = 0; c < 8; ++c) {
          const int di = c & 1, dj = (c >> 1) & 1, dk = (c >> 2) & 1;
          const auto& s = dk ? above : below;
          f[c] = s[std::size_t(j + dj) * n[0] + i + di];
          p[c] = node(i + di, j + dj, k + dk);
          g[c] = (i + di) + std::int64_t(n[0]) * ((j + dj) + std::int64_t(n[1]) * (k + dk));
          (f[c] < field.iso ? any_in : any_out) = true;
        }
        if (!any_in || !any_out) continue;
        for (const auto& tet : kTets) {
          int in[4], out[4], ni = 0, no = 0;
          for (int c : tet) (f[c] < field.iso ? in[ni++] : out[no++]) = c;
          if (ni == 0 || no == 0) continue;
          auto V = [&](int a, int b) { return vertex_on_edge(g[a], g[b], p[a], p[b], f[a], f[b]); };
          Vec3 cin{0, 0, 0}, cout{0, 0, 0};
          for (int t = 0; t < ni; ++t)
            for (int a = 0; a < 3; ++a) cin[a] += p[in[t]][a] / ni;
          for (int t = 0; t < no; ++t)
            for (int a = 0; a < 3; ++a) cout[a] += p[out[t]][a] / no;
          auto emit = [&](int a, int b, int c) {
            const Vec3 &A = mesh.vertices[a], &B = mesh.vertices[b], &C = mesh.vertices[c];
            const Vec3 u{B[0] - A[0], B[1] - A[1], B[2] - A[2]}, w{C[0] - A[0], C[1] - A[1], C[2] - A[2]};
            const Vec3 nrm{u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
            const double dot = nrm[0] * (cout[0] - cin[0]) + nrm[1] * (cout[1] - cin[1]) + nrm[2] * (cout[2] - cin[2]);
            if (a == b || b == c || a == c) return;
            if (dot >= 0) mesh.triangles.push_back({a, b, c});
            else mesh.triangles.push_back({a, c, b});
          };
          if (ni == 1) emit(V(in[0], out[0]), V(in[0], out[1]), V(in[0], out[2]));
          else if (no == 1) emit(V(out[0], in[0]), V(out[0], in[1]), V(out[0], in[2]));
          else {
            const int a = V(in[0], out[0]), b = V(in[0], out[1]), c = V(in[1], out[1]), d = V(in[1], out[0]);
            emit(a, b, c);
            emit(a, c, d);
          }
        }
      }
    std::swap(below, above);
  }
  sum.tiles_total = sum.tiles_meshed = 1;
  sum.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (summary) *summary = sum;
  return mesh;
}

}  // namespace quijibo
