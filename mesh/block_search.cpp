// The sparse search of the mesher (docs/meshing.md): a coarse-to-fine block search on corner values,
// then surface following, which meshes the neighbour across every block face the surface crosses.
// Both hold their sets as bitmaps and take their nodes a slab (search) or a chunk (following) at a
// time, so that their memory grows as the box's volume in bits, not in listed ids and values.
#include <limits>
#include <string>

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

// A level's corner grid: corner c of axis a is lattice node min(c stride, cells[a]), so corner ids
// (x fastest) grow with node ids.
struct CornerGrid {
  int stride = 1;
  std::array<std::int64_t, 3> count{0, 0, 0}, cells{0, 0, 0};
  std::int64_t size() const { return count[0] * count[1] * count[2]; }
  std::int64_t id(std::int64_t i, std::int64_t j, std::int64_t k) const { return i + count[0] * (j + count[1] * k); }
  std::int64_t node(std::int64_t c, int a) const { return std::min<std::int64_t>(c * stride, cells[a]); }
  // The corner at lattice node coordinate x of axis a, or -1 when x is none.
  std::int64_t corner_of(std::int64_t x, int a) const {
    if (x == cells[a]) return count[a] - 1;
    return x % stride == 0 ? x / stride : -1;
  }
};

CornerGrid CornersOf(const BlockGrid& g, const MeshLattice& l) {
  CornerGrid c;
  c.stride = g.stride;
  for (int a = 0; a < 3; ++a) c.count[a] = g.count[a] + 1, c.cells[a] = l.cells[a];
  return c;
}

// Values at some corners of one level, appended in ascending corner id, found again by rank.
class LevelValues {
 public:
  LevelValues() = default;
  explicit LevelValues(const CornerGrid& grid) : grid_(grid), has_(grid.size()) {}
  const CornerGrid& grid() const { return grid_; }
  void append(std::int64_t id, double v) {
    has_.set(id);
    values_.push_back(v);
  }
  void finish() {
    const auto& w = has_.words();
    rank_.resize(w.size());
    std::int64_t r = 0;
    for (std::size_t i = 0; i < w.size(); ++i) rank_[i] = r, r += __builtin_popcountll(w[i]);
  }
  bool find(std::int64_t id, double* v) const {
    if (!has_.test(id)) return false;
    const std::uint64_t word = has_.words()[std::size_t(id >> 6)];
    const std::uint64_t below = word & ((std::uint64_t(1) << (id & 63)) - 1);
    *v = values_[std::size_t(rank_[std::size_t(id >> 6)] + __builtin_popcountll(below))];
    return true;
  }
  bool empty() const { return values_.empty(); }

 private:
  CornerGrid grid_;
  Bitmap has_;
  std::vector<double> values_;
  std::vector<std::int64_t> rank_;
};

// Node ids with their side (inside or not), open addressing: the following's face nodes that are
// not corners of the search, 8 bytes each at half load.
class NodeSides {
 public:
  NodeSides() : slots_(1024, 0) {}
  // 1 inside, 0 outside, -1 unknown.
  int find(std::int64_t key) const {
    for (std::size_t s = slot(key);; s = (s + 1) & (slots_.size() - 1)) {
      const std::uint64_t e = slots_[s];
      if (e == 0) return -1;
      if (std::int64_t((e - 1) >> 1) == key) return int((e - 1) & 1);
    }
  }
  void insert(std::int64_t key, bool inside) {
    if (2 * (size_ + 1) > slots_.size()) grow();
    put(std::uint64_t(key) * 2 + (inside ? 1 : 0) + 1);
    ++size_;
  }

 private:
  std::size_t slot(std::int64_t key) const {
    return std::size_t((std::uint64_t(key) * 0x9E3779B97F4A7C15ull) >> (64 - bits_));
  }
  void put(std::uint64_t e) {
    std::size_t s = slot(std::int64_t((e - 1) >> 1));
    while (slots_[s] != 0) s = (s + 1) & (slots_.size() - 1);
    slots_[s] = e;
  }
  void grow() {
    std::vector<std::uint64_t> old;
    old.swap(slots_);
    slots_.assign(old.size() * 2, 0);
    ++bits_;
    for (std::uint64_t e : old)
      if (e) put(e);
  }
  std::vector<std::uint64_t> slots_;
  int bits_ = 10;
  std::size_t size_ = 0;
};

}  // namespace

