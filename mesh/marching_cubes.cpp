// Marching cubes with bisection on the edges, sparse coarse-to-fine block search, parallel tiles.
//
// Layout. Nodes of the lattice (MeshLattice) are indexed (i, j, k), i in [0, cells_x]; the edge
// from node (i, j, k) along axis a has the global id 3 * (i + N_x (j + N_y k)) + a (N = cells + 1).
// Every vertex sits on one edge and is keyed by that id, so the tiles mesh independently: a seam
// edge is bisected by each tile that touches it, from the same end values and in the same order,
// giving bit-identical positions, and the merge keeps one vertex per id. Vertices come out sorted
// by edge id and triangles in tile order, then cell order: the output does not depend on the
// number of threads, and the dense and sparse modes give the same mesh when the search misses
// nothing.
//
// Case table. Built at start-up from the corner signs, not copied from a table: on each cube face
// the crossing edges are paired into segments (an ambiguous face, two diagonal inside corners,
// cuts off each inside corner: neighbouring cells see the same face and pair it the same way, so
// the surface has no cracks); the segments of the six faces form closed cycles, each cycle is one
// polygon, oriented so that its normal points from the inside corners to the outside ones, and fanned
// into triangles.
#include "mesh/marching_cubes.h"

#include <omp.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <sstream>

#include "mesh/mesher_internal.h"
#include "util/error.h"
#include "util/progress.h"

