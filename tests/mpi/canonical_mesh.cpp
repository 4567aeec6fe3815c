// canonical_mesh IN.ply OUT.bin: the mesh in a form independent of vertex and face order (vertices
// sorted, faces remapped, each face rotated to start at its smallest index, faces sorted), for
// comparing the MPI and single-process meshes byte for byte (tests/CMakeLists.txt, docs/mpi.md).
#include <algorithm>
#include <array>
#include <cstdio>
#include <fstream>
#include <numeric>
#include <vector>

#include "mesh/triangle_mesh.h"

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: canonical_mesh IN.ply OUT.bin\n");
    return 2;
  }
  try {
    const quijibo::mesh::TriangleMesh m = quijibo::mesh::ReadMesh(argv[1]);
    std::vector<std::size_t> order(m.vertices.size());
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
      const auto &u = m.vertices[a], &v = m.vertices[b];
      return std::array<double, 3>{u[0], u[1], u[2]} < std::array<double, 3>{v[0], v[1], v[2]};
    });
    std::vector<std::int64_t> rank(order.size());
    for (std::size_t i = 0; i < order.size(); ++i) rank[order[i]] = std::int64_t(i);
    std::vector<std::array<std::int64_t, 3>> faces;
    for (const auto& t : m.triangles) {
      std::array<std::int64_t, 3> f{rank[std::size_t(t[0])], rank[std::size_t(t[1])], rank[std::size_t(t[2])]};
      std::rotate(f.begin(), std::min_element(f.begin(), f.end()), f.end());  // keeps the orientation
      faces.push_back(f);
    }
    std::sort(faces.begin(), faces.end());
    std::ofstream out(argv[2], std::ios::binary);
    const std::uint64_t nv = order.size(), nf = faces.size();
    out.write(reinterpret_cast<const char*>(&nv), sizeof nv);
    out.write(reinterpret_cast<const char*>(&nf), sizeof nf);
    for (std::size_t i : order) {
      const double p[3] = {m.vertices[i][0], m.vertices[i][1], m.vertices[i][2]};
      out.write(reinterpret_cast<const char*>(p), sizeof p);
    }
    for (const auto& f : faces) out.write(reinterpret_cast<const char*>(f.data()), sizeof f);
    std::printf("%llu vertices, %llu faces\n", (unsigned long long)nv, (unsigned long long)nf);
    return out ? 0 : 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "canonical_mesh: %s\n", e.what());
    return 1;
  }
}