SearchResult SearchBlocks(const BatchField& field, const MeshingOptions& o, int first_stride, const Geometry& geo,
                          Counters& counters, const PointsEvaluator& external) {
  const MeshLattice& l = geo.lattice;
  int stride = first_stride;
  Bitmap candidates;  // blocks of the current stride
  {
    const BlockGrid g = MakeBlocks(l, stride);
    candidates = Bitmap(g.count[0] * g.count[1] * g.count[2]);
    for (std::int64_t i = 0; i < candidates.size(); ++i) candidates.set(i);
  }
  const double value_margin = o.search_value_margin >= 0 ? o.search_value_margin : field.value_margin;
  Progress progress("mesh: sparse search", 1.0, !o.show_progress);
  double done = 0.0;
  LevelValues previous;  // the coarser level's values, reused at its corners
  SearchResult result;
  for (;;) {
    const BlockGrid g = MakeBlocks(l, stride);
    const CornerGrid cg = CornersOf(g, l);
    const bool finest = stride == o.block_cells;
    LevelValues current = finest ? LevelValues() : LevelValues(cg);
    if (finest) {
      result.finest.corners = cg.count;
      result.finest.known = Bitmap(cg.size());
      result.finest.inside = Bitmap(cg.size());
    }
    auto store = [&](std::int64_t id, double v) {
      if (!finest) return current.append(id, v);
      result.finest.known.set(id);
      if (Inside(v, field.iso)) result.finest.inside.set(id);
    };
    // The coarser level's value at this level's corner (i, j, k), when it has one.
    auto reuse = [&](std::int64_t i, std::int64_t j, std::int64_t k, double* v) {
      if (previous.empty()) return false;
      const CornerGrid& pg = previous.grid();
      const std::int64_t pi = pg.corner_of(cg.node(i, 0), 0), pj = pg.corner_of(cg.node(j, 1), 1),
                         pk = pg.corner_of(cg.node(k, 2), 2);
      return pi >= 0 && pj >= 0 && pk >= 0 && previous.find(pg.id(pi, pj, pk), v);
    };
    Bitmap crossing(candidates.size());
    // Slabs of block layers [k0, k1), whose corners are the corner layers [k0, k1]; the last corner
    // layer is carried to the next slab, whose first layer it is, and stored once complete.
    const std::int64_t layer = cg.count[0] * cg.count[1];
    const std::int64_t slab = std::max<std::int64_t>(1, o.search_slab_nodes / layer - 1);
    Bitmap need, carry_need(layer);
    std::vector<double> value, carry_value = std::vector<double>(std::size_t(layer));
    std::vector<std::int64_t> fresh;
    std::vector<Vec3> points;
    std::vector<double> fresh_values;
    for (std::int64_t k0 = 0; k0 < g.count[2]; k0 += slab) {
      const std::int64_t k1 = std::min(g.count[2], k0 + slab), layers = k1 - k0 + 1;
      need = Bitmap(layers * layer);
      value.assign(std::size_t(layers * layer), 0.0);
      // Local corner id: (i, j, k - k0); the first layer's known corners come from the carry.
      auto local = [&](std::int64_t i, std::int64_t j, std::int64_t k) { return i + cg.count[0] * (j + cg.count[1] * (k - k0)); };
      carry_need.for_each(0, layer, [&](std::int64_t a) {
        need.set(a);
        return true;
      });
      const std::int64_t block_layer = g.count[0] * g.count[1];
      candidates.for_each(k0 * block_layer, k1 * block_layer, [&](std::int64_t id) {
        const auto c = g.coords(id);
        for (int v = 0; v < 8; ++v) need.set(local(c[0] + (v & 1), c[1] + ((v >> 1) & 1), c[2] + ((v >> 2) & 1)));
        return true;
      });
      fresh.clear();
      need.for_each(0, need.size(), [&](std::int64_t at) {
        const std::int64_t i = at % cg.count[0], j = (at / cg.count[0]) % cg.count[1], k = k0 + at / layer;
        if (k == k0 && carry_need.test(at)) value[std::size_t(at)] = carry_value[std::size_t(at)];
        else if (!reuse(i, j, k, &value[std::size_t(at)])) fresh.push_back(at);
        return true;
      });
      points.resize(fresh.size());
      for (std::size_t n = 0; n < fresh.size(); ++n) {
        const std::int64_t at = fresh[n];
        const std::int64_t i = at % cg.count[0], j = (at / cg.count[0]) % cg.count[1], k = k0 + at / layer;
        points[n] = l.node(cg.node(i, 0), cg.node(j, 1), cg.node(k, 2));
      }
      if (!points.empty()) {
        EvaluatePoints(field, points, fresh_values, counters.search, counters, external);
        for (std::size_t n = 0; n < fresh.size(); ++n) value[std::size_t(fresh[n])] = fresh_values[n];
      }
      // Crossing blocks: corners on both sides, or same-side corners close enough to iso to hide a
      // speck smaller than the block.
      candidates.for_each(k0 * block_layer, k1 * block_layer, [&](std::int64_t id) {
        const auto c = g.coords(id);
        int in = 0;
        double nearest = std::numeric_limits<double>::infinity();  // smallest |f - iso| at a corner
        for (int v = 0; v < 8; ++v) {
          const double f = value[std::size_t(local(c[0] + (v & 1), c[1] + ((v >> 1) & 1), c[2] + ((v >> 2) & 1)))];
          in += Inside(f, field.iso);
          if (std::isfinite(f)) nearest = std::min(nearest, std::abs(f - field.iso));
        }
        if ((in != 0 && in != 8) || nearest < value_margin) crossing.set(id);
        return true;
      });
      // Store the complete corner layers (all but the last, unless this is the last slab), ascending.
      const bool last = k1 == g.count[2];
      need.for_each(0, last ? need.size() : (layers - 1) * layer, [&](std::int64_t at) {
        store(at + k0 * layer, value[std::size_t(at)]);
        return true;
      });
      carry_need = Bitmap(layer);
      need.for_each((layers - 1) * layer, need.size(), [&](std::int64_t at) {
        const std::int64_t a = at - (layers - 1) * layer;
        carry_need.set(a);
        carry_value[std::size_t(a)] = value[std::size_t(at)];
        return true;
      });
      progress.update(done + (1.0 - done) * 0.5 * double(k1) / double(g.count[2]),
                      "blocks of " + std::to_string(stride) + " cells");
    }
    if (!finest) current.finish();
    previous = LevelValues();
    candidates = Bitmap();
    // Dilate by the margin (at least one block).
    const int m = std::max(1, (o.coarse_margin_cells + stride - 1) / stride);
    Bitmap marked(crossing.size());
    crossing.for_each(0, crossing.size(), [&](std::int64_t id) {
      const auto c = g.coords(id);
      for (std::int64_t dk = -m; dk <= m; ++dk)
        for (std::int64_t dj = -m; dj <= m; ++dj)
          for (std::int64_t di = -m; di <= m; ++di) {
            const std::int64_t i = c[0] + di, j = c[1] + dj, k = c[2] + dk;
            if (i < 0 || j < 0 || k < 0 || i >= g.count[0] || j >= g.count[1] || k >= g.count[2]) continue;
            marked.set(g.id(i, j, k));
          }
      return true;
    });
    crossing = Bitmap();
    done = 0.5 * (done + 1.0);
    progress.update(done, std::to_string(marked.count()) + " blocks of " + std::to_string(stride) + " cells");
    if (finest) {
      progress.finish();
      result.active = std::move(marked);
      return result;
    }
    // Children at half the stride.
    const int half = stride / 2;
    const BlockGrid child = MakeBlocks(l, half);
    candidates = Bitmap(child.count[0] * child.count[1] * child.count[2]);
    marked.for_each(0, marked.size(), [&](std::int64_t id) {
      const auto c = g.coords(id);
      for (int v = 0; v < 8; ++v) {
        const std::int64_t i = 2 * c[0] + (v & 1), j = 2 * c[1] + ((v >> 1) & 1), k = 2 * c[2] + ((v >> 2) & 1);
        if (i < child.count[0] && j < child.count[1] && k < child.count[2]) candidates.set(child.id(i, j, k));
      }
      return true;
    });
    stride = half;
    previous = std::move(current);
  }
}

