#include "mesh/fidelity.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <unordered_map>
#include <unordered_set>
#include <utility>

#include "mesh/sdf.h"
#include "util/error.h"
#include "quijibo/iou.h"

namespace quijibo::mesh {

std::string FidelityOptions::Validate() const {
  if (lattice < 8 || lattice > 512) return "lattice must be in [8, 512]";
  if (!(extend >= 0 && extend <= 2)) return "extend must be in [0, 2]";
  if (surface_samples < 100 || surface_samples > 10000000) return "surface samples must be in [100, 1e7]";
  if (julia.iterations > 0)
    if (auto why = julia.Validate(); !why.empty()) return why;
  if (closing < 0 || closing > 16) return "closing must be in [0, 16] cells";
  return {};
}

nlohmann::json Fidelity::ToJson() const {
  nlohmann::json j = {{"inside_nodes", inside_nodes},
                      {"one_step",
                       {{"iou", one_step.iou},
                        {"volume_iou", one_step.volume_iou},
                        {"leak", one_step.leak},
                        {"set_nodes", one_step.set_nodes}}}};
  if (has_n_step)
    j["n_step"] = {{"iou", n_step.iou},
                   {"volume_iou", n_step.volume_iou},
                   {"closed_iou", n_step_closed_iou},
                   {"leak", n_step.leak},
                   {"set_nodes", n_step.set_nodes}};
  if (chamfer >= 0) j["chamfer"] = chamfer, j["hausdorff"] = hausdorff;
  return j;
}

namespace {

double EdgeLength(const Vec3& a, const Vec3& b) {
  return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}

double SurfaceArea(const TriangleMesh& m) {
  double total = 0;
  for (const auto& t : m.triangles) {
    const Vec3 &a = m.vertices[t[0]], &b = m.vertices[t[1]], &c = m.vertices[t[2]];
    const Vec3 u{b[0] - a[0], b[1] - a[1], b[2] - a[2]}, v{c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    total += 0.5 * std::hypot(u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]);
  }
  return total;
}

// Connected components of the triangles, joined by shared vertices (union-find).
std::int64_t MeshComponents(const TriangleMesh& m) {
  std::vector<std::int64_t> parent(m.vertices.size());
  for (std::size_t i = 0; i < parent.size(); ++i) parent[i] = std::int64_t(i);
  auto find = [&](std::int64_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  std::vector<char> used(m.vertices.size(), 0);
  for (const auto& t : m.triangles) {
    for (int k = 0; k < 3; ++k) used[t[k]] = 1;
    parent[find(t[1])] = find(t[0]);
    parent[find(t[2])] = find(t[0]);
  }
  std::int64_t count = 0;
  for (std::size_t i = 0; i < parent.size(); ++i) count += used[i] && find(std::int64_t(i)) == std::int64_t(i);
  return count;
}

// One pass of a separable cube filter of half side r over an n^3 lattice: dilation (any set node
// within r along the axis) or erosion (every node within r set; outside the lattice counts as
// unset for both, so a set touching the lattice's faces erodes there as an open set would).
std::vector<char> CubeFilter(const std::vector<char>& in, int n, int r, bool dilate) {
  std::vector<char> cur = in, next(in.size());
  for (int axis = 0; axis < 3; ++axis) {
    const std::int64_t stride = axis == 0 ? 1 : axis == 1 ? n : std::int64_t(n) * n;
    for (std::int64_t c = 0; c < std::int64_t(cur.size()); ++c) {
      const int i = int((c / stride) % n);
      bool any = false, all = true;
      for (int d = -r; d <= r; ++d) {
        const int j = i + d;
        const bool v = j >= 0 && j < n && cur[std::size_t(c + std::int64_t(d) * stride)];
        any |= v, all &= v;
      }
      next[std::size_t(c)] = dilate ? any : all;
    }
    std::swap(cur, next);
  }
  return cur;
}

}  // namespace

// Morphological closing of an n^3 lattice set by a cube of half side r (cells).
std::vector<char> Close(const std::vector<char>& set, int n, int r) {
  if (r <= 0) return set;
  return CubeFilter(CubeFilter(set, n, r, true), n, r, false);
}

namespace {

// A uniform double in [0, 1) from (seed, index, axis): SplitMix64's finalizer, so a point depends
// on its cell alone, not on the thread that draws it.
double CellUniform(std::uint64_t seed, std::int64_t index, int axis) {
  std::uint64_t z = seed * 0x9E3779B97F4A7C15ull + std::uint64_t(index) * 3 + std::uint64_t(axis) + 1;
  z *= 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  z ^= z >> 31;
  return double(z >> 11) * 0x1.0p-53;
}

}  // namespace

Fidelity MeasureSets(const RationalMap& map, const ScalarGrid& target, const FidelityOptions& o) {
  if (auto why = o.Validate(); !why.empty()) throw Error("fidelity: " + why);
  if (o.julia.iterations > 0 && !o.iterated)
    throw Error("fidelity: the n-step set needs the map as iterated (its frame and detail applied: JuliaSetup::map)");
  const double b = map.frame.fractal_radius * (1.0 - 2.0 * map.frame.padding) / 2;  // half side of B
  const double half = b * (1.0 + 2.0 * o.extend);
  const int n = o.lattice;
  const double step = 2 * half / (n - 1);
  const Vec3 bc = map.frame.box_center();
  const Vec3 lo = target.frame.min_corner, ext = target.frame.extent();
  auto in_grid = [&](const Vec3& p) {
    for (int a = 0; a < 3; ++a)
      if (p[a] < lo[a] || p[a] > lo[a] + ext[a]) return false;
    return true;
  };
  std::unique_ptr<JuliaMap<double>> julia;
  if (o.julia.iterations > 0) julia = std::make_unique<JuliaMap<double>>(*o.iterated, o.julia);
  const RationalMap& iterated = o.julia.iterations > 0 ? *o.iterated : map;
  const std::int64_t count = std::int64_t(n) * n * n;
  std::vector<char> in_set(julia ? static_cast<std::size_t>(count) : 0), in_target(static_cast<std::size_t>(count));
  auto in_one_step = [&](const Vec3& p) {
    const double L = OneStepLogModulus(map, p);
    return !std::isnan(L) && L < 0;
  };
  auto in_n_step = [&](const Vec3& p) {
    const double v = julia->At(iterated.frame.user_to_fractal(map.frame.fractal_to_user(p))).log_modulus;
    return !std::isnan(v) && v < o.iso;
  };
  std::int64_t inside = 0, inter1 = 0, union1 = 0, set1 = 0, leak1 = 0, interN = 0, unionN = 0, setN = 0, leakN = 0;
  std::int64_t v_inter1 = 0, v_union1 = 0, v_interN = 0, v_unionN = 0;
#pragma omp parallel for schedule(dynamic, 64) \
    reduction(+ : inside, inter1, union1, set1, leak1, interN, unionN, setN, leakN, v_inter1, v_union1, v_interN, v_unionN)
  for (std::int64_t c = 0; c < count; ++c) {
    const int i = int(c % n), j = int((c / n) % n), k = int(c / (std::int64_t(n) * n));
    const Vec3 p{bc[0] - half + i * step, bc[1] - half + j * step, bc[2] - half + k * step};
    const bool in = in_grid(p) && target.sample(p) < 0;
    in_target[std::size_t(c)] = in;
    const bool outside_b = std::abs(p[0] - bc[0]) > b || std::abs(p[1] - bc[1]) > b || std::abs(p[2] - bc[2]) > b;
    inside += in;
    const bool s1 = in_one_step(p);
    set1 += s1, inter1 += s1 && in, union1 += s1 || in, leak1 += s1 && outside_b;
    if (julia) {
      const bool sn = in_n_step(p);
      in_set[std::size_t(c)] = sn;
      setN += sn, interN += sn && in, unionN += sn || in, leakN += sn && outside_b;
    }
    // The cell whose lowest corner is this node: one uniform point in it.
    if (i + 1 < n && j + 1 < n && k + 1 < n) {
      Vec3 q;
      for (int a = 0; a < 3; ++a) q[a] = p[a] + step * CellUniform(o.seed, c, a);
      const bool qin = in_grid(q) && target.sample(q) < 0;
      const bool q1 = in_one_step(q);
      v_inter1 += q1 && qin, v_union1 += q1 || qin;
      if (julia) {
        const bool qn = in_n_step(q);
        v_interN += qn && qin, v_unionN += qn || qin;
      }
    }
  }
  Fidelity f;
  f.inside_nodes = inside;
  auto figures = [&](std::int64_t set, std::int64_t inter, std::int64_t uni, std::int64_t leak) {
    SetFigures s;
    s.set_nodes = set, s.leak_nodes = leak;
    s.iou = IntersectionOverUnion(inter, uni);
    s.leak = inside ? double(leak) / double(inside) : 0;
    return s;
  };
  f.one_step = figures(set1, inter1, union1, leak1);
  f.one_step.volume_iou = IntersectionOverUnion(v_inter1, v_union1);
  if (julia) {
    f.n_step = figures(setN, interN, unionN, leakN), f.has_n_step = true;
    f.n_step.volume_iou = IntersectionOverUnion(v_interN, v_unionN);
    const std::vector<char> closed = Close(in_set, n, o.closing);
    std::int64_t inter = 0, uni = 0;
    for (std::size_t c = 0; c < closed.size(); ++c) inter += closed[c] && in_target[c], uni += closed[c] || in_target[c];
    f.n_step_closed_iou = IntersectionOverUnion(inter, uni);
  }
  return f;
}

nlohmann::json NodeFit::ToJson() const {
  return {{"on_nodes_iou", on_nodes},       {"between_nodes_iou", between_nodes},
          {"nodes", nodes},                 {"corners", corners},
          {"undecided_nodes", undecided_nodes}, {"undecided_corners", undecided_corners}};
}

namespace {
// IoU of {L < 0} and {phi < 0} over points 0..count-1 (at(c) gives the point and phi there),
// leaving out those with |phi| < undecided; the number left out in `*skipped`.
template <typename At>
double DecidedIoU(const RationalMap& map, std::int64_t count, double undecided, At at, std::int64_t* skipped) {
  std::int64_t inter = 0, uni = 0, left_out = 0;
#pragma omp parallel for schedule(static) reduction(+ : inter, uni, left_out)
  for (std::int64_t c = 0; c < count; ++c) {
    const auto [p, phi] = at(c);
    if (std::abs(phi) < undecided) {
      ++left_out;
      continue;
    }
    const double L = OneStepLogModulus(map, p);
    const bool in = phi < 0, set = !std::isnan(L) && L < 0;
    inter += in && set, uni += in || set;
  }
  *skipped = left_out;
  return IntersectionOverUnion(inter, uni);
}
}  // namespace

NodeFit MeasureNodeFit(const RationalMap& map, const ScalarGrid& target) {
  const GridFrame& g = target.frame;
  const double undecided = 0.25 * g.spacing;
  NodeFit fit;
  const std::int64_t cells = g.cell_count();
  fit.on_nodes = DecidedIoU(
      map, cells, undecided, [&](std::int64_t c) { return std::pair{g.cell_center(c), target.values[std::size_t(c)]}; },
      &fit.undecided_nodes);
  fit.nodes = cells - fit.undecided_nodes;
  // Interior corners: (i + 1) spacing from the min corner, i in [0, dims - 2].
  const std::int64_t cx = std::max(g.dims[0] - 1, 0), cy = std::max(g.dims[1] - 1, 0), cz = std::max(g.dims[2] - 1, 0);
  const std::int64_t corners = cx * cy * cz;
  fit.between_nodes = DecidedIoU(
      map, corners, undecided,
      [&](std::int64_t c) {
        const std::int64_t i = c % cx, j = (c / cx) % cy, k = c / (cx * cy);
        const Vec3 p{g.min_corner[0] + g.spacing * double(i + 1), g.min_corner[1] + g.spacing * double(j + 1),
                     g.min_corner[2] + g.spacing * double(k + 1)};
        return std::pair{p, target.sample(p)};
      },
      &fit.undecided_corners);
  fit.corners = corners - fit.undecided_corners;
  return fit;
}

nlohmann::json MeshDetail::ToJson() const {
  nlohmann::json j = {{"area", area}, {"components", components}, {"box_dimension", dimension}, {"box_counts", box_counts}};
  if (area_ratio >= 0) j["area_ratio"] = area_ratio;
  return j;
}

MeshDetail MeasureMeshDetail(const TriangleMesh& julia, const TriangleMesh* shape, double side) {
  if (!(side > 0) || !std::isfinite(side)) throw Error("detail: the shape box's side must be positive");
  MeshDetail d;
  d.area = SurfaceArea(julia);
  if (shape) {
    const double a = SurfaceArea(*shape);
    d.area_ratio = a > 0 ? d.area / a : -1;
  }
  d.components = MeshComponents(julia);
  // Box counting: points on every triangle no farther apart than half the finest box, so a
  // triangle marks every finest box it crosses except at most slivers at box corners.
  constexpr int kFirst = 3, kLast = 7;
  const double finest = side / double(1 << kLast), spacing = finest / 2;
  Vec3 lo{0, 0, 0};
  if (!julia.vertices.empty()) lo = julia.vertices[0];
  for (const Vec3& v : julia.vertices)
    for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], v[a]);
  std::vector<std::unordered_set<std::uint64_t>> boxes(kLast - kFirst + 1);
  auto mark = [&](const Vec3& p) {
    std::uint64_t cell[3];
    for (int a = 0; a < 3; ++a) cell[a] = std::uint64_t(std::max(0.0, std::floor((p[a] - lo[a]) / finest)));
    for (int k = kLast; k >= kFirst; --k) {
      const int shift = kLast - k;
      boxes[k - kFirst].insert(((cell[0] >> shift) << 42) | ((cell[1] >> shift) << 21) | (cell[2] >> shift));
    }
  };
  for (const auto& t : julia.triangles) {
    const Vec3 &a = julia.vertices[t[0]], &b = julia.vertices[t[1]], &c = julia.vertices[t[2]];
    const double longest = std::max({EdgeLength(a, b), EdgeLength(b, c), EdgeLength(c, a)});
    const int m = std::max(1, int(std::ceil(longest / spacing)));
    for (int i = 0; i <= m; ++i)
      for (int j = 0; i + j <= m; ++j) {
        const double u = double(i) / m, v = double(j) / m;
        mark({a[0] + u * (b[0] - a[0]) + v * (c[0] - a[0]), a[1] + u * (b[1] - a[1]) + v * (c[1] - a[1]),
              a[2] + u * (b[2] - a[2]) + v * (c[2] - a[2])});
      }
  }
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  const int levels = kLast - kFirst + 1;
  for (int k = kFirst; k <= kLast; ++k) {
    const std::int64_t count = std::int64_t(boxes[k - kFirst].size());
    d.box_counts.push_back(count);
    const double x = k * std::log(2.0), y = std::log(double(std::max<std::int64_t>(count, 1)));
    sx += x, sy += y, sxx += x * x, sxy += x * y;
  }
  d.dimension = julia.triangles.empty() ? 0 : (levels * sxy - sx * sy) / (levels * sxx - sx * sx);
  return d;
}

