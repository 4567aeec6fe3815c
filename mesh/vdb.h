// OpenVDB volumes (.vdb, what Houdini and Blender read) for our cell-centred grids.
//
// Index convention: OpenVDB puts voxel (i, j, k) at index coordinates (i, j, k) and a linear
// transform maps them to world = voxel_size * (i, j, k) + translation, so voxel centres sit on
// integer coordinates. We set voxel_size = spacing and translation = min_corner + spacing / 2:
// voxel (i, j, k)'s centre is exactly our grid.cell_center(i, j, k).
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "mesh/triangle_mesh.h"
#include "quijibo/grid.h"

namespace quijibo::mesh {

// Writes `grid` as a dense FloatGrid named `name` (every cell an active voxel, values rounded
// to float). Quantity "signed-distance" is tagged as a level set (GRID_LEVEL_SET class, the
// background is the largest value), anything else as a fog volume. The file goes to a
// temporary name and is renamed into place. Throws quijibo::Error.
void WriteVdb(const std::string& path, const ScalarGrid& grid, const std::string& name = "sdf");

// Writes sparse samples as a FloatGrid `name` (a narrow band): voxel (i, j, k) centred at
// origin + spacing * (i, j, k), only the given voxels active, everything else `background`. Tagged
// as a fog volume with metadata quijibo_quantity, quijibo_coordinates and quijibo_iso. Atomic.
void WriteVdbSparse(const std::string& path, const Vec3& origin, double spacing,
                    const std::vector<std::array<int, 3>>& voxels, const std::vector<float>& values,
                    float background, double iso, const std::string& name, const std::string& quantity,
                    const std::string& coordinates);

// The same grid built piece by piece (the mesher's narrow band as its tiles finish, for streamed
// meshing), so that only OpenVDB's sparse tree is held, not the samples; Write gives the bytes
// WriteVdbSparse gives for the samples in the order added (but the file's random UUID), streamed to
// a temporary file and renamed into place.
class SparseVdbBuilder {
 public:
  SparseVdbBuilder(const Vec3& origin, double spacing, float background, double iso, const std::string& name,
                   const std::string& quantity, const std::string& coordinates);
  ~SparseVdbBuilder();
  SparseVdbBuilder(const SparseVdbBuilder&) = delete;
  SparseVdbBuilder& operator=(const SparseVdbBuilder&) = delete;
  void Add(const std::vector<std::array<int, 3>>& voxels, const std::vector<float>& values);
  void Write(const std::string& path) const;  // atomic; throws quijibo::Error
  std::int64_t memory_bytes() const;          // the tree's (OpenVDB's memUsage)
  std::int64_t active_voxels() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Volumes that Houdini and Blender use as they are (issue 16), from a welded triangle mesh:
//  - "surface": a narrow-band level set (GRID_LEVEL_SET) built by openvdb::tools::meshToLevelSet:
//    signed distance in the mesh's units, negative inside, background = half_width * voxel_size;
//  - "density": a fog volume (GRID_FOG_VOLUME): 1 inside, 0 outside, and across the band the
//    smooth ramp 0.5 - d / (2 half_width voxel_size) of the distance d (0.5 on the surface);
//  - optionally the raw field on its own band (`raw`, as WriteVdbSparse).
// Voxel (i, j, k) is centred at voxel_size * (i, j, k) (world origin on a voxel centre). The inside
// is found by OpenVDB's flood fill from the outside, so a surface cut open by the box faces gets
// an unreliable sign near the cut. Atomic; throws quijibo::Error.
struct VdbVolumeOptions {
  double voxel_size = 0.0;  // world units (> 0)
  double half_width = 3.0;  // narrow band half-width, voxels (>= 1)
  bool surface = true;
  bool density = true;
  std::string coordinates;  // metadata quijibo_coordinates
  std::string Validate() const;
};
struct VdbRawField {
  Vec3 origin{0.0, 0.0, 0.0};
  double spacing = 0.0;
  const std::vector<std::array<int, 3>>* voxels = nullptr;
  const std::vector<float>* values = nullptr;
  float background = 0.0f;
  double iso = 0.0;
  std::string name, quantity;
};
void WriteVdbVolumes(const std::string& path, const TriangleMesh& mesh, const VdbVolumeOptions& options,
                     const VdbRawField* raw = nullptr);

// Reads the FloatGrid `name` (the first FloatGrid when empty) back onto the grid its active
// voxels span. Needs a uniform linear transform. Throws quijibo::Error.
ScalarGrid ReadVdb(const std::string& path, const std::string& name = "");

}  // namespace quijibo::mesh