std::int64_t FollowSurface(const BatchField& field, const MeshingOptions& o, const Geometry& geo, Bitmap& active,
                           Counters& counters, const PointsEvaluator& external, const CornerSigns* seed) {
  const MeshLattice& l = geo.lattice;
  const BlockGrid g = MakeBlocks(l, o.block_cells);
  const CornerGrid cg = CornersOf(g, l);
  const std::int64_t bc = o.block_cells;
  if (seed && seed->corners != cg.count) throw Error("meshing: the search's corner signs do not fit the blocks");
  NodeSides sides;  // the face nodes evaluated here
  // The side of node (i, j, k) of id `key` when known: 1 inside, 0 outside, -1 unknown.
  auto side_of = [&](std::int64_t key, std::int64_t i, std::int64_t j, std::int64_t k) {
    if (seed) {
      const std::int64_t ci = cg.corner_of(i, 0), cj = cg.corner_of(j, 1), ck = cg.corner_of(k, 2);
      if (ci >= 0 && cj >= 0 && ck >= 0) {
        const std::int64_t c = cg.id(ci, cj, ck);
        if (seed->known.test(c)) return int(seed->inside.test(c));
      }
    }
    return sides.find(key);
  };
  struct Face {
    std::array<std::int64_t, 3> lo, hi;  // node ranges, inclusive (one axis flat)
    std::int64_t neighbour;
  };
  auto for_each_node = [&](const Face& f, auto&& visit) {
    for (std::int64_t k = f.lo[2]; k <= f.hi[2]; ++k)
      for (std::int64_t j = f.lo[1]; j <= f.hi[1]; ++j)
        for (std::int64_t i = f.lo[0]; i <= f.hi[0]; ++i) visit(geo.node_id(i, j, k), i, j, k);
  };
  std::vector<Face> faces;
  std::vector<std::int64_t> keys, chunk;
  std::vector<Vec3> points;
  std::vector<double> values;
  Bitmap frontier = active;  // blocks whose faces are not checked yet
  std::int64_t added = 0;
  while (frontier.any()) {
    // Active does not change during a round, so the chunks see what one pass over the frontier would.
    Bitmap next(active.size());
    auto check = [&]() {
      // The faces of the chunk's blocks towards inactive blocks, and their nodes not known yet.
      faces.clear();
      keys.clear();
      for (std::int64_t id : chunk) {
        const auto c = g.coords(id);
        for (int a = 0; a < 3; ++a)
          for (int side = 0; side < 2; ++side) {
            auto nc = c;
            nc[a] += side ? 1 : -1;
            if (nc[a] < 0 || nc[a] >= g.count[a]) continue;  // a box face: nothing beyond
            const std::int64_t n = g.id(nc[0], nc[1], nc[2]);
            if (active.test(n)) continue;
            Face f;
            for (int b = 0; b < 3; ++b) {
              f.lo[b] = c[b] * bc;
              f.hi[b] = std::min<std::int64_t>((c[b] + 1) * bc, l.cells[b]);
            }
            if (side) f.lo[a] = f.hi[a];
            else f.hi[a] = f.lo[a];
            f.neighbour = n;
            faces.push_back(f);
            for_each_node(f, [&](std::int64_t key, std::int64_t i, std::int64_t j, std::int64_t k) {
              if (side_of(key, i, j, k) < 0) keys.push_back(key);
            });
          }
      }
      chunk.clear();
      std::sort(keys.begin(), keys.end());
      keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
      if (!keys.empty()) {
        points.resize(keys.size());
        for (std::size_t i = 0; i < keys.size(); ++i) {
          const std::int64_t k = keys[i];
          points[i] = l.node(k % geo.nodes[0], (k / geo.nodes[0]) % geo.nodes[1], k / (geo.nodes[0] * geo.nodes[1]));
        }
        EvaluatePoints(field, points, values, counters.follow, counters, external);
        for (std::size_t i = 0; i < keys.size(); ++i) sides.insert(keys[i], Inside(values[i], field.iso));
      }
      // A face with nodes on both sides has mesh edges on it: the block across it must be meshed.
      for (const Face& f : faces) {
        int in = 0, total = 0;
        for_each_node(f, [&](std::int64_t key, std::int64_t i, std::int64_t j, std::int64_t k) {
          in += side_of(key, i, j, k) == 1;
          ++total;
        });
        if (in != 0 && in != total) next.set(f.neighbour);
      }
    };
    frontier.for_each(0, frontier.size(), [&](std::int64_t id) {
      chunk.push_back(id);
      if (std::int64_t(chunk.size()) >= o.follow_chunk_blocks) check();
      return true;
    });
    if (!chunk.empty()) check();
    added += next.count();
    active |= next;
    frontier = std::move(next);
  }
  return added;
}

}  // namespace quijibo::mesh::mesher
