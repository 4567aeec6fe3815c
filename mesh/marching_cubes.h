// Meshing an implicit field: marching cubes with bisection on the edges, sparse coarse-to-fine
// block search and parallel tiles (2015 paper §5; Kim and Duff 2020 for the 64-bit arrangement).
//
// One mesher for every method: QUIJIBO rational maps, the shape modulus and portals all hand it a
// BatchField. The surface is {f = iso}; "inside" is f < iso.
//
// INTERFACE FIXED BY THE LEAD (issue 5 implements it, issue 6 uses it): change it only together.
#pragma once
#include <cstdint>
#include <functional>
#include <string>

#include "mesh/triangle_mesh.h"
#include "quijibo/grid.h"

namespace quijibo {

// A scalar field evaluated in batches (one virtual call per batch, not per point).
struct BatchField {
  // Writes f(points[i]) to values[i] for i < n. Called concurrently from several threads, so it
  // must be thread-safe. Non-finite values are allowed (they count as "outside" and are reported).
  std::function<void(const Vec3* points, std::size_t n, double* values)> evaluate;
  double iso = 0.0;
};

struct MeshingOptions {
  Vec3 min_corner{-2.0, -2.0, -2.0};  // the box meshed (fractal frame)
  Vec3 max_corner{2.0, 2.0, 2.0};
  int resolution = 256;               // cells along the longest side of the box
  int bisection_steps = 6;            // reference: 6 steps ...
  double bisection_tolerance = 1e-8;  // ... or |f - iso| below this
  bool sparse = true;                 // coarse-to-fine block search; false evaluates every node
  int tile_cells = 32;                // cells per tile side (the unit of parallel work and memory)
  int coarse_margin_cells = 2;        // safety margin of the sparse block search, in fine cells
  std::string validate() const;       // empty when valid, else what is wrong
};

struct MeshingSummary {
  std::int64_t nodes_evaluated = 0;   // field evaluations, bisection excluded
  std::int64_t bisection_evaluations = 0;
  std::int64_t non_finite_values = 0;
  std::int64_t tiles_total = 0, tiles_meshed = 0;
  double seconds = 0.0;
  std::string report() const;         // a few readable lines
};

// Meshes {f = iso} inside the box. Vertices are shared between cells and tiles (no duplicates at
// seams), triangles are counter-clockwise seen from outside (f > iso). Throws quijibo::Error on
// invalid options. Memory is O(tile³ · threads + output), independent of resolution³ when sparse.
TriangleMesh MeshField(const BatchField& field, const MeshingOptions& options,
                       MeshingSummary* summary = nullptr);

}  // namespace quijibo