namespace quijibo::mesh {

using namespace mesher;

namespace {

// ---------------------------------------------------------------------------------------------
// Case table.

struct CubeEdge {
  int axis;
  int c0, c1;  // corners, c1 = c0 + (1 << axis)
};

constexpr int CornerBit(int c, int axis) { return (c >> axis) & 1; }

std::array<CubeEdge, 12> MakeEdges() {
  std::array<CubeEdge, 12> e{};
  for (int a = 0; a < 3; ++a) {
    const int b1 = (a + 1) % 3 < (a + 2) % 3 ? (a + 1) % 3 : (a + 2) % 3;
    const int b2 = 3 - a - b1;
    for (int m = 0; m < 4; ++m) {
      const int c0 = ((m & 1) << b1) | (((m >> 1) & 1) << b2);
      e[4 * a + m] = {a, c0, c0 | (1 << a)};
    }
  }
  return e;
}

const std::array<CubeEdge, 12>& Edges() {
  static const std::array<CubeEdge, 12> e = MakeEdges();
  return e;
}

struct CaseTable {
  // For each of the 256 configurations (bit c set: corner c inside), triangles as cube-edge triples.
  std::array<std::vector<std::array<std::uint8_t, 3>>, 256> triangles;
};

CaseTable MakeCaseTable() {
  const auto& E = Edges();
  CaseTable table;
  auto corner_pos = [](int c) {
    return std::array<double, 3>{double(c & 1), double((c >> 1) & 1), double((c >> 2) & 1)};
  };
  for (int config = 0; config < 256; ++config) {
    auto inside = [&](int c) { return (config >> c) & 1; };
    std::array<std::vector<int>, 12> adj;
    for (int a = 0; a < 3; ++a)
      for (int side = 0; side < 2; ++side) {
        std::vector<int> face_edges;
        for (int e = 0; e < 12; ++e)
          if (E[e].axis != a && CornerBit(E[e].c0, a) == side) face_edges.push_back(e);
        std::vector<int> crossing;
        for (int e : face_edges)
          if (inside(E[e].c0) != inside(E[e].c1)) crossing.push_back(e);
        if (crossing.size() == 2) {
          adj[crossing[0]].push_back(crossing[1]);
          adj[crossing[1]].push_back(crossing[0]);
        } else if (crossing.size() == 4) {
          // Ambiguous face: pair the two crossing edges at each inside corner.
          for (int c = 0; c < 8; ++c) {
            if (CornerBit(c, a) != side || !inside(c)) continue;
            std::vector<int> at;
            for (int e : crossing)
              if (E[e].c0 == c || E[e].c1 == c) at.push_back(e);
            adj[at[0]].push_back(at[1]);
            adj[at[1]].push_back(at[0]);
          }
        }
      }
    std::array<bool, 12> used{};
    for (int start = 0; start < 12; ++start) {
      if (used[start] || adj[start].empty()) continue;
      std::vector<int> cycle{start};
      used[start] = true;
      int prev = -1, cur = start;
      for (;;) {
        const int next = adj[cur][0] != prev ? adj[cur][0] : adj[cur][1];
        if (next == start) break;
        cycle.push_back(next);
        used[next] = true;
        prev = cur;
        cur = next;
      }
      // Orientation: polygon normal (Newell) against the inside -> outside direction.
      std::array<double, 3> n{0, 0, 0}, d{0, 0, 0};
      std::vector<std::array<double, 3>> p;
      for (int e : cycle) {
        auto a = corner_pos(E[e].c0), b = corner_pos(E[e].c1);
        p.push_back({(a[0] + b[0]) / 2, (a[1] + b[1]) / 2, (a[2] + b[2]) / 2});
        const double s = inside(E[e].c0) ? 1.0 : -1.0;  // from the inside end to the outside end
        for (int k = 0; k < 3; ++k) d[k] += s * (b[k] - a[k]);
      }
      for (std::size_t i = 0; i < p.size(); ++i) {
        const auto& u = p[i];
        const auto& v = p[(i + 1) % p.size()];
        n[0] += (u[1] - v[1]) * (u[2] + v[2]);
        n[1] += (u[2] - v[2]) * (u[0] + v[0]);
        n[2] += (u[0] - v[0]) * (u[1] + v[1]);
      }
      if (n[0] * d[0] + n[1] * d[1] + n[2] * d[2] < 0) std::reverse(cycle.begin(), cycle.end());
      for (std::size_t i = 1; i + 1 < cycle.size(); ++i)
        table.triangles[config].push_back(
            {std::uint8_t(cycle[0]), std::uint8_t(cycle[i]), std::uint8_t(cycle[i + 1])});
    }
  }
  return table;
}

const CaseTable& Table() {
  static const CaseTable t = MakeCaseTable();
  return t;
}


// A tile's cells and nodes: n cells, nn nodes and nb blocks per axis; nodes indexed x fastest.
struct TileShape {
  std::array<int, 3> n, nn, nb;
  TileShape(const std::array<int, 3>& c0, const std::array<int, 3>& c1, int bc)
      : n{c1[0] - c0[0], c1[1] - c0[1], c1[2] - c0[2]},
        nn{n[0] + 1, n[1] + 1, n[2] + 1},
        nb{(n[0] + bc - 1) / bc, (n[1] + bc - 1) / bc, (n[2] + bc - 1) / bc} {}
  std::size_t local(int i, int j, int k) const {
    return std::size_t(i) + std::size_t(nn[0]) * (std::size_t(j) + std::size_t(nn[1]) * k);
  }
  std::size_t node_count() const { return std::size_t(nn[0]) * nn[1] * nn[2]; }
};

// The field at the nodes of the active blocks (NaN elsewhere), evaluated in one batch.
std::vector<double> TileNodeValues(const BatchField& field, const MeshLattice& l, const std::array<int, 3>& c0,
                                   const TileShape& s, int bc, const std::vector<char>& active, Counters& counters) {
  std::vector<char> needed(s.node_count(), 0);
  for (int bk = 0; bk < s.nb[2]; ++bk)
    for (int bj = 0; bj < s.nb[1]; ++bj)
      for (int bi = 0; bi < s.nb[0]; ++bi) {
        if (!active[std::size_t(bi) + std::size_t(s.nb[0]) * (bj + std::size_t(s.nb[1]) * bk)]) continue;
        for (int k = bk * bc; k <= std::min((bk + 1) * bc, s.n[2]); ++k)
          for (int j = bj * bc; j <= std::min((bj + 1) * bc, s.n[1]); ++j)
            for (int i = bi * bc; i <= std::min((bi + 1) * bc, s.n[0]); ++i) needed[s.local(i, j, k)] = 1;
      }
  std::vector<std::uint32_t> which;
  std::vector<Vec3> points;
  for (int k = 0; k < s.nn[2]; ++k)
    for (int j = 0; j < s.nn[1]; ++j)
      for (int i = 0; i < s.nn[0]; ++i)
        if (needed[s.local(i, j, k)]) {
          which.push_back(std::uint32_t(s.local(i, j, k)));
          points.push_back(l.node(c0[0] + i, c0[1] + j, c0[2] + k));
        }
  std::vector<double> value(s.node_count(), std::numeric_limits<double>::quiet_NaN());
  std::vector<double> v(points.size());
  Evaluate(field, points.data(), points.size(), v.data(), counters.nodes, counters);
  for (std::size_t i = 0; i < which.size(); ++i) value[which[i]] = v[i];
  return value;
}

// A crossing edge whose vertex is still to be placed: its ends, a on the side of value fa.
struct PendingVertex {
  Vec3 a, b;
  double fa, fb;
  int kept = 0;  // false position: the end the last step kept (+1 a, -1 b, 0 none yet)
};

// The triangles of the active cells by the case table into `out` (with each vertex's global edge
// id), one pending vertex per crossing edge; `band_flag` (when not empty) marks the nodes of
// crossing cells.
std::vector<PendingVertex> TileTriangles(const Geometry& geo, const std::array<int, 3>& c0, const TileShape& s, int bc,
                                         const std::vector<char>& active, const std::vector<double>& value,
                                         double iso, std::vector<char>& band_flag, TilePiece& out) {
  const MeshLattice& l = geo.lattice;
  const auto& E = Edges();
  const auto& table = Table();
  const bool want_band = !band_flag.empty();
  std::vector<std::int32_t> vertex_of(3 * s.node_count(), -1);
  std::vector<PendingVertex> pending;
  for (int k = 0; k < s.n[2]; ++k)
    for (int j = 0; j < s.n[1]; ++j)
      for (int i = 0; i < s.n[0]; ++i) {
        if (!active[std::size_t(i / bc) + std::size_t(s.nb[0]) * (j / bc + std::size_t(s.nb[1]) * (k / bc))]) continue;
        int config = 0;
        for (int c = 0; c < 8; ++c)
          config |= int(Inside(value[s.local(i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1))], iso)) << c;
        if (config == 0 || config == 255) continue;
        if (want_band)
          for (int c = 0; c < 8; ++c) band_flag[s.local(i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1))] = 1;
        std::array<std::int32_t, 12> vid;
        vid.fill(-1);
        for (const auto& tri : table.triangles[config]) {
          std::array<std::int32_t, 3> t;
          for (int v = 0; v < 3; ++v) {
            const int e = tri[v];
            if (vid[e] < 0) {
              const int c = E[e].c0;
              const int ni = i + (c & 1), nj = j + ((c >> 1) & 1), nk = k + ((c >> 2) & 1);
              const std::size_t key = 3 * s.local(ni, nj, nk) + std::size_t(E[e].axis);
              if (vertex_of[key] < 0) {
                vertex_of[key] = std::int32_t(pending.size());
                std::array<std::int64_t, 3> g{c0[0] + ni, c0[1] + nj, c0[2] + nk};
                out.vertex_edges.push_back(3 * geo.node_id(g[0], g[1], g[2]) + E[e].axis);
                const Vec3 a = l.node(g[0], g[1], g[2]);
                g[E[e].axis] += 1;
                const std::size_t other = s.local(ni + (E[e].axis == 0), nj + (E[e].axis == 1), nk + (E[e].axis == 2));
                pending.push_back({a, l.node(g[0], g[1], g[2]), value[s.local(ni, nj, nk)], value[other]});
              }
              vid[e] = vertex_of[key];
            }
            t[v] = vid[e];
          }
          out.triangles.push_back(t);
        }
      }
  return pending;
}