std::vector<Vec3> SampleSurface(const TriangleMesh& m, int count, std::uint64_t seed) {
  std::vector<double> cdf;
  double total = 0;
  for (const auto& t : m.triangles) {
    const Vec3 &a = m.vertices[t[0]], &b = m.vertices[t[1]], &c = m.vertices[t[2]];
    const Vec3 u{b[0] - a[0], b[1] - a[1], b[2] - a[2]}, v{c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    total += 0.5 * std::hypot(u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]);
    cdf.push_back(total);
  }
  std::vector<Vec3> out;
  if (!(total > 0)) return out;
  std::mt19937_64 rng(seed);
  auto uniform = [&] { return double(rng() >> 11) * 0x1.0p-53; };
  out.reserve(std::size_t(count));
  for (int n = 0; n < count; ++n) {
    const std::size_t i =
        std::min(cdf.size() - 1, std::size_t(std::lower_bound(cdf.begin(), cdf.end(), uniform() * total) - cdf.begin()));
    double r1 = uniform(), r2 = uniform();
    if (r1 + r2 > 1) r1 = 1 - r1, r2 = 1 - r2;
    const auto& t = m.triangles[i];
    const Vec3 &a = m.vertices[t[0]], &b = m.vertices[t[1]], &c = m.vertices[t[2]];
    out.push_back({a[0] + r1 * (b[0] - a[0]) + r2 * (c[0] - a[0]), a[1] + r1 * (b[1] - a[1]) + r2 * (c[1] - a[1]),
                   a[2] + r1 * (b[2] - a[2]) + r2 * (c[2] - a[2])});
  }
  return out;
}

