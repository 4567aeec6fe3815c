// Streaming a lattice mesh to disk as its tiles finish (docs/meshing.md "Streaming to disk"), so that
// memory is bounded by the front of tiles being meshed, not by the mesh, and a mesh larger than
// memory can be made.
//
// Tiles are taken in plan order (x fastest, then y, then z), so they finish layer by layer in z. A
// vertex is keyed by its lattice edge id, whose order is z-major: once every tile touching the planes
// below z = G is in, the vertices there are numbered in edge-id order, which is the order of the
// in-memory mesh (MeshField: sorted by edge id), and the triangles whose vertices are all numbered
// are written in tile order. Vertices and faces go to two unnamed scratch files, concatenated under
// the PLY header at the end into the output by an atomic rename: the file is byte for byte what
// WritePly(MeshField(...)) writes, and a failure or an interrupt leaves no file (and no scratch).
//
// The global passes run on the front: one-node specks are decided when every cell around the node is
// in (the same specks as RemoveNodeSpecks); components, open edges and non-manifold edges are counted
// by a union-find and edge counts over the front only, carried from layer to layer. Memory: the pieces
// of about two layers of tiles (and the pieces that finished ahead of the oldest unfinished tile).
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include "mesh/marching_cubes.h"
#include "mesh/triangle_mesh.h"

namespace quijibo::mesh {

struct MeshStreamOptions {
  std::string path;                                 // the binary PLY (.ply)
  PlyPrecision precision = PlyPrecision::kFloat32;  // vertex coordinates, as WritePly
  // Applied to every vertex before it is written (the output frame); empty: none.
  std::function<Vec3(const Vec3&)> transform;
  // Given every piece in tile order (its narrow band, for a .vdb); empty: none. May throw.
  std::function<void(const TilePiece&)> band;
  // Face index type: 0 chooses by the vertex count (PlyIndexType). 64 forces uint64 (tests of the
  // 64-bit path on a small mesh).
  int index_bits = 0;
  std::string Validate() const;  // empty when valid
};

// What the stream wrote and how large its front grew.
struct MeshStreamReport {
  std::int64_t non_manifold_edges = 0;   // mesh edges used by more than two triangles
  std::string index_type;                // of the faces: int, uint or uint64
  std::int64_t bytes = 0;                // of the PLY (0: nothing written, no triangles)
  std::int64_t peak_front_tiles = 0;     // pieces held at once (waiting for their layer's neighbours)
  std::int64_t peak_front_triangles = 0; // triangles in them
  std::int64_t flushes = 0;              // times vertices were numbered and written
  std::int64_t band_samples = 0;         // narrow-band samples of the pieces (as FieldBand::nodes.size())
};

// The PLY face index type for a mesh of `vertices` vertices: "int" (as WritePly) up to 2^31, "uint"
// up to 2^32 (the largest index is vertices - 1), "uint64" beyond; index_bits 64 forces "uint64".
std::string PlyIndexType(std::uint64_t vertices, int index_bits = 0);

// Receives the pieces of a TilePlan's tiles (any order, each once) and streams the mesh to the PLY.
// The destructor removes everything when Finish did not succeed. Not thread-safe: one Add at a time.
class MeshStreamWriter {
 public:
  MeshStreamWriter(const TilePlan& plan, MeshStreamOptions options);
  ~MeshStreamWriter();
  MeshStreamWriter(const MeshStreamWriter&) = delete;
  MeshStreamWriter& operator=(const MeshStreamWriter&) = delete;
  // The piece of plan.tile_ids[index]. Throws quijibo::Error (a bad index, a failed write).
  void Add(std::size_t index, TilePiece piece);
  // Every piece added: writes the file (none when there is no triangle) and fills `summary` as
  // WeldTilePieces does (seconds excluded). Throws quijibo::Error.
  MeshStreamReport Finish(MeshingSummary* summary);

 private:
  struct State;
  std::unique_ptr<State> s_;
};

// MeshField streamed to stream.path: the file is WritePly(MeshField(field, options)) byte for byte
// (with the transform applied), the summary the same. Throws quijibo::Error; nothing is left on failure.
MeshStreamReport MeshFieldStreamed(const BatchField& field, const MeshingOptions& options,
                                   const MeshStreamOptions& stream, MeshingSummary* summary);

// Reads a binary little-endian PLY of float or double x y z vertices and a face list of triangles with
// int, uint, int64 or uint64 indices (what WritePly and the stream write, including 64-bit indices,
// which the assimp reader of ReadMesh does not take). Throws quijibo::Error naming the file.
struct IndexedMesh64 {
  std::vector<Vec3> vertices;
  std::vector<std::array<std::uint64_t, 3>> triangles;
  std::string index_type;
};
IndexedMesh64 ReadBinaryPly(const std::string& path);

}  // namespace quijibo::mesh