// Bisection on all crossing edges of the tile at once, then o.secant_steps false-position steps
// (Illinois variant: when a step keeps the same end as the step before, that end's value is moved
// halfway to iso, so that a bracket on a curved field still shrinks from both sides); each vertex is
// its edge's last evaluated point, or with o.bisection_interpolate or secant steps the point where
// the line through the last bracket's end values crosses iso (the midpoint when an end value is not
// finite). Every step costs one evaluation per open edge; false position needs no more state than
// the bracket, so seam edges stay bit-identical between tiles.
void BisectVertices(const BatchField& field, const MeshingOptions& o, std::vector<PendingVertex>& pending,
                    Counters& counters, TilePiece& out) {
  const double iso = field.iso;
  const std::size_t nv = pending.size();
  out.vertex_positions.resize(nv);
  for (std::size_t v = 0; v < nv; ++v) {  // with 0 steps: the edge's midpoint before interpolation
    const PendingVertex& p = pending[v];
    out.vertex_positions[v] = {0.5 * (p.a[0] + p.b[0]), 0.5 * (p.a[1] + p.b[1]), 0.5 * (p.a[2] + p.b[2])};
  }
  std::vector<char> done(nv, 0);
  std::vector<std::uint32_t> open;
  std::vector<Vec3> mid;
  std::vector<double> fm;
  // Where the line through the bracket's end values crosses iso (its midpoint when an end value is
  // not finite or both are equal).
  auto crossing = [iso](const PendingVertex& p) -> Vec3 {
    double t = 0.5;
    if (std::isfinite(p.fa) && std::isfinite(p.fb) && p.fa != p.fb) t = std::clamp((iso - p.fa) / (p.fb - p.fa), 0.0, 1.0);
    return {p.a[0] + t * (p.b[0] - p.a[0]), p.a[1] + t * (p.b[1] - p.a[1]), p.a[2] + t * (p.b[2] - p.a[2])};
  };
  for (int step = 0; step < o.bisection_steps + o.secant_steps; ++step) {
    const bool secant = step >= o.bisection_steps;
    open.clear();
    mid.clear();
    for (std::size_t v = 0; v < nv; ++v)
      if (!done[v]) {
        open.push_back(std::uint32_t(v));
        const PendingVertex& p = pending[v];
        mid.push_back(secant ? crossing(p)
                             : Vec3{0.5 * (p.a[0] + p.b[0]), 0.5 * (p.a[1] + p.b[1]), 0.5 * (p.a[2] + p.b[2])});
      }
    if (open.empty()) break;
    fm.resize(mid.size());
    Evaluate(field, mid.data(), mid.size(), fm.data(), counters.bisection, counters);
    for (std::size_t q = 0; q < open.size(); ++q) {
      PendingVertex& p = pending[open[q]];
      out.vertex_positions[open[q]] = mid[q];
      if (std::abs(fm[q] - iso) < o.bisection_tolerance) {
        done[open[q]] = 1;
        continue;
      }
      const int keep = Inside(fm[q], iso) == Inside(p.fa, iso) ? -1 : +1;  // the new point replaces a: b is kept
      if (keep < 0) {
        p.a = mid[q];
        p.fa = fm[q];
      } else {
        p.b = mid[q];
        p.fb = fm[q];
      }
      if (!secant) continue;
      if (keep == p.kept) {  // Illinois: the same end kept twice in a row
        double& f = keep > 0 ? p.fa : p.fb;
        if (std::isfinite(f)) f = iso + 0.5 * (f - iso);
      }
      p.kept = keep;
    }
  }
  if (!o.bisection_interpolate && o.secant_steps == 0) return;
  for (std::size_t v = 0; v < nv; ++v) {
    const PendingVertex& p = pending[v];
    if (done[v] || !std::isfinite(p.fa) || !std::isfinite(p.fb) || p.fa == p.fb) continue;
    out.vertex_positions[v] = crossing(p);
  }
}

