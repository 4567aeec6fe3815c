// Pieces of the mesher shared by its source files (marching_cubes.cpp, block_search.cpp,
// lattice_mesh.cpp); not an interface for other modules.
#pragma once

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <vector>

#include "mesh/marching_cubes.h"

namespace quijibo::mesh::mesher {

inline bool Inside(double v, double iso) { return v < iso; }  // NaN and +inf: outside

struct Counters {
  std::atomic<std::int64_t> nodes{0}, bisection{0}, non_finite{0}, search{0}, follow{0};
};

// Evaluates `points` into `values` (one call per chunk), counting non-finite values.
inline void Evaluate(const BatchField& field, const Vec3* points, std::size_t n, double* values,
                     std::atomic<std::int64_t>& counter, Counters& counters) {
  if (n == 0) return;
  field.evaluate(points, n, values);
  std::int64_t bad = 0;
  for (std::size_t i = 0; i < n; ++i) bad += !std::isfinite(values[i]);
  counter += std::int64_t(n);
  if (bad) counters.non_finite += bad;
}

struct Geometry {
  MeshLattice lattice;
  std::array<std::int64_t, 3> nodes;  // nodes per axis
  std::int64_t node_id(std::int64_t i, std::int64_t j, std::int64_t k) const {
    return i + nodes[0] * (j + nodes[1] * k);
  }
};

inline Geometry GeometryFor(const MeshLattice& l) {
  Geometry geo;
  geo.lattice = l;
  for (int a = 0; a < 3; ++a) geo.nodes[a] = l.cells[a] + 1;
  return geo;
}

// Blocks of `stride` cells: block b spans cells [b s, min((b + 1) s, n)).
struct BlockGrid {
  int stride;
  std::array<std::int64_t, 3> count;
  std::int64_t id(std::int64_t i, std::int64_t j, std::int64_t k) const { return i + count[0] * (j + count[1] * k); }
  std::array<std::int64_t, 3> coords(std::int64_t id) const {
    return {id % count[0], (id / count[0]) % count[1], id / (count[0] * count[1])};
  }
};

inline BlockGrid MakeBlocks(const MeshLattice& l, int stride) {
  BlockGrid g{stride, {}};
  for (int a = 0; a < 3; ++a) g.count[a] = (l.cells[a] + stride - 1) / stride;
  return g;
}

// A set of ids in [0, n), one bit each. The search's sets (candidate, crossing and kept blocks, the
// finest corners' signs) grow as the box's volume: listed as 8-byte ids they passed 4 GB at 2048³
// on a porous set (docs/benchmarks.md §26), as bits they take 128 MB per billion blocks.
class Bitmap {
 public:
  explicit Bitmap(std::int64_t n = 0) : n_(n), words_(std::size_t((n + 63) / 64), 0) {}
  std::int64_t size() const { return n_; }
  void set(std::int64_t i) { words_[std::size_t(i >> 6)] |= std::uint64_t(1) << (i & 63); }
  void reset(std::int64_t i) { words_[std::size_t(i >> 6)] &= ~(std::uint64_t(1) << (i & 63)); }
  bool test(std::int64_t i) const { return (words_[std::size_t(i >> 6)] >> (i & 63)) & 1; }
  std::int64_t count() const {
    std::int64_t c = 0;
    for (std::uint64_t w : words_) c += __builtin_popcountll(w);
    return c;
  }
  bool any() const {
    for (std::uint64_t w : words_)
      if (w) return true;
    return false;
  }
  void operator|=(const Bitmap& o) {
    for (std::size_t i = 0; i < words_.size(); ++i) words_[i] |= o.words_[i];
  }
  // Calls f(id) for every set id in [begin, end), ascending; stops early when f returns false.
  template <class F>
  void for_each(std::int64_t begin, std::int64_t end, F&& f) const {
    if (begin >= end) return;
    for (std::int64_t w = begin >> 6, last = (end - 1) >> 6; w <= last; ++w) {
      std::uint64_t bits = words_[std::size_t(w)];
      if (w == (begin >> 6)) bits &= ~std::uint64_t(0) << (begin & 63);
      if (w == last && (end & 63)) bits &= (std::uint64_t(1) << (end & 63)) - 1;
      while (bits) {
        const std::int64_t id = (w << 6) + __builtin_ctzll(bits);
        bits &= bits - 1;
        if (!f(id)) return;
      }
    }
  }
  const std::vector<std::uint64_t>& words() const { return words_; }

 private:
  std::int64_t n_;
  std::vector<std::uint64_t> words_;
};

// The signs at the finest search level's block corners (a grid of count + 1 corners per axis; corner
// c of axis a is node min(c block_cells, cells[a])): which were evaluated and which are inside.
struct CornerSigns {
  std::array<std::int64_t, 3> corners{0, 0, 0};
  Bitmap known, inside;
};

// What the search keeps: the finest blocks (of o.block_cells) to mesh, one bit per block id.
struct SearchResult {
  Bitmap active;
  CornerSigns finest;  // the finest level's corner signs (seeds surface following)
};

// The coarse-to-fine block search (block_search.cpp), a level at a time and, within a level, a slab
// of corner layers at a time, so that besides its bitmaps it holds one slab's values and the previous
// level's values (reused: every corner of a coarse block is a corner of its children). `external`
// (optional) evaluates the search lattice instead of the field.
SearchResult SearchBlocks(const BatchField& field, const MeshingOptions& o, int first_stride, const Geometry& geo,
                          Counters& counters, const PointsEvaluator& external);

// Surface following (block_search.cpp): adds to `active` every block across a face of an active block
// on which the field changes sign, until none is added, so that every piece of surface the active
// blocks touch is meshed whole. Returns how many it added. `seed` (optional): the search's corner
// signs, not evaluated again. The frontier is taken in chunks, so its faces never all exist at once.
std::int64_t FollowSurface(const BatchField& field, const MeshingOptions& o, const Geometry& geo, Bitmap& active,
                           Counters& counters, const PointsEvaluator& external, const CornerSigns* seed = nullptr);

// Removes the components that enclose a single lattice node (lattice_mesh.cpp); `edges[v]` is vertex
// v's edge id. Returns how many.
std::int64_t RemoveNodeSpecks(const MeshLattice& l, std::vector<std::int64_t>& edges, TriangleMesh& mesh);

// Open edges of a mesh whose vertices lie on lattice edges (`edges[v]`, vertex v's edge id), split into
// those on the box faces and the rest, and connected components (lattice_mesh.cpp).
struct LatticeMeshFacts {
  std::int64_t open_edges = 0, open_edges_inside = 0, components = 0;
};
LatticeMeshFacts AnalyzeLatticeMesh(const MeshLattice& l, const std::vector<std::int64_t>& edges,
                                    const TriangleMesh& mesh);

}  // namespace quijibo::mesh::mesher
