// How well a Julia set takes the shape of its target: the figures of the shape suite
// (docs/benchmarks.md, `quijibo fidelity`, `quijibo bench shapes`).
//
// The lattice: `lattice`^3 nodes over the shape box B (the cube of side
// fractal_radius * (1 - 2 padding) about the frame's box_center(): the mesh's longest side) grown by `extend`
// of its side on every side, so it sees set beyond the region the energy fits.
//   inside     phi < 0, phi sampled from the target grid; outside the target grid: outside
//   one-step   {L < 0}, L = ln C + tau sum T_i log|q - t_i| - beta sum B_i log|q - b_i| at q = [x, 0]
//   n-step     {log|q_n| < iso} of the meshed field (JuliaMap, n iterations)
//   IoU        |set and inside| / |set or inside|
//   leak       |set outside B| / |inside|
// Chamfer and Hausdorff distances compare the meshed Julia set with the target mesh by points
// sampled uniformly by area on each (seeded), nearest distances by BVH: Chamfer is the mean of
// the two directed mean distances, Hausdorff the larger directed maximum, both divided by the
// target's bounding-box diagonal.
#pragma once

#include <cstdint>
#include <string>

#include "mesh/triangle_mesh.h"
#include "quijibo/grid.h"
#include "quijibo/julia.h"
#include "quijibo/rational_map.h"

namespace quijibo::mesh {

struct FidelityOptions {
  int lattice = 72;             // nodes per axis, in [8, 512]
  double extend = 0.2;          // growth of B on every side, as a fraction of its side
  JuliaOptions julia;           // the n-step field (iterations 0: skip it)
  double iso = 0.0;
  int surface_samples = 20000;  // points per mesh for Chamfer and Hausdorff
  std::uint64_t seed = 1;
  std::string validate() const;
};

struct SetFigures {
  double iou = 0, leak = 0;
  std::int64_t set_nodes = 0, leak_nodes = 0;
};

struct Fidelity {
  std::int64_t inside_nodes = 0;
  SetFigures one_step, n_step;
  bool has_n_step = false;
  double chamfer = -1, hausdorff = -1;  // fractions of the diagonal; -1 when not measured
  nlohmann::json ToJson() const;
};

// The lattice figures of `map` against the target grid `target` (both in the fractal frame).
Fidelity MeasureSets(const RationalMap& map, const ScalarGrid& target, const FidelityOptions& options = {});

// `count` points uniformly distributed by area on `mesh` (seeded; doubles from the top 53 bits of
// std::mt19937_64, portable); empty when the mesh has no area.
std::vector<Vec3> SampleSurface(const TriangleMesh& mesh, int count, std::uint64_t seed);

// Chamfer and Hausdorff of `julia` against `shape` (same frame), filled into `f`.
void MeasureSurfaceDistances(const TriangleMesh& julia, const TriangleMesh& shape, const FidelityOptions& options,
                             Fidelity& f);

// For each point of `a`, the distance to the nearest point of `b` (a uniform hash grid over b;
// infinity when b is empty).
std::vector<double> NearestPointDistances(const std::vector<Vec3>& a, const std::vector<Vec3>& b);
// The mean of `v` (NaN when empty).
double Mean(const std::vector<double>& v);

}  // namespace quijibo::mesh