// Meshes one tile. `active` (per block of the tile, x fastest) says which blocks to mesh.
void MeshTile(const BatchField& field, const MeshingOptions& o, const Geometry& geo, const std::array<int, 3>& c0,
              const std::array<int, 3>& c1, const std::vector<char>& active, bool want_band, Counters& counters,
              TilePiece& out) {
  const int bc = o.block_cells;
  const TileShape s(c0, c1, bc);
  const std::vector<double> value = TileNodeValues(field, geo.lattice, c0, s, bc, active, counters);
  std::vector<char> band_flag;
  if (want_band) band_flag.assign(s.node_count(), 0);
  std::vector<PendingVertex> pending = TileTriangles(geo, c0, s, bc, active, value, field.iso, band_flag, out);
  BisectVertices(field, o, pending, counters, out);
  if (want_band)
    for (int k = 0; k < s.nn[2]; ++k)
      for (int j = 0; j < s.nn[1]; ++j)
        for (int i = 0; i < s.nn[0]; ++i)
          if (band_flag[s.local(i, j, k)]) {
            const double v = value[s.local(i, j, k)];
            out.band_nodes.push_back({c0[0] + i, c0[1] + j, c0[2] + k});
            out.band_values.push_back(std::isfinite(v) ? float(std::clamp(v, -3.0e38, 3.0e38))
                                                       : (v < 0 ? -std::numeric_limits<float>::max()
                                                                : std::numeric_limits<float>::max()));
          }
}

}  // namespace

