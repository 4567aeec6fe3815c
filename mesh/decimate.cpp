#include "mesh/decimate.h"

#include <meshoptimizer.h>

#include <vector>

#include "util/error.h"

namespace quijibo::mesh {

TriangleMesh Decimate(const TriangleMesh& mesh, const DecimateOptions& options, DecimateSummary* summary) {
  if (options.max_triangles < 0) throw Error("Decimate: max_triangles must be >= 0");
  DecimateSummary s;
  s.triangles_in = std::int64_t(mesh.triangles.size());
  const std::size_t target = std::size_t(options.max_triangles) * 3;
  std::vector<unsigned> indices;
  indices.reserve(mesh.triangles.size() * 3);
  for (const auto& t : mesh.triangles)
    for (int v : t) indices.push_back(unsigned(v));
  std::vector<float> positions;
  positions.reserve(mesh.vertices.size() * 3);
  for (const Vec3& v : mesh.vertices)
    for (double c : v) positions.push_back(float(c));
  if (indices.size() > target) {
    std::vector<unsigned> out(indices.size());
    float error = 0;
    std::size_t n = meshopt_simplify(out.data(), indices.data(), indices.size(), positions.data(),
                                     mesh.vertices.size(), sizeof(float) * 3, target,
                                     float(options.max_relative_error), 0, &error);
    if (n > target) {
      // Topology (many small components, a crust's pores) stops the collapses: cluster the rest.
      std::vector<unsigned> sloppy(n);
      n = meshopt_simplifySloppy(sloppy.data(), out.data(), n, positions.data(), mesh.vertices.size(),
                                 sizeof(float) * 3, target, 1.0f, &error);
      sloppy.resize(n);
      out.swap(sloppy);
      s.clustered = true;
    }
    out.resize(n);
    indices.swap(out);
    s.relative_error = error;
  }
  // Keep the used vertices only, in order of first use (meshopt_optimizeVertexFetch).
  std::vector<float> fetched(positions.size());
  const std::size_t vertex_count = meshopt_optimizeVertexFetch(fetched.data(), indices.data(), indices.size(),
                                                               positions.data(), mesh.vertices.size(),
                                                               sizeof(float) * 3);
  TriangleMesh result;
  result.vertices.resize(vertex_count);
  for (std::size_t i = 0; i < vertex_count; ++i)
    result.vertices[i] = {fetched[3 * i], fetched[3 * i + 1], fetched[3 * i + 2]};
  result.triangles.resize(indices.size() / 3);
  for (std::size_t t = 0; t < result.triangles.size(); ++t)
    result.triangles[t] = {int(indices[3 * t]), int(indices[3 * t + 1]), int(indices[3 * t + 2])};
  s.triangles_out = std::int64_t(result.triangles.size());
  if (summary) *summary = s;
  return result;
}

}  // namespace quijibo::mesh
