// Meshing an implicit field: marching cubes with bisection on the edges, sparse coarse-to-fine
// block search with surface following (block_search.cpp: no open edge away from the box faces) and
// parallel tiles (2015 paper §5; Kim and Duff 2020 for the 64-bit arrangement).
//
// One mesher for every method: QUIJIBO rational maps, the shape modulus and portals all hand it a
// BatchField. The surface is {f = iso}; "inside" is f < iso.
//
// INTERFACE FIXED BY THE LEAD (issue 5 implements it, issue 6 uses it): change it only together.
#pragma once
#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "mesh/triangle_mesh.h"
#include "quijibo/grid.h"
#include "util/settings.h"

namespace quijibo::mesh {

// A scalar field evaluated in batches (one virtual call per batch, not per point).
struct BatchField {
  // Writes f(points[i]) to values[i] for i < n. Called concurrently from several threads, so it
  // must be thread-safe. Non-finite values are allowed (they count as "outside" and are reported).
  std::function<void(const Vec3* points, std::size_t n, double* values)> evaluate;
  double iso = 0.0;
  // Added by issue 5: the sparse search also refines blocks whose corners are all on one side when
  // one of them lies within this of iso (field units; 0: off). Fields with sub-cell detail near
  // the surface set it (log|q_n| fields: 2.0, julia_field.h); a distance field keeps 0.
  double value_margin = 0.0;
  // Added by issue 40: the values are log|q| of a map (log-modulus fields; set by julia_field.h).
  // Not used by the mesher: interpolating bisection's last bracket in |q| = e^f instead of f was
  // measured and moved vertices further (docs/benchmarks.md §21), so both are linear in f.
  bool log_modulus = false;
};

struct MeshingOptions {
  Vec3 min_corner{-2.0, -2.0, -2.0};  // the box meshed (fractal frame)
  Vec3 max_corner{2.0, 2.0, 2.0};
  int resolution = 256;               // cells along the longest side of the box
  static constexpr ValueRange kResolutionRange{2, 65536};
  int bisection_steps = 6;            // reference: 6 steps ...
  double bisection_tolerance = 1e-8;  // ... or |f - iso| below this
  // Added by issue 40: after the steps, place the vertex where the line through the last bracket's
  // end values crosses iso instead of at the bracket's midpoint (0 steps allowed: plain marching
  // cubes interpolation). Fewer steps for nearly the same vertices; docs/meshing.md "Bisection".
  bool bisection_interpolate = false;
  // After the bisection steps, this many false-position steps (the field evaluated where the line
  // through the bracket's end values crosses iso, that point replacing the end on its side;
  // Illinois variant), then the vertex interpolated in the last bracket (as bisection_interpolate;
  // the bisection steps may then be 0). In [0, 8]. Fewer evaluations than plain bisection for
  // vertices as close to the surface; docs/meshing.md "Bisection".
  int secant_steps = 0;
  bool sparse = true;                 // coarse-to-fine block search; false evaluates every node
  int tile_cells = 32;                // cells per tile side (the unit of parallel work and memory)
  int coarse_margin_cells = 2;        // safety margin of the sparse block search, in fine cells
  // Added by issue 5 (see docs/meshing.md):
  int search_stride = 8;              // sparse: the coarsest lattice, evaluated everywhere (power of 2)
  int search_min_cells = 64;          // ... but never coarser than this many cells along the longest
                                      // side (smaller strides for small resolutions; dense meshing
                                      // when the stride would fall below block_cells)
  int block_cells = 2;                // sparse: the finest block kept or skipped (power of 2,
                                      // <= search_stride, divides tile_cells)
  double search_value_margin = -1.0;  // sparse: overrides BatchField::value_margin when >= 0
  bool remove_specks = true;          // drop components enclosing a single lattice node (sub-cell
                                      // specks a node fell into by chance; docs/meshing.md)
  // Added by issue 16: sparse: mesh the block across every face of a meshed block that the surface
  // crosses, until none is left, so no piece of surface the search touched is cut open.
  bool follow_surface = true;
  // Sparse: the search evaluates a slab of corner layers of about this many nodes at a time, and the
  // surface following checks this many blocks at a time. They bound the working memory besides the
  // search's bitmaps (docs/meshing.md "Memory") and never change the mesh or the evaluations.
  std::int64_t search_slab_nodes = std::int64_t(1) << 22;
  std::int64_t follow_chunk_blocks = std::int64_t(1) << 17;
  bool show_progress = false;         // Progress on stderr (util/progress.h)
  std::string Validate() const;       // empty when valid, else what is wrong
};

struct MeshingSummary {
  std::int64_t nodes_evaluated = 0;   // field evaluations, bisection excluded
  std::int64_t bisection_evaluations = 0;
  std::int64_t non_finite_values = 0;
  std::int64_t tiles_total = 0, tiles_meshed = 0;
  double seconds = 0.0;
  // Added by issue 5:
  std::int64_t search_evaluations = 0;  // sparse search (included in nodes_evaluated)
  std::int64_t blocks_active = 0;       // blocks meshed (sparse), of blocks_total
  std::int64_t blocks_total = 0;
  std::int64_t vertices = 0, triangles = 0;
  std::int64_t specks_removed = 0;      // one-node components dropped (remove_specks)
  // Added by issue 16:
  std::int64_t follow_evaluations = 0;  // surface following (included in nodes_evaluated)
  std::int64_t blocks_followed = 0;     // blocks added by surface following (in blocks_active)
  std::int64_t open_edges = 0;          // mesh edges used by one triangle ...
  std::int64_t open_edges_inside = 0;   // ... of which away from the box faces (0 unless a bug)
  std::int64_t components = 0;          // connected components of the mesh
  bool speck_removal = true;            // whether specks were removed
  int search_stride = 0;                // the stride the sparse search used (0: dense)
  std::array<int, 3> cells{0, 0, 0};    // cells per axis of the lattice meshed
  double spacing = 0.0;                 // cell side
  std::string report() const;         // a few readable lines
};

// The lattice MeshField samples: nodes at min_corner + spacing * (i, j, k), i in [0, cells_x],
// spacing = longest side / resolution, cells per axis rounded up so the lattice covers the box.
struct MeshLattice {
  Vec3 origin{0.0, 0.0, 0.0};
  double spacing = 0.0;
  std::array<int, 3> cells{0, 0, 0};
  Vec3 node(std::int64_t i, std::int64_t j, std::int64_t k) const {
    return {origin[0] + spacing * double(i), origin[1] + spacing * double(j), origin[2] + spacing * double(k)};
  }
};
MeshLattice LatticeFor(const MeshingOptions& options);

// The field on a narrow band around the surface (the nodes of every cell the surface crosses),
// for .vdb export. Nodes are indices into the MeshLattice.
struct FieldBand {
  MeshLattice lattice;
  std::vector<std::array<int, 3>> nodes;
  std::vector<float> values;  // non-finite values stored as +FLT_MAX (outside)
};

// As above, also filling `band` when it is not null.
TriangleMesh MeshField(const BatchField& field, const MeshingOptions& options, MeshingSummary* summary,
                       FieldBand* band);

// Meshes {f = iso} inside the box. Vertices are shared between cells and tiles (no duplicates at
// seams), triangles are counter-clockwise seen from outside (f > iso). Throws quijibo::Error on
// invalid options. Memory is O(tile³ · threads + output), independent of resolution³ when sparse.
TriangleMesh MeshField(const BatchField& field, const MeshingOptions& options,
                       MeshingSummary* summary = nullptr);

// ---------------------------------------------------------------------------------------------
// Tile-level API (issue 8, docs/mpi.md): MeshField is PlanTiles, then MeshTilePiece for every planned
// tile (in parallel), then WeldTilePieces. A distributed mesher calls the same three steps and gets the
// same mesh, bit for bit, whatever process meshed which tile.

// Evaluates points[i] into values[i] (values resized by the callee) exactly as field.evaluate would; lets
// the sparse search spread its lattice over processes (e.g. MPI ranks).
using PointsEvaluator = std::function<void(const std::vector<Vec3>& points, std::vector<double>& values)>;

// What the sparse search found: the tiles to mesh and their active blocks. Deterministic: depends only on
// the field's values and the options.
struct TilePlan {
  MeshingOptions options;
  MeshLattice lattice;
  bool sparse = true;
  int search_stride = 0;                              // 0: dense
  std::array<std::int64_t, 3> tiles{0, 0, 0};         // tiles per axis
  std::vector<std::int64_t> tile_ids;                 // tiles to mesh, ascending (x fastest)
  std::vector<std::vector<std::int64_t>> tile_blocks; // sparse: active block ids of each (empty: dense)
  std::int64_t search_evaluations = 0, search_non_finite = 0;
  std::int64_t follow_evaluations = 0, blocks_followed = 0;  // surface following (in the search's counts)
  std::int64_t blocks_total = 0;
  double search_seconds = 0.0;
  std::int64_t tiles_total() const { return tiles[0] * tiles[1] * tiles[2]; }
};

// The sparse block search and surface following (or the dense tile list). Throws quijibo::Error on invalid options.
// `search_evaluate` (optional) replaces the local parallel evaluation of the search lattice.
TilePlan PlanTiles(const BatchField& field, const MeshingOptions& options, const PointsEvaluator& search_evaluate = {});

// One meshed tile: vertices keyed by global edge id (3 * node id + axis, node id = i + N_x (j + N_y k)),
// triangles as indices into vertex_edges (so, equivalently, as edge-id triples).
struct TilePiece {
  std::int64_t tile = -1;
  std::vector<std::int64_t> vertex_edges;
  std::vector<Vec3> vertex_positions;
  std::vector<std::array<std::int32_t, 3>> triangles;
  std::vector<std::array<int, 3>> band_nodes;  // filled when asked for
  std::vector<float> band_values;
  std::int64_t nodes_evaluated = 0, bisection_evaluations = 0, non_finite_values = 0, blocks_active = 0;
};

// Meshes plan.tile_ids[index] (single-threaded; thread-safe, call it from many threads).
TilePiece MeshTilePiece(const BatchField& field, const TilePlan& plan, std::size_t index, bool want_band);

// Welds pieces[i] (the piece of plan.tile_ids[i], for every i) into one mesh: one vertex per edge id,
// sorted by id; triangles in tile order. Releases the pieces' memory. Fills `summary` (seconds excluded)
// and `band` when not null.
TriangleMesh WeldTilePieces(const TilePlan& plan, std::vector<TilePiece>& pieces, MeshingSummary* summary,
                            FieldBand* band);

}  // namespace quijibo::mesh