std::string MeshingOptions::Validate() const {
  auto pow2 = [](int v) { return v > 0 && (v & (v - 1)) == 0; };
  for (int a = 0; a < 3; ++a) {
    if (!std::isfinite(min_corner[a]) || !std::isfinite(max_corner[a])) return "box corners must be finite";
    if (!(max_corner[a] > min_corner[a])) return "box: max corner must exceed min corner on every axis";
  }
  if (auto why = CheckRange("resolution", SettingType::kInteger, resolution, kResolutionRange); !why.empty())
    return why;
  if (secant_steps < 0 || secant_steps > 8) return "secant steps must be in [0, 8]";
  // The vertex is interpolated in its last bracket with bisection_interpolate or secant steps: the
  // bisection steps may then be 0.
  const bool interpolated = bisection_interpolate || secant_steps > 0;
  if (bisection_steps < (interpolated ? 0 : 1) || bisection_steps > 60)
    return interpolated ? "bisection steps must be in [0, 60]"
                        : "bisection steps must be in [1, 60] (0 only with --bisection-interpolate or secant steps)";
  if (!(bisection_tolerance >= 0) || !std::isfinite(bisection_tolerance)) return "bisection tolerance must be finite and >= 0";
  if (!pow2(block_cells)) return "block cells must be a power of 2";
  if (!pow2(search_stride) || search_stride < block_cells) return "search stride must be a power of 2 >= block cells";
  if (tile_cells < block_cells || tile_cells > 256 || tile_cells % block_cells != 0)
    return "tile cells must be a multiple of block cells, at most 256";
  if (coarse_margin_cells < 0) return "coarse margin must be >= 0";
  if (search_min_cells < 1) return "search min cells must be >= 1";
  if (search_slab_nodes < 1 || follow_chunk_blocks < 1) return "search slab nodes and follow chunk blocks must be >= 1";
  if (!std::isfinite(search_value_margin)) return "search value margin must be finite (negative: the field's)";
  double longest = 0;
  for (int a = 0; a < 3; ++a) longest = std::max(longest, max_corner[a] - min_corner[a]);
  for (int a = 0; a < 3; ++a)
    if ((max_corner[a] - min_corner[a]) / longest * resolution > 65536) return "box too elongated";
  return {};
}

