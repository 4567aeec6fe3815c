// The sparse search of the mesher (docs/meshing.md): a coarse-to-fine block search on corner values,
// then surface following, which meshes the neighbour across every block face the surface crosses.
#include <limits>
#include <string>
#include <unordered_map>

#include "mesh/mesher_internal.h"
#include "util/error.h"
#include "util/progress.h"

namespace quijibo::mesh::mesher {

namespace {

// Evaluates `points` with the external evaluator or in parallel, counting into `counter`.
void EvaluatePoints(const BatchField& field, const std::vector<Vec3>& points, std::vector<double>& values,
                    std::atomic<std::int64_t>& counter, Counters& counters, const PointsEvaluator& external) {
  if (external) {
    external(points, values);
    if (values.size() != points.size()) throw Error("meshing: the search evaluator returned a wrong count");
    std::int64_t bad = 0;
    for (double v : values) bad += !std::isfinite(v);
    counters.non_finite += bad;
  } else {
    values.assign(points.size(), 0.0);
    const std::int64_t chunk = 2048, n = std::int64_t(points.size());
    const std::int64_t chunks = (n + chunk - 1) / chunk;
    std::atomic<std::int64_t> ignored{0};
#pragma omp parallel for schedule(dynamic)
    for (std::int64_t c = 0; c < chunks; ++c) {
      const std::int64_t b = c * chunk, e = std::min(n, b + chunk);
      Evaluate(field, points.data() + b, std::size_t(e - b), values.data() + b, ignored, counters);
    }
  }
  counter += std::int64_t(points.size());
  counters.nodes += std::int64_t(points.size());
}

}  // namespace

// The sparse search: returns the sorted ids of the active blocks of `block_cells`.
std::vector<std::int64_t> SearchBlocks(const BatchField& field, const MeshingOptions& o, int first_stride,
                                       const Geometry& geo, Counters& counters, const PointsEvaluator& external,
                                       NodeValues* finest) {
  const MeshLattice& l = geo.lattice;
  std::vector<std::int64_t> candidates;  // block ids at the current stride
  int stride = first_stride;
  {
    const BlockGrid g = MakeBlocks(l, stride);
    candidates.resize(std::size_t(g.count[0] * g.count[1] * g.count[2]));
    for (std::size_t i = 0; i < candidates.size(); ++i) candidates[i] = std::int64_t(i);
  }
  const double value_margin = o.search_value_margin >= 0 ? o.search_value_margin : field.value_margin;
  Progress progress("mesh: sparse search", 1.0, !o.show_progress);
  double done = 0.0;
  // The previous level's nodes and values, sorted by node id: every corner of a coarse block is a
  // corner of its children, so about one in eight nodes of a level is known already. A node's
  // value does not depend on its batch, so reusing it changes nothing.
  std::vector<std::int64_t> known_keys;
  std::vector<double> known_values;
  for (;;) {
    const BlockGrid g = MakeBlocks(l, stride);
    // Corner nodes of the candidates, sorted and unique: marked on a bitmap of the level's corners
    // (node ids grow with the corner indices) rather than listed once per block and sorted, which on
    // porous sets took 8 ids per candidate block (docs/benchmarks.md §26).
    auto corner = [&](std::int64_t b, int a, int bit) { return std::min<std::int64_t>((b + bit) * stride, l.cells[a]); };
    std::vector<std::int64_t> keys;
    {
      const std::int64_t cx = g.count[0] + 1, cy = g.count[1] + 1, cz = g.count[2] + 1;
      std::vector<bool> on(std::size_t(cx * cy * cz), false);
      for (std::int64_t id : candidates) {
        const auto c = g.coords(id);
        for (int v = 0; v < 8; ++v)
          on[std::size_t((c[0] + (v & 1)) + cx * ((c[1] + ((v >> 1) & 1)) + cy * (c[2] + ((v >> 2) & 1))))] = true;
      }
      std::size_t n = 0;
      for (bool b : on) n += b;
      keys.reserve(n);
      for (std::int64_t k = 0, at = 0; k < cz; ++k)
        for (std::int64_t j = 0; j < cy; ++j)
          for (std::int64_t i = 0; i < cx; ++i, ++at)
            if (on[std::size_t(at)]) keys.push_back(geo.node_id(corner(i, 0, 0), corner(j, 1, 0), corner(k, 2, 0)));
    }
    std::vector<double> values(keys.size());
    {
      std::vector<std::size_t> fresh;  // indices into keys of the nodes not known yet
      for (std::size_t i = 0; i < keys.size(); ++i) {
        const auto it = std::lower_bound(known_keys.begin(), known_keys.end(), keys[i]);
        if (it != known_keys.end() && *it == keys[i]) values[i] = known_values[std::size_t(it - known_keys.begin())];
        else fresh.push_back(i);
      }
      std::vector<Vec3> points(fresh.size());
      for (std::size_t i = 0; i < fresh.size(); ++i) {
        const std::int64_t k = keys[fresh[i]];
        points[i] = l.node(k % geo.nodes[0], (k / geo.nodes[0]) % geo.nodes[1], k / (geo.nodes[0] * geo.nodes[1]));
      }
      std::vector<double> fresh_values;
      if (!points.empty()) EvaluatePoints(field, points, fresh_values, counters.search, counters, external);
      for (std::size_t i = 0; i < fresh.size(); ++i) values[fresh[i]] = fresh_values[i];
    }
    auto value_of = [&](std::int64_t key) {
      return values[std::size_t(std::lower_bound(keys.begin(), keys.end(), key) - keys.begin())];
    };
    // Crossing blocks.
    std::vector<std::int64_t> crossing;
    for (std::int64_t id : candidates) {
      const auto c = g.coords(id);
      int in = 0;
      double nearest = std::numeric_limits<double>::infinity();  // smallest |f - iso| at a corner
      for (int v = 0; v < 8; ++v) {
        const double f = value_of(geo.node_id(corner(c[0], 0, v & 1), corner(c[1], 1, (v >> 1) & 1),
                                              corner(c[2], 2, (v >> 2) & 1)));
        in += Inside(f, field.iso);
        if (std::isfinite(f)) nearest = std::min(nearest, std::abs(f - field.iso));
      }
      // Same-side corners close to iso may hide a speck smaller than the block: keep it too.
      if ((in != 0 && in != 8) || nearest < value_margin) crossing.push_back(id);
    }
    // Dilate by the margin (at least one block).
    const int m = std::max(1, (o.coarse_margin_cells + stride - 1) / stride);
    std::vector<std::int64_t> marked;  // sorted and unique, through a bitmap of the level's blocks
    {
      std::vector<bool> on(std::size_t(g.count[0] * g.count[1] * g.count[2]), false);
      for (std::int64_t id : crossing) {
        const auto c = g.coords(id);
        for (std::int64_t dk = -m; dk <= m; ++dk)
          for (std::int64_t dj = -m; dj <= m; ++dj)
            for (std::int64_t di = -m; di <= m; ++di) {
              const std::int64_t i = c[0] + di, j = c[1] + dj, k = c[2] + dk;
              if (i < 0 || j < 0 || k < 0 || i >= g.count[0] || j >= g.count[1] || k >= g.count[2]) continue;
              on[std::size_t(g.id(i, j, k))] = true;
            }
      }
      crossing = {};
      std::size_t n = 0;
      for (bool b : on) n += b;
      marked.reserve(n);
      for (std::size_t id = 0; id < on.size(); ++id)
        if (on[id]) marked.push_back(std::int64_t(id));
    }
    done = 0.5 * (done + 1.0);
    progress.update(done, std::to_string(marked.size()) + " blocks of " + std::to_string(stride) + " cells");
    if (stride == o.block_cells) {
      progress.finish();
      if (finest) finest->keys = std::move(keys), finest->values = std::move(values);
      return marked;
    }
    // Children at half the stride.
    const int half = stride / 2;
    const BlockGrid child = MakeBlocks(l, half);
    candidates.clear();
    for (std::int64_t id : marked) {
      const auto c = g.coords(id);
      for (int v = 0; v < 8; ++v) {
        const std::int64_t i = 2 * c[0] + (v & 1), j = 2 * c[1] + ((v >> 1) & 1), k = 2 * c[2] + ((v >> 2) & 1);
        if (i < child.count[0] && j < child.count[1] && k < child.count[2]) candidates.push_back(child.id(i, j, k));
      }
    }
    std::sort(candidates.begin(), candidates.end());
    stride = half;
    known_keys.swap(keys);
    known_values.swap(values);
  }
}

std::int64_t FollowSurface(const BatchField& field, const MeshingOptions& o, const Geometry& geo,
                           std::vector<std::int64_t>& active, Counters& counters, const PointsEvaluator& external,
                           const NodeValues* seed) {
  const MeshLattice& l = geo.lattice;
  const BlockGrid g = MakeBlocks(l, o.block_cells);
  const std::int64_t bc = o.block_cells;
  // Values of the face nodes seen so far (a face is shared by rounds and by neighbouring faces).
  std::unordered_map<std::int64_t, double> known;
  if (seed)
    for (std::size_t i = 0; i < seed->keys.size(); ++i) known.emplace(seed->keys[i], seed->values[i]);
  std::vector<std::int64_t> frontier = active;  // blocks whose faces are not checked yet
  std::int64_t added = 0;
  struct Face {
    std::array<std::int64_t, 3> lo, hi;  // node ranges, inclusive (one axis flat)
    std::int64_t neighbour;
  };
  std::vector<Face> faces;
  std::vector<std::int64_t> keys, next;
  auto for_each_node = [&](const Face& f, auto&& visit) {
    for (std::int64_t k = f.lo[2]; k <= f.hi[2]; ++k)
      for (std::int64_t j = f.lo[1]; j <= f.hi[1]; ++j)
        for (std::int64_t i = f.lo[0]; i <= f.hi[0]; ++i) visit(geo.node_id(i, j, k));
  };
  while (!frontier.empty()) {
    // The faces of the frontier blocks towards inactive blocks, and their nodes not seen yet.
    faces.clear();
    keys.clear();
    for (std::int64_t id : frontier) {
      const auto c = g.coords(id);
      for (int a = 0; a < 3; ++a)
        for (int side = 0; side < 2; ++side) {
          auto nc = c;
          nc[a] += side ? 1 : -1;
          if (nc[a] < 0 || nc[a] >= g.count[a]) continue;  // a box face: nothing beyond
          const std::int64_t n = g.id(nc[0], nc[1], nc[2]);
          if (std::binary_search(active.begin(), active.end(), n)) continue;
          Face f;
          for (int b = 0; b < 3; ++b) {
            f.lo[b] = c[b] * bc;
            f.hi[b] = std::min<std::int64_t>((c[b] + 1) * bc, l.cells[b]);
          }
          if (side) f.lo[a] = f.hi[a];
          else f.hi[a] = f.lo[a];
          f.neighbour = n;
          faces.push_back(f);
          for_each_node(f, [&](std::int64_t key) {
            if (!known.count(key)) keys.push_back(key);
          });
        }
    }
    std::sort(keys.begin(), keys.end());
    keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
    if (!keys.empty()) {
      std::vector<Vec3> points(keys.size());
      for (std::size_t i = 0; i < keys.size(); ++i) {
        const std::int64_t k = keys[i];
        points[i] = l.node(k % geo.nodes[0], (k / geo.nodes[0]) % geo.nodes[1], k / (geo.nodes[0] * geo.nodes[1]));
      }
      std::vector<double> values;
      EvaluatePoints(field, points, values, counters.follow, counters, external);
      for (std::size_t i = 0; i < keys.size(); ++i) known.emplace(keys[i], values[i]);
    }
    // A face with nodes on both sides has mesh edges on it: the block across it must be meshed.
    next.clear();
    for (const Face& f : faces) {
      int in = 0, total = 0;
      for_each_node(f, [&](std::int64_t key) {
        in += Inside(known.at(key), field.iso);
        ++total;
      });
      if (in != 0 && in != total) next.push_back(f.neighbour);
    }
    std::sort(next.begin(), next.end());
    next.erase(std::unique(next.begin(), next.end()), next.end());
    const std::size_t old = active.size();
    active.insert(active.end(), next.begin(), next.end());
    std::inplace_merge(active.begin(), active.begin() + std::ptrdiff_t(old), active.end());
    added += std::int64_t(next.size());
    frontier.swap(next);
  }
  return added;
}

}  // namespace quijibo::mesh::mesher
