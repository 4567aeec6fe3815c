#include "mesh/sdf.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numbers>
#include <numeric>

#include "util/error.h"

namespace quijibo::mesh {

namespace {

struct V3 {
  double x, y, z;
};
inline V3 operator-(V3 a, V3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline V3 operator+(V3 a, V3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline V3 operator*(double s, V3 a) { return {s * a.x, s * a.y, s * a.z}; }
inline double Dot(V3 a, V3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline V3 Cross(V3 a, V3 b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline double Norm(V3 a) { return std::sqrt(Dot(a, a)); }
inline V3 ToV3(const Vec3& p) { return {p[0], p[1], p[2]}; }

struct Triangle {
  V3 a, b, c;
  V3 normal{0, 0, 0};  // unit normal (zero for a degenerate triangle)
  double offset = 0;   // normal . a
};

Triangle MakeTriangle(V3 a, V3 b, V3 c) {
  Triangle t{a, b, c};
  const V3 n = Cross(b - a, c - a);
  const double len = Norm(n);
  if (len > 0) t.normal = (1.0 / len) * n;
  t.offset = Dot(t.normal, a);
  return t;
}

// Squared distance from p to triangle abc (Ericson, Real-Time Collision Detection, 5.1.5).
double PointTriangleDistanceSq(V3 p, const Triangle& t) {
  const V3 ab = t.b - t.a, ac = t.c - t.a, ap = p - t.a;
  const double d1 = Dot(ab, ap), d2 = Dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) return Dot(ap, ap);
  const V3 bp = p - t.b;
  const double d3 = Dot(ab, bp), d4 = Dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return Dot(bp, bp);
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const V3 q = p - (t.a + (d1 / (d1 - d3)) * ab);
    return Dot(q, q);
  }
  const V3 cp = p - t.c;
  const double d5 = Dot(ab, cp), d6 = Dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return Dot(cp, cp);
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const V3 q = p - (t.a + (d2 / (d2 - d6)) * ac);
    return Dot(q, q);
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const V3 q = p - (t.b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (t.c - t.b));
    return Dot(q, q);
  }
  const double denom = 1.0 / (va + vb + vc);
  const V3 q = p - (t.a + (vb * denom) * ab + (vc * denom) * ac);
  return Dot(q, q);
}

// Solid angle of triangle abc seen from p (Van Oosterom and Strackee 1983), positive when p
// is on the side its counter-clockwise normal points away from.
double SolidAngle(V3 p, const Triangle& t) {
  const V3 a = t.a - p, b = t.b - p, c = t.c - p;
  const double la = Norm(a), lb = Norm(b), lc = Norm(c);
  const double det = Dot(a, Cross(b, c));
  const double den = la * lb * lc + Dot(a, b) * lc + Dot(a, c) * lb + Dot(b, c) * la;
  return 2.0 * std::atan2(det, den);
}

// BVH over triangles stored contiguously per node, with far-field winding-number moments.
class Bvh {
 public:
  Bvh(std::vector<Triangle> triangles, int leaf_size) : tris_(std::move(triangles)) {
    std::vector<V3> centroids(tris_.size());
    for (std::size_t t = 0; t < tris_.size(); ++t)
      centroids[t] = (1.0 / 3.0) * (tris_[t].a + tris_[t].b + tris_[t].c);
    std::vector<int> order(tris_.size());
    std::iota(order.begin(), order.end(), 0);
    nodes_.reserve(2 * tris_.size() / std::max(1, leaf_size) + 1);
    Build(order, centroids, 0, int(order.size()), std::max(1, leaf_size));
    std::vector<Triangle> sorted(tris_.size());
    for (std::size_t t = 0; t < order.size(); ++t) sorted[t] = tris_[order[t]];
    tris_ = std::move(sorted);
    for (Node& n : nodes_) ComputeMoments(n);
  }

  // Distance from p to the nearest triangle. `hint` is a triangle (index into the BVH's
  // order, or -1) likely to be nearest, e.g. the previous cell's; it is updated.
  double Distance(V3 p, int& hint) const {
    double best = std::numeric_limits<double>::infinity();
    if (hint >= 0) best = PointTriangleDistanceSq(p, tris_[hint]);
    int stack[128];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
      const Node& n = nodes_[stack[--top]];
      if (LowerBoundSq(n, p) >= best) continue;
      if (n.left < 0) {
        for (int t = n.first; t < n.first + n.count; ++t) {
          // The distance to the triangle's plane is a cheap lower bound.
          const double plane = Dot(tris_[t].normal, p) - tris_[t].offset;
          if (plane * plane >= best) continue;
          const double d = PointTriangleDistanceSq(p, tris_[t]);
          if (d < best) {
            best = d;
            hint = t;
          }
        }
        continue;
      }
      const double dl = LowerBoundSq(nodes_[n.left], p), dr = LowerBoundSq(nodes_[n.right], p);
      const int near = dl <= dr ? n.left : n.right, far = dl <= dr ? n.right : n.left;
      if (std::max(dl, dr) < best) stack[top++] = far;
      if (std::min(dl, dr) < best) stack[top++] = near;
    }
    return std::sqrt(best);
  }

  // Generalized winding number at p; beta is the far-field acceptance ratio.
  double Winding(V3 p, double beta) const {
    double sum = 0.0;  // 4 pi w
    int stack[128];
    int top = 0;
    stack[top++] = 0;
    const double beta_sq = beta * beta;
    while (top > 0) {
      const Node& n = nodes_[stack[--top]];
      const V3 r = n.center - p;
      const double r2 = Dot(r, r);
      if (r2 > beta_sq * n.radius_sq) {
        // Taylor expansion of (x - p) / |x - p|^3 about the node's centre, dotted with the
        // normals: f.N + J:M with J = I / |r|^3 - 3 r r^T / |r|^5.
        const double inv_r = 1.0 / std::sqrt(r2), inv_r3 = inv_r * inv_r * inv_r;
        const double* m = n.moment;
        const double trace = m[0] + m[4] + m[8];
        const V3 mr{m[0] * r.x + m[1] * r.y + m[2] * r.z, m[3] * r.x + m[4] * r.y + m[5] * r.z,
                    m[6] * r.x + m[7] * r.y + m[8] * r.z};
        sum += inv_r3 * (Dot(r, n.area_normal) + trace - 3.0 * Dot(r, mr) / r2);
        continue;
      }
      if (n.left < 0) {
        for (int t = n.first; t < n.first + n.count; ++t) sum += SolidAngle(p, tris_[t]);
        continue;
      }
      stack[top++] = n.left;
      stack[top++] = n.right;
    }
    return sum / (4.0 * std::numbers::pi);
  }

 private:
  struct Node {
    V3 lo, hi;
    int left = -1, right = -1;  // children; -1 for a leaf
    int first = 0, count = 0;   // triangle range
    V3 center{0, 0, 0};         // area-weighted centroid
    double radius_sq = 0.0;     // bounding sphere about center
    V3 area_normal{0, 0, 0};    // sum of area * normal
    double moment[9] = {};      // sum_t N_t (c_t - center)^T, row-major
    // Slab bound: every point x of the node's triangles has axis.x in [slab_lo, slab_hi].
    // For the nearly flat patches near a far query it is much tighter than the box.
    V3 axis{0, 0, 0};
    double slab_lo = 0.0, slab_hi = 0.0;
  };

  // A lower bound on the squared distance from p to the node's triangles.
  static double LowerBoundSq(const Node& n, V3 p) {
    const double s = Dot(n.axis, p);
    const double slab = std::max({n.slab_lo - s, 0.0, s - n.slab_hi});
    return std::max(BoxDistanceSq(n, p), slab * slab);
  }

  static double BoxDistanceSq(const Node& n, V3 p) {
    const double dx = std::max({n.lo.x - p.x, 0.0, p.x - n.hi.x});
    const double dy = std::max({n.lo.y - p.y, 0.0, p.y - n.hi.y});
    const double dz = std::max({n.lo.z - p.z, 0.0, p.z - n.hi.z});
    return dx * dx + dy * dy + dz * dz;
  }

  int Build(std::vector<int>& order, const std::vector<V3>& centroids, int first, int count,
            int leaf_size) {
    const int id = int(nodes_.size());
    nodes_.emplace_back();
    Node n;
    n.first = first;
    n.count = count;
    const double inf = std::numeric_limits<double>::infinity();
    n.lo = {inf, inf, inf};
    n.hi = {-inf, -inf, -inf};
    V3 clo = n.lo, chi = n.hi;
    for (int i = first; i < first + count; ++i) {
      const Triangle& t = tris_[order[i]];
      for (V3 v : {t.a, t.b, t.c}) {
        n.lo = {std::min(n.lo.x, v.x), std::min(n.lo.y, v.y), std::min(n.lo.z, v.z)};
        n.hi = {std::max(n.hi.x, v.x), std::max(n.hi.y, v.y), std::max(n.hi.z, v.z)};
      }
      const V3 c = centroids[order[i]];
      clo = {std::min(clo.x, c.x), std::min(clo.y, c.y), std::min(clo.z, c.z)};
      chi = {std::max(chi.x, c.x), std::max(chi.y, c.y), std::max(chi.z, c.z)};
    }
    if (count > leaf_size) {
      const V3 ext = chi - clo;
      const int axis = ext.x >= ext.y && ext.x >= ext.z ? 0 : (ext.y >= ext.z ? 1 : 2);
      auto key = [&](int t) {
        const V3& c = centroids[t];
        return axis == 0 ? c.x : (axis == 1 ? c.y : c.z);
      };
      const int half = count / 2;
      std::nth_element(order.begin() + first, order.begin() + first + half,
                       order.begin() + first + count,
                       [&](int a, int b) { return key(a) < key(b); });
      n.left = Build(order, centroids, first, half, leaf_size);
      n.right = Build(order, centroids, first + half, count - half, leaf_size);
    }
    nodes_[id] = n;
    return id;
  }

  void ComputeMoments(Node& n) const {
    double area = 0.0;
    V3 weighted{0, 0, 0};
    for (int t = n.first; t < n.first + n.count; ++t) {
      const Triangle& tr = tris_[t];
      const V3 an = 0.5 * Cross(tr.b - tr.a, tr.c - tr.a);
      const double a = Norm(an);
      n.area_normal = n.area_normal + an;
      weighted = weighted + (a / 3.0) * (tr.a + tr.b + tr.c);
      area += a;
    }
    n.center = area > 0 ? (1.0 / area) * weighted : 0.5 * (n.lo + n.hi);
    for (int t = n.first; t < n.first + n.count; ++t) {
      const Triangle& tr = tris_[t];
      const V3 an = 0.5 * Cross(tr.b - tr.a, tr.c - tr.a);
      const V3 d = (1.0 / 3.0) * (tr.a + tr.b + tr.c) - n.center;
      const double nv[3] = {an.x, an.y, an.z}, dv[3] = {d.x, d.y, d.z};
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) n.moment[3 * i + j] += nv[i] * dv[j];
      for (V3 v : {tr.a, tr.b, tr.c}) {
        const V3 e = v - n.center;
        n.radius_sq = std::max(n.radius_sq, Dot(e, e));
      }
    }
    const double len = Norm(n.area_normal);
    n.axis = len > 0 ? (1.0 / len) * n.area_normal : V3{1, 0, 0};
    n.slab_lo = std::numeric_limits<double>::infinity();
    n.slab_hi = -n.slab_lo;
    for (int t = n.first; t < n.first + n.count; ++t)
      for (V3 v : {tris_[t].a, tris_[t].b, tris_[t].c}) {
        n.slab_lo = std::min(n.slab_lo, Dot(n.axis, v));
        n.slab_hi = std::max(n.slab_hi, Dot(n.axis, v));
      }
  }