std::string MeshingSummary::report() const {
  std::ostringstream s;
  s << "lattice " << cells[0] << " x " << cells[1] << " x " << cells[2] << " cells of " << spacing << "\n"
    << "tiles meshed " << tiles_meshed << " of " << tiles_total << ", blocks " << blocks_active << " of "
    << blocks_total << "\n"
    << "field evaluations " << nodes_evaluated << " at nodes (" << search_evaluations << " in the search) + "
    << bisection_evaluations << " in bisection, non-finite " << non_finite_values << "\n"
    << "surface following " << follow_evaluations << " evaluations (in the search), " << blocks_followed
    << " blocks added\n"
    << "vertices " << vertices << ", triangles " << triangles << ", components " << components
    << ", open edges " << open_edges << " (" << open_edges_inside << " away from the box faces)\n"
    << "one-node specks " << (speck_removal ? "removed " + std::to_string(specks_removed) : std::string("kept"))
    << ", " << seconds << " s\n";
  return s.str();
}

MeshLattice LatticeFor(const MeshingOptions& o) {
  MeshLattice l;
  double longest = 0;
  for (int a = 0; a < 3; ++a) longest = std::max(longest, o.max_corner[a] - o.min_corner[a]);
  l.origin = o.min_corner;
  l.spacing = longest / o.resolution;
  for (int a = 0; a < 3; ++a) {
    const double cells = (o.max_corner[a] - o.min_corner[a]) / l.spacing;
    l.cells[a] = std::max(1, int(std::ceil(cells - 1e-9 * o.resolution)));
  }
  return l;
}


TilePlan PlanTiles(const BatchField& field, const MeshingOptions& o, const PointsEvaluator& search_evaluate) {
  if (auto why = o.Validate(); !why.empty()) throw Error("meshing: " + why);
  if (!field.evaluate) throw Error("meshing: the field has no evaluate function");
  if (!std::isfinite(field.iso)) throw Error("meshing: the iso value must be finite");
  const auto t0 = std::chrono::steady_clock::now();
  TilePlan plan;
  plan.options = o;
  plan.lattice = LatticeFor(o);
  const Geometry geo = GeometryFor(plan.lattice);
  Counters counters;
  const BlockGrid blocks = MakeBlocks(geo.lattice, o.block_cells);
  plan.blocks_total = blocks.count[0] * blocks.count[1] * blocks.count[2];

  // The coarsest stride: at most search_stride, and at least search_min_cells cells along the
  // longest side; dense when that leaves nothing to skip.
  int stride = o.search_stride;
  const int longest = std::max({geo.lattice.cells[0], geo.lattice.cells[1], geo.lattice.cells[2]});
  while (stride > 1 && longest / stride < o.search_min_cells) stride /= 2;
  plan.sparse = o.sparse && stride >= o.block_cells;
  plan.search_stride = plan.sparse ? stride : 0;

  // Active blocks, one bit each (sparse only).
  Bitmap active;
  if (plan.sparse) {
    SearchResult found = SearchBlocks(field, o, stride, geo, counters, search_evaluate);
    active = std::move(found.active);
    if (o.follow_surface)
      plan.blocks_followed = FollowSurface(field, o, geo, active, counters, search_evaluate, &found.finest);
  }
  plan.follow_evaluations = counters.follow;
  plan.search_evaluations = counters.search + counters.follow;
  plan.search_non_finite = counters.non_finite;

  // Tiles, ascending, each with its active blocks ascending.
  const int T = o.tile_cells, per = T / o.block_cells;
  for (int a = 0; a < 3; ++a) plan.tiles[a] = (geo.lattice.cells[a] + T - 1) / T;
  if (plan.sparse) {
    std::vector<std::int64_t> ids;
    for (std::int64_t t = 0; t < plan.tiles_total(); ++t) {
      const std::int64_t tx = t % plan.tiles[0], ty = (t / plan.tiles[0]) % plan.tiles[1],
                         tz = t / (plan.tiles[0] * plan.tiles[1]);
      ids.clear();
      for (std::int64_t k = tz * per; k < std::min<std::int64_t>((tz + 1) * per, blocks.count[2]); ++k)
        for (std::int64_t j = ty * per; j < std::min<std::int64_t>((ty + 1) * per, blocks.count[1]); ++j) {
          const std::int64_t row = blocks.id(0, j, k);
          active.for_each(row + tx * per, row + std::min<std::int64_t>((tx + 1) * per, blocks.count[0]),
                          [&](std::int64_t id) {
                            ids.push_back(id);
                            return true;
                          });
        }
      if (ids.empty()) continue;
      plan.tile_ids.push_back(t);
      plan.tile_blocks.emplace_back(ids);
    }
  } else {
    plan.tile_ids.resize(std::size_t(plan.tiles_total()));
    for (std::int64_t t = 0; t < plan.tiles_total(); ++t) plan.tile_ids[std::size_t(t)] = t;
  }
  plan.search_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return plan;
}