void MeasureSurfaceDistances(const TriangleMesh& julia, const TriangleMesh& shape, const FidelityOptions& o,
                             Fidelity& f) {
  if (auto why = o.Validate(); !why.empty()) throw Error("fidelity: " + why);
  Vec3 lo = shape.vertices.at(0), hi = lo;
  for (const Vec3& v : shape.vertices)
    for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], v[a]), hi[a] = std::max(hi[a], v[a]);
  const double diagonal = std::sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                                    (hi[2] - lo[2]) * (hi[2] - lo[2]));
  const std::vector<Vec3> on_julia = SampleSurface(julia, o.surface_samples, o.seed),
                          on_shape = SampleSurface(shape, o.surface_samples, o.seed + 1);
  if (on_julia.empty() || on_shape.empty()) throw Error("fidelity: a mesh without area");
  const std::vector<double> ab = UnsignedDistance(shape, on_julia), ba = UnsignedDistance(julia, on_shape);
  f.chamfer = 0.5 * (Mean(ab) + Mean(ba)) / diagonal;
  f.hausdorff = std::max(*std::max_element(ab.begin(), ab.end()), *std::max_element(ba.begin(), ba.end())) / diagonal;
}

std::vector<double> NearestPointDistances(const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
  std::vector<double> out(a.size(), std::numeric_limits<double>::infinity());
  if (b.empty() || a.empty()) return out;
  Vec3 lo = b[0], hi = b[0];
  for (const Vec3& p : b)
    for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], p[k]), hi[k] = std::max(hi[k], p[k]);
  double vol = 1;
  for (int k = 0; k < 3; ++k) vol *= std::max(hi[k] - lo[k], 1e-9);
  const double cell = std::max(std::cbrt(vol / double(b.size())) * 2.0, 1e-9);
  auto key = [&](long long i, long long j, long long k) {
    return std::uint64_t(i) * 73856093ULL ^ std::uint64_t(j) * 19349663ULL ^ std::uint64_t(k) * 83492791ULL;
  };
  auto idx = [&](double x, int k) { return (long long)std::floor((x - lo[k]) / cell); };
  std::unordered_multimap<std::uint64_t, int> grid;
  grid.reserve(b.size());
  for (int i = 0; i < int(b.size()); ++i) grid.emplace(key(idx(b[i][0], 0), idx(b[i][1], 1), idx(b[i][2], 2)), i);