  std::vector<Triangle> tris_;
  std::vector<Node> nodes_;
};

std::vector<Triangle> Triangles(const TriangleMesh& mesh) {
  std::vector<Triangle> tris;
  tris.reserve(mesh.triangles.size());
  for (const auto& t : mesh.triangles)
    tris.push_back(MakeTriangle(ToV3(mesh.vertices[t[0]]), ToV3(mesh.vertices[t[1]]),
                                ToV3(mesh.vertices[t[2]])));
  return tris;
}

}  // namespace

std::string SdfOptions::Validate() const {
  if (!(winding_beta >= 1.0) || !std::isfinite(winding_beta))
    return "winding_beta must be a finite number >= 1";
  if (!(max_ambiguous_fraction >= 0.0)) return "max_ambiguous_fraction must be >= 0";
  if (leaf_size < 1 || leaf_size > 64) return "leaf_size must be in [1, 64]";
  return {};
}

std::vector<double> WindingNumbersExact(const TriangleMesh& mesh,
                                        const std::vector<Vec3>& points) {
  const std::vector<Triangle> tris = Triangles(mesh);
  std::vector<double> w(points.size());
#pragma omp parallel for schedule(static)
  for (std::int64_t i = 0; i < std::int64_t(points.size()); ++i) {
    double sum = 0.0;
    for (const Triangle& t : tris) sum += SolidAngle(ToV3(points[i]), t);
    w[i] = sum / (4.0 * std::numbers::pi);
  }
  return w;
}