TilePiece MeshTilePiece(const BatchField& field, const TilePlan& plan, std::size_t index, bool want_band) {
  if (index >= plan.tile_ids.size()) throw Error("meshing: tile index out of range");
  const MeshingOptions& o = plan.options;
  const Geometry geo = GeometryFor(plan.lattice);
  const BlockGrid blocks = MakeBlocks(geo.lattice, o.block_cells);
  const int T = o.tile_cells, per = T / o.block_cells;
  const std::int64_t t = plan.tile_ids[index];
  const auto& tiles = plan.tiles;
  const std::array<std::int64_t, 3> tc{t % tiles[0], (t / tiles[0]) % tiles[1], t / (tiles[0] * tiles[1])};
  std::array<int, 3> c0, c1, nb;
  for (int a = 0; a < 3; ++a) {
    c0[a] = int(tc[a] * T);
    c1[a] = std::min(c0[a] + T, geo.lattice.cells[a]);
    nb[a] = (c1[a] - c0[a] + o.block_cells - 1) / o.block_cells;
  }
  std::vector<char> active(std::size_t(nb[0]) * nb[1] * nb[2], plan.sparse ? 0 : 1);
  if (plan.sparse)
    for (std::int64_t id : plan.tile_blocks[index]) {
      const auto c = blocks.coords(id);
      active[std::size_t(c[0] - tc[0] * per) +
             std::size_t(nb[0]) * std::size_t((c[1] - tc[1] * per) + nb[1] * (c[2] - tc[2] * per))] = 1;
    }
  TilePiece piece;
  piece.tile = t;
  for (char a : active) piece.blocks_active += a;
  Counters counters;
  MeshTile(field, o, geo, c0, c1, active, want_band, counters, piece);
  piece.nodes_evaluated = counters.nodes;
  piece.bisection_evaluations = counters.bisection;
  piece.non_finite_values = counters.non_finite;
  return piece;
}


