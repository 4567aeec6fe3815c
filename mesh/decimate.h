// Decimation to a triangle budget (meshoptimizer's simplifier, Debian's libmeshoptimizer-dev): what
// report.html's viewer embeds, since a browser holds a few hundred thousand triangles, not the
// millions of an intricate Julia set.
#pragma once

#include <cstdint>

#include "mesh/triangle_mesh.h"

namespace quijibo::mesh {

struct DecimateOptions {
  std::int64_t max_triangles = 200000;  // the budget; a mesh at or under it is returned as it is
  // The error the edge-collapse simplifier may reach, relative to the mesh's extent; where it stops
  // above the budget (collapses that would exceed this, or change the topology), the rest is done by
  // clustering (meshopt_simplifySloppy), which reaches any budget.
  double max_relative_error = 0.02;
};

struct DecimateSummary {
  std::int64_t triangles_in = 0;
  std::int64_t triangles_out = 0;
  double relative_error = 0;  // meshoptimizer's error estimate, relative to the extent
  bool clustered = false;     // the budget needed meshopt_simplifySloppy
};

// The mesh with at most `options.max_triangles` triangles (unused vertices dropped, coordinates in float
// precision: what the simplifier and a browser read), in the same frame.
// Inputs: a mesh with at least one triangle. Output: a mesh with at least one triangle unless the
// budget is zero; `summary` (optional) says what it did.
TriangleMesh Decimate(const TriangleMesh& mesh, const DecimateOptions& options, DecimateSummary* summary = nullptr);

}  // namespace quijibo::mesh
