// OpenVDB volumes (.vdb, what Houdini and Blender read) for our cell-centred grids.
//
// Index convention: OpenVDB puts voxel (i, j, k) at index coordinates (i, j, k) and a linear
// transform maps them to world = voxel_size * (i, j, k) + translation, so voxel centres sit on
// integer coordinates. We set voxel_size = spacing and translation = min_corner + spacing / 2:
// voxel (i, j, k)'s centre is exactly our grid.cell_center(i, j, k).
#pragma once

#include <array>
#include <string>
#include <vector>

#include "quijibo/grid.h"

namespace quijibo {

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

// Reads the FloatGrid `name` (the first FloatGrid when empty) back onto the grid its active
// voxels span. Needs a uniform linear transform. Throws quijibo::Error.
ScalarGrid ReadVdb(const std::string& path, const std::string& name = "");

}  // namespace quijibo