#pragma omp parallel for schedule(dynamic, 256)
  for (long long n = 0; n < (long long)a.size(); ++n) {
    const Vec3& p = a[n];
    const long long ci = idx(p[0], 0), cj = idx(p[1], 1), ck = idx(p[2], 2);
    double best2 = std::numeric_limits<double>::infinity();
    for (int r = 0; r < 100000; ++r) {
      // Scan the shell of cells at Chebyshev radius r; stop when no closer point can remain.
      for (long long i = ci - r; i <= ci + r; ++i)
        for (long long j = cj - r; j <= cj + r; ++j)
          for (long long k = ck - r; k <= ck + r; ++k) {
            if (std::max({std::llabs(i - ci), std::llabs(j - cj), std::llabs(k - ck)}) != r) continue;
            auto range = grid.equal_range(key(i, j, k));
            for (auto it = range.first; it != range.second; ++it) {
              const Vec3& q = b[it->second];
              const double d2 = (p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) + (p[2] - q[2]) * (p[2] - q[2]);
              best2 = std::min(best2, d2);
            }
          }
      if (std::isfinite(best2) && std::sqrt(best2) <= r * cell) break;
    }
    out[n] = std::sqrt(best2);
  }
  return out;
}

SampleChamfer MeasureSampleChamfer(const std::vector<Vec3>& set, const std::vector<Vec3>& target) {
  return {Mean(NearestPointDistances(set, target)), Mean(NearestPointDistances(target, set))};
}

double Mean(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x;
  return v.empty() ? std::nan("") : s / double(v.size());
}

}  // namespace quijibo::mesh