TriangleMesh WeldTilePieces(const TilePlan& plan, std::vector<TilePiece>& pieces, MeshingSummary* summary,
                            FieldBand* band) {
  if (pieces.size() != plan.tile_ids.size()) throw Error("meshing: weld: expected one piece per planned tile");
  for (std::size_t i = 0; i < pieces.size(); ++i)
    if (pieces[i].tile != plan.tile_ids[i]) throw Error("meshing: weld: pieces out of tile order");
  // One vertex per edge id, sorted by id.
  std::size_t total_refs = 0, total_tris = 0;
  std::int64_t nodes = 0, bisection = 0, non_finite = 0, blocks_active = 0;
  for (const auto& r : pieces) {
    total_refs += r.vertex_edges.size();
    total_tris += r.triangles.size();
    nodes += r.nodes_evaluated;
    bisection += r.bisection_evaluations;
    non_finite += r.non_finite_values;
    blocks_active += r.blocks_active;
  }
  std::vector<std::int64_t> edges;
  edges.reserve(total_refs);
  for (const auto& r : pieces) edges.insert(edges.end(), r.vertex_edges.begin(), r.vertex_edges.end());
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  edges.shrink_to_fit();
  TriangleMesh mesh;
  mesh.vertices.resize(edges.size());
  mesh.triangles.resize(total_tris);
  std::vector<std::size_t> tri_offset(pieces.size() + 1, 0);
  for (std::size_t r = 0; r < pieces.size(); ++r) tri_offset[r + 1] = tri_offset[r] + pieces[r].triangles.size();
#pragma omp parallel for schedule(dynamic)
  for (std::int64_t ri = 0; ri < std::int64_t(pieces.size()); ++ri) {
    TilePiece& r = pieces[std::size_t(ri)];
    std::vector<int> global(r.vertex_edges.size());
    for (std::size_t v = 0; v < r.vertex_edges.size(); ++v) {
      const std::size_t g = std::size_t(std::lower_bound(edges.begin(), edges.end(), r.vertex_edges[v]) - edges.begin());
      global[v] = int(g);
      mesh.vertices[g] = r.vertex_positions[v];  // identical from every tile that has it
    }
    std::size_t at = tri_offset[std::size_t(ri)];
    for (const auto& t : r.triangles) mesh.triangles[at++] = {global[t[0]], global[t[1]], global[t[2]]};
    r.vertex_edges = {};
    r.vertex_positions = {};
    r.triangles = {};
  }
  const std::int64_t specks = plan.options.remove_specks ? RemoveNodeSpecks(plan.lattice, edges, mesh) : 0;
  const LatticeMeshFacts facts = summary ? AnalyzeLatticeMesh(plan.lattice, edges, mesh) : LatticeMeshFacts{};
  if (band) {
    band->lattice = plan.lattice;
    band->nodes.clear();
    band->values.clear();
    for (auto& r : pieces) {
      band->nodes.insert(band->nodes.end(), r.band_nodes.begin(), r.band_nodes.end());
      band->values.insert(band->values.end(), r.band_values.begin(), r.band_values.end());
      r.band_nodes = {};
      r.band_values = {};
    }
  }
  if (summary) {
    MeshingSummary& s = *summary;
    s.nodes_evaluated = plan.search_evaluations + nodes;
    s.bisection_evaluations = bisection;
    s.non_finite_values = plan.search_non_finite + non_finite;
    s.search_evaluations = plan.search_evaluations;
    s.tiles_total = plan.tiles_total();
    s.tiles_meshed = std::int64_t(plan.tile_ids.size());
    s.blocks_total = plan.blocks_total;
    s.blocks_active = blocks_active;
    s.specks_removed = specks;
    s.speck_removal = plan.options.remove_specks;
    s.follow_evaluations = plan.follow_evaluations;
    s.blocks_followed = plan.blocks_followed;
    s.open_edges = facts.open_edges;
    s.open_edges_inside = facts.open_edges_inside;
    s.components = facts.components;
    s.vertices = std::int64_t(mesh.vertices.size());
    s.triangles = std::int64_t(mesh.triangles.size());
    s.cells = plan.lattice.cells;
    s.search_stride = plan.search_stride;
    s.spacing = plan.lattice.spacing;
  }
  return mesh;
}

TriangleMesh MeshField(const BatchField& field, const MeshingOptions& options, MeshingSummary* summary) {
  return MeshField(field, options, summary, nullptr);
}

TriangleMesh MeshField(const BatchField& field, const MeshingOptions& o, MeshingSummary* summary, FieldBand* band) {
  const auto t0 = std::chrono::steady_clock::now();
  const TilePlan plan = PlanTiles(field, o);
  std::vector<TilePiece> pieces(plan.tile_ids.size());
  Progress progress("mesh: tiles", double(pieces.size()), !o.show_progress);
  std::int64_t tiles_done = 0;
  const bool want_band = band != nullptr;
#pragma omp parallel for schedule(dynamic)
  for (std::int64_t ti = 0; ti < std::int64_t(pieces.size()); ++ti) {
    pieces[std::size_t(ti)] = MeshTilePiece(field, plan, std::size_t(ti), want_band);
#pragma omp critical(quijibo_mesh_progress)
    {
      ++tiles_done;
      progress.update(double(tiles_done), std::to_string(tiles_done) + " of " + std::to_string(pieces.size()) + " tiles");
    }
  }
  progress.finish();
  TriangleMesh mesh = WeldTilePieces(plan, pieces, summary, band);
  if (summary) summary->seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return mesh;
}

}  // namespace quijibo::mesh
