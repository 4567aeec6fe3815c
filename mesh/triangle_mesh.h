// Triangle meshes: reading (OBJ, PLY, STL, OFF through assimp), validation, writing (PLY, OBJ)
// and the topology facts the signed distance field needs.
//
// Reading policy (one place, so every stage sees the same mesh):
//  - polygons are triangulated (assimp's aiProcess_Triangulate); points and lines are ignored;
//  - vertices with bit-identical positions are joined (our own exact weld; assimp's
//    JoinIdenticalVertices uses a bbox-relative epsilon and also compares normals and UVs), so
//    STL triangle soups become indexed meshes. Vertices are numbered in order of first use by
//    the faces (assimp does not keep the file's vertex numbering), unused vertices are dropped;
//  - degenerate triangles (a repeated vertex after welding, or exactly zero area) are DROPPED
//    and counted in MeshReadReport; they carry no surface and would only upset normals;
//  - anything else that is wrong throws quijibo::Error with one line naming the file and the
//    element: missing or unreadable file, unknown extension, empty file, parse error (assimp's
//    message), non-finite coordinate, a mesh left with no triangles.
// Coordinates pass through assimp's single precision (Debian builds it with float ai_real).
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "quijibo/grid.h"

namespace quijibo::mesh {

struct TriangleMesh {
  std::vector<Vec3> vertices;
  std::vector<std::array<int, 3>> triangles;  // counter-clockwise seen from outside
};

// What ReadMesh did to the file's faces.
struct MeshReadReport {
  std::int64_t faces_read = 0;            // triangles after triangulation, before cleaning
  std::int64_t degenerate_dropped = 0;    // repeated vertex or zero area
  std::int64_t non_triangles_ignored = 0; // point and line primitives
  std::int64_t corners_welded = 0;        // face corners that reused an existing vertex
};

// Reads `path` (.obj, .ply ascii/binary, .stl ascii/binary, .off; extension case-insensitive).
// Returns a valid mesh (see ValidateMesh) with at least one triangle; throws quijibo::Error.
TriangleMesh ReadMesh(const std::string& path, MeshReadReport* report = nullptr);

// Throws quijibo::Error("<name>: ...") unless the mesh has a triangle, finite coordinates and
// indices in range. `name` is the file (or whatever the message should name).
void ValidateMesh(const TriangleMesh& mesh, const std::string& name);

// Removes triangles with a repeated index or exactly zero area; returns how many.
std::int64_t RemoveDegenerateTriangles(TriangleMesh& mesh);

enum class PlyPrecision { kFloat32, kFloat64 };

// Binary little-endian PLY ("float x y z" or "double x y z", faces as "list uchar int
// vertex_indices"), written atomically. Float32 is what every viewer reads; choose Float64 for
// a lossless round trip.
void WritePly(const std::string& path, const TriangleMesh& mesh,
              PlyPrecision precision = PlyPrecision::kFloat32);

// Wavefront OBJ with shortest round-trip decimal coordinates and 1-based faces, atomically.
void WriteObj(const std::string& path, const TriangleMesh& mesh);

struct BoundingBox {
  Vec3 min{0.0, 0.0, 0.0};
  Vec3 max{0.0, 0.0, 0.0};
};
// Bounding box of the vertices (the mesh must have at least one vertex).
BoundingBox ComputeBoundingBox(const TriangleMesh& mesh);

// Edge facts: an edge used by one face is a boundary (a hole), by more than two non-manifold;
// an edge whose two faces traverse it in the same direction is misoriented.
struct MeshTopology {
  std::int64_t edges = 0;
  std::int64_t boundary_edges = 0;
  std::int64_t non_manifold_edges = 0;
  std::int64_t misoriented_edges = 0;
  // Volume enclosed (divergence theorem, about the bbox centre); negative when the faces
  // point inwards. Only meaningful for closed meshes.
  double signed_volume = 0.0;
  bool closed() const { return boundary_edges == 0 && non_manifold_edges == 0; }
};
MeshTopology AnalyzeTopology(const TriangleMesh& mesh);

// Reverses every triangle's orientation.
void FlipOrientation(TriangleMesh& mesh);

}  // namespace quijibo::mesh
