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
//   volume IoU the same at one point drawn uniformly in each lattice cell (seeded, stratified): an
//              estimate of the IoU of the volumes, free of the lattice's aliasing, which on walls a
//              few lattice cells thick moves the node IoU by 0.01-0.03 between lattices
//              (docs/fidelity.md §10); it doubles the evaluations of a measurement
//   leak       |set outside B| / |inside|
//   closed IoU IoU of the n-step set after a morphological closing (dilation then erosion by a cube
//              of `closing` lattice cells' half side): whether the coarse shape, the silhouette,
//              stays when the surface grows intricate (holes and folds finer than the closing fill)
// The n-step set is of the map as iterated (`iterated`: the mesh stage's `iteration_frame` and
// `detail` applied), sampled at the same user points.
// Detail of a meshed set (MeasureMeshDetail): its area against the target mesh's, its connected
// components, and a box-counting dimension: the boxes of side s = side / 2^k (k = 3 .. 7, side the
// shape box's) that the surface meets, N(s), and the least-squares slope of log N against
// log(1/s): 2 for a smooth surface, more as detail fills space at those scales.
// Chamfer and Hausdorff distances compare the meshed Julia set with the target mesh by points
// sampled uniformly by area on each (seeded), nearest distances by BVH: Chamfer is the mean of
// the two directed mean distances, Hausdorff the larger directed maximum, both divided by the
// target's bounding-box diagonal.
#pragma once

#include <memory>
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
  // The map as iterated (its frame and detail applied: JuliaSetup::map, made once by the caller,
  // quijibo/julia_setup.h); needed for the n-step set, whose translation is `julia`'s.
  std::shared_ptr<const RationalMap> iterated;
  int closing = 2;              // closed IoU: half side of the closing's cube, lattice cells, in [0, 16]
  double iso = 0.0;
  int surface_samples = 20000;  // points per mesh for Chamfer and Hausdorff
  std::uint64_t seed = 1;      // surface samples and the volume IoU's points
  std::string Validate() const;
};

struct SetFigures {
  double iou = 0, leak = 0;
  double volume_iou = 0;  // at the jittered points (see the header comment)
  std::int64_t set_nodes = 0, leak_nodes = 0;
};

struct Fidelity {
  std::int64_t inside_nodes = 0;
  SetFigures one_step, n_step;
  double n_step_closed_iou = 0;  // the n-step set after the closing (has_n_step)
  bool has_n_step = false;
  double chamfer = -1, hausdorff = -1;  // fractions of the diagonal; -1 when not measured
  nlohmann::json ToJson() const;
};

// The lattice figures of `map` against the target grid `target` (both in the fractal frame). The
// n-step figures (options.julia.iterations > 0) need options.iterated; throws quijibo::Error without.
Fidelity MeasureSets(const RationalMap& map, const ScalarGrid& target, const FidelityOptions& options);

// The one-step fit at the target grid's nodes and between them: the IoU of {L < 0} and {phi < 0}
// at the cell centres of `target` (the points the energy fits) and at its interior cell corners
// (each the centre of eight cells, phi trilinear there). The energy sees only the nodes, so a fit
// whose thin parts pass through them and narrow in between (beads along a wall two or three cells
// thick) scores well on the nodes and markedly worse between them; a faithful fit scores alike.
// Trilinear phi is biased outward on curved surfaces (by about h^2 / 4r at radius r), so points
// with |phi| < h / 4 are left undecided and not counted, corners and nodes alike (the two figures
// then judge the same kind of point): counting every corner, the exact set of a sphere nine cells
// across scores 0.95 between the nodes against 1.00 on them. Both figures are therefore higher
// than CheckStart's IoU on the nodes, which counts every node.
struct NodeFit {
  double on_nodes = 0, between_nodes = 0;
  std::int64_t nodes = 0, corners = 0, undecided_nodes = 0, undecided_corners = 0;
  nlohmann::json ToJson() const;
};
NodeFit MeasureNodeFit(const RationalMap& map, const ScalarGrid& target);

// How much detail a meshed set has (see the header comment).
struct MeshDetail {
  double area = 0;              // of the mesh
  double area_ratio = -1;       // area / the target mesh's area (-1 without a target mesh)
  std::int64_t components = 0;  // connected components (by shared vertices)
  double dimension = 0;         // box-counting dimension estimate
  std::vector<std::int64_t> box_counts;  // N(side / 2^k), k = 3 .. 7
  nlohmann::json ToJson() const;
};
// `julia` and `shape` (may be null) in the same frame; `side` the side of the shape box in that
// frame (the boxes' scales). Throws quijibo::Error for a side that is not positive.
MeshDetail MeasureMeshDetail(const TriangleMesh& julia, const TriangleMesh* shape, double side);

// Morphological closing (dilation then erosion by a cube of half side r cells) of a set on an n^3
// lattice (x fastest); r = 0: the set itself.
std::vector<char> Close(const std::vector<char>& set, int n, int r);

// `count` points uniformly distributed by area on `mesh` (seeded; doubles from the top 53 bits of
// std::mt19937_64, portable); empty when the mesh has no area.
std::vector<Vec3> SampleSurface(const TriangleMesh& mesh, int count, std::uint64_t seed);

// Chamfer and Hausdorff of `julia` against `shape` (same frame), filled into `f`.
void MeasureSurfaceDistances(const TriangleMesh& julia, const TriangleMesh& shape, const FidelityOptions& options,
                             Fidelity& f);

// The Chamfer of point samples (`quijibo compare`): the mean distance from each sample of a set to
// the nearest sample of its target (`to_target`) and back (`from_target`), and their sum.
// Nearest samples, not the nearest surface point as MeasureSurfaceDistances; not normalized.
struct SampleChamfer {
  double to_target = 0, from_target = 0;
  double sum() const { return to_target + from_target; }
};
SampleChamfer MeasureSampleChamfer(const std::vector<Vec3>& set, const std::vector<Vec3>& target);

// For each point of `a`, the distance to the nearest point of `b` (a uniform hash grid over b;
// infinity when b is empty).
std::vector<double> NearestPointDistances(const std::vector<Vec3>& a, const std::vector<Vec3>& b);
// The mean of `v` (NaN when empty).
double Mean(const std::vector<double>& v);

}  // namespace quijibo::mesh