std::vector<double> UnsignedDistance(const TriangleMesh& mesh_in, const std::vector<Vec3>& points) {
  TriangleMesh mesh = mesh_in;
  RemoveDegenerateTriangles(mesh);
  ValidateMesh(mesh, "distance");
  const Bvh bvh(Triangles(mesh), SdfOptions{}.leaf_size);
  std::vector<double> d(points.size());
#pragma omp parallel
  {
    int hint = -1;
#pragma omp for schedule(dynamic, 256)
    for (std::int64_t k = 0; k < std::int64_t(points.size()); ++k) {
      const Vec3& p = points[std::size_t(k)];
      d[std::size_t(k)] = bvh.Distance(V3{p[0], p[1], p[2]}, hint);
    }
  }
  return d;
}

ScalarGrid SignedDistance(const TriangleMesh& mesh_in, const GridFrame& grid,
                          const SdfOptions& options, SdfSummary* summary_out) {
  const auto start = std::chrono::steady_clock::now();
  const std::string& name = options.name;
  if (const std::string why = options.Validate(); !why.empty())
    throw Error(name + ": invalid SDF options: " + why);
  if (const std::string why = grid.Validate(); !why.empty())
    throw Error(name + ": invalid SDF grid: " + why);
  ValidateMesh(mesh_in, name);
  TriangleMesh mesh = mesh_in;
  RemoveDegenerateTriangles(mesh);
  ValidateMesh(mesh, name);

  SdfSummary summary;
  summary.topology = AnalyzeTopology(mesh);
  const MeshTopology& topo = summary.topology;
  if (topo.misoriented_edges > 0 && !options.allow_misoriented)
    throw Error(name + ": " + std::to_string(topo.misoriented_edges) +
                " edges have faces of opposite orientation on either side, so inside and "
                "outside cannot be told apart; orient the faces consistently");
  if (topo.boundary_edges > 0 && !options.allow_open)
    throw Error(name + ": the mesh has holes (" + std::to_string(topo.boundary_edges) +
                " boundary edges) and open meshes are refused by the SDF options");
  if (topo.signed_volume < 0.0) {
    FlipOrientation(mesh);
    summary.flipped_orientation = true;
  }
  // Only closed, consistently oriented meshes have a piecewise-constant winding number, which
  // is what lets the sign be carried along rows away from the surface.
  const bool carry_sign = topo.closed() && topo.misoriented_edges == 0;

  const Bvh bvh(Triangles(mesh), options.leaf_size);
  ScalarGrid out;
  out.frame = grid;
  out.quantity = "signed-distance";
  out.coordinates = "fractal";
  out.values.assign(std::size_t(grid.cell_count()), 0.0);
  const int nx = grid.dims[0], ny = grid.dims[1], nz = grid.dims[2];
  const double h = grid.spacing;
  std::int64_t inside = 0, ambiguous = 0, evaluations = 0;

#pragma omp parallel for schedule(dynamic, 4) reduction(+ : inside, ambiguous, evaluations)
  for (std::int64_t row = 0; row < std::int64_t(ny) * nz; ++row) {
    const int j = int(row % ny), k = int(row / ny);
    double previous = std::numeric_limits<double>::infinity();
    bool previous_inside = false;
    int hint = -1;  // nearest triangle of the previous cell: a tight first bound
    for (int i = 0; i < nx; ++i) {
      const V3 p = ToV3(grid.cell_center(i, j, k));
      const double d = bvh.Distance(p, hint);
      bool is_inside;
      if (carry_sign && i > 0 && std::max(previous, d) > h) {
        is_inside = previous_inside;
      } else {
        const double w = bvh.Winding(p, options.winding_beta);
        ++evaluations;
        is_inside = w > 0.5;
        const double aw = std::abs(w);
        if (aw > 0.25 && aw < 0.75) ++ambiguous;
      }
      inside += is_inside;
      out.values[grid.index(i, j, k)] = is_inside ? -d : d;
      previous = d;
      previous_inside = is_inside;
    }
  }
  summary.inside_cells = inside;
  summary.ambiguous_cells = ambiguous;
  summary.winding_evaluations = evaluations;
  const auto [lo, hi] = std::minmax_element(out.values.begin(), out.values.end());
  summary.min_value = *lo;
  summary.max_value = *hi;

  if (inside == 0)
    throw Error(name + ": no grid cell is inside the mesh (an open surface, or thinner than a "
                "cell of the grid); refusing to build a signed distance field");
  if (double(ambiguous) > options.max_ambiguous_fraction * double(inside))
    throw Error(name + ": " + std::to_string(ambiguous) + " cells have an ambiguous winding "
                "number against " + std::to_string(inside) + " inside cells: the mesh does not "
                "bound a clear volume (large holes?); refusing to guess the sign");
  // When the grid box strictly contains the mesh, its border cells must all be outside.
  const BoundingBox box = ComputeBoundingBox(mesh);
  bool contains = true;
  for (int a = 0; a < 3; ++a)
    contains = contains && box.min[a] > grid.min_corner[a] &&
               box.max[a] < grid.min_corner[a] + h * grid.dims[a];
  if (contains) {
    for (int k = 0; k < nz; ++k)
      for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) {
          const bool border =
              i == 0 || j == 0 || k == 0 || i == nx - 1 || j == ny - 1 || k == nz - 1;
          if (border && out.values[grid.index(i, j, k)] < 0.0)
            throw Error(name + ": grid border cell (" + std::to_string(i) + ", " +
                        std::to_string(j) + ", " + std::to_string(k) +
                        ") came out inside the mesh although the grid contains it; refusing "
                        "an inconsistent sign");
          if (!border && j > 0 && j < ny - 1 && k > 0 && k < nz - 1) i = nx - 2;  // skip interior
        }
  }
  summary.seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (summary_out) *summary_out = summary;
  return out;
}

}  // namespace quijibo::mesh
