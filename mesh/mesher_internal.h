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

// Node ids (sorted) and their field values.
struct NodeValues {
  std::vector<std::int64_t> keys;
  std::vector<double> values;
};

// The coarse-to-fine block search (block_search.cpp): the sorted ids of the blocks of
// o.block_cells it keeps. `external` (optional) evaluates the search lattice instead of the field.
// `finest` (optional) receives the values of the last level's nodes.
std::vector<std::int64_t> SearchBlocks(const BatchField& field, const MeshingOptions& o, int first_stride,
                                       const Geometry& geo, Counters& counters, const PointsEvaluator& external,
                                       NodeValues* finest = nullptr);

// Surface following (block_search.cpp): adds to `active` (sorted block ids of o.block_cells) every
// block across a face of an active block on which the field changes sign, until none is added, so
// that every piece of surface the active blocks touch is meshed whole. Returns how many it added.
// `known` (optional): node values already evaluated (the search's), not evaluated again.
std::int64_t FollowSurface(const BatchField& field, const MeshingOptions& o, const Geometry& geo,
                           std::vector<std::int64_t>& active, Counters& counters, const PointsEvaluator& external,
                           const NodeValues* known = nullptr);

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
