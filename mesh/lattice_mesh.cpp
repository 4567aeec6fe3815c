// Facts and clean-up of a mesh from the lattice (vertices keyed by their lattice edge): one-node
// specks, open edges on and away from the box faces, connected components.
#include <algorithm>
#include <numeric>

#include "mesh/mesher_internal.h"

namespace quijibo::mesh::mesher {

namespace {

// Union-find over the vertices, joined by the triangles.
struct Components {
  std::vector<int> parent;
  explicit Components(const TriangleMesh& mesh) : parent(mesh.vertices.size()) {
    std::iota(parent.begin(), parent.end(), 0);
    for (const auto& t : mesh.triangles)
      for (int k = 1; k < 3; ++k) {
        const int a = find(t[0]), b = find(t[k]);
        if (a != b) parent[std::size_t(std::max(a, b))] = std::min(a, b);
      }
  }
  int find(int v) {
    while (parent[std::size_t(v)] != v) v = parent[std::size_t(v)] = parent[std::size_t(parent[std::size_t(v)])];
    return v;
  }
};

}  // namespace

// Removes the components that enclose a single lattice node: 6 vertices on the 6 edges of that
// node and 8 triangles. Such a speck is smaller than a cell and exists in the mesh only because a
// node happened to fall into it (log|q_n| is steep enough to make one-node islands and bubbles
// common); the sparse search cannot promise to find them and a shifted lattice would not see
// them, so both modes drop them unless asked to keep them. `edges[v]` is vertex v's edge id (sorted; compacted
// with the vertices). Returns how many.
std::int64_t RemoveNodeSpecks(const MeshLattice& l, std::vector<std::int64_t>& edges, TriangleMesh& mesh) {
  const std::size_t nv = mesh.vertices.size();
  Components comp(mesh);
  auto find = [&](int v) { return comp.find(v); };
  std::vector<int> verts(nv, 0), tris(nv, 0);
  for (std::size_t v = 0; v < nv; ++v) ++verts[std::size_t(find(int(v)))];
  for (const auto& t : mesh.triangles) ++tris[std::size_t(find(t[0]))];
  const std::int64_t nx = l.cells[0] + 1, ny = l.cells[1] + 1;
  const std::int64_t step[3] = {1, nx, nx * ny};
  // Candidate components: 6 vertices and 8 triangles. A speck's 6 edges share one lattice node:
  // list (component, edge end) for every candidate vertex, sort, and look for 6 equal entries.
  std::vector<std::pair<int, std::int64_t>> ends;
  for (std::size_t v = 0; v < nv; ++v) {
    const int root = find(int(v));
    if (verts[std::size_t(root)] == 6 && tris[std::size_t(root)] == 8) {
      const std::int64_t node = edges[v] / 3;
      ends.push_back({root, node});
      ends.push_back({root, node + step[edges[v] % 3]});
    }
  }
  std::sort(ends.begin(), ends.end());
  std::vector<char> speck(nv, 0);
  std::int64_t removed = 0;
  for (std::size_t i = 0; i + 5 < ends.size(); ++i)
    if (ends[i] == ends[i + 5] && !speck[std::size_t(ends[i].first)]) {
      speck[std::size_t(ends[i].first)] = 1;
      ++removed;
    }
  if (!removed) return 0;
  std::vector<int> remap(nv, -1);
  std::size_t kept = 0;
  for (std::size_t v = 0; v < nv; ++v)
    if (!speck[std::size_t(find(int(v)))]) {
      remap[v] = int(kept);
      edges[kept] = edges[v];
      mesh.vertices[kept++] = mesh.vertices[v];
    }
  mesh.vertices.resize(kept);
  edges.resize(kept);
  std::size_t kt = 0;
  for (const auto& t : mesh.triangles)
    if (remap[std::size_t(t[0])] >= 0) mesh.triangles[kt++] = {remap[std::size_t(t[0])], remap[std::size_t(t[1])], remap[std::size_t(t[2])]};
  mesh.triangles.resize(kt);
  return removed;
}

LatticeMeshFacts AnalyzeLatticeMesh(const MeshLattice& l, const std::vector<std::int64_t>& edges,
                                    const TriangleMesh& mesh) {
  LatticeMeshFacts facts;
  Components comp(mesh);
  for (std::size_t v = 0; v < mesh.vertices.size(); ++v) facts.components += comp.find(int(v)) == int(v);
  // Undirected edges as (low, high) pairs; an edge used once is open.
  std::vector<std::uint64_t> keys;
  keys.reserve(3 * mesh.triangles.size());
  for (const auto& t : mesh.triangles)
    for (int c = 0; c < 3; ++c) {
      const auto a = std::uint64_t(t[c]), b = std::uint64_t(t[(c + 1) % 3]);
      keys.push_back((std::min(a, b) << 32) | std::max(a, b));
    }
  std::sort(keys.begin(), keys.end());
  const std::int64_t nx = l.cells[0] + 1, ny = l.cells[1] + 1;
  // Bit 2a (2a + 1): the vertex lies on the low (high) box face normal to axis a.
  auto faces_of = [&](std::size_t v) {
    const std::int64_t e = edges[v], node = e / 3, axis = e % 3;
    const std::int64_t ijk[3] = {node % nx, (node / nx) % ny, node / (nx * ny)};
    unsigned bits = 0;
    for (int a = 0; a < 3; ++a) {
      if (a == axis) continue;
      const std::int64_t i = ijk[a], n = l.cells[a];
      bits |= (i == 0 ? 1u : 0u) << (2 * a) | (i == n ? 1u : 0u) << (2 * a + 1);
    }
    return bits;
  };
  for (std::size_t i = 0; i < keys.size();) {
    std::size_t j = i;
    while (j < keys.size() && keys[j] == keys[i]) ++j;
    if (j - i == 1) {
      ++facts.open_edges;
      if (!(faces_of(std::size_t(keys[i] >> 32)) & faces_of(std::size_t(keys[i] & 0xffffffffu))))
        ++facts.open_edges_inside;
    }
    i = j;
  }
  return facts;
}

}  // namespace quijibo::mesh::mesher
