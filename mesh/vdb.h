// OpenVDB volumes (.vdb, what Houdini and Blender read) for our cell-centred grids.
//
// Index convention: OpenVDB puts voxel (i, j, k) at index coordinates (i, j, k) and a linear
// transform maps them to world = voxel_size * (i, j, k) + translation, so voxel centres sit on
// integer coordinates. We set voxel_size = spacing and translation = min_corner + spacing / 2:
// voxel (i, j, k)'s centre is exactly our grid.cell_center(i, j, k).
#pragma once

#include <string>

#include "quijibo/grid.h"

namespace quijibo {

// Writes `grid` as a dense FloatGrid named `name` (every cell an active voxel, values rounded
// to float). Quantity "signed-distance" is tagged as a level set (GRID_LEVEL_SET class, the
// background is the largest value), anything else as a fog volume. The file goes to a
// temporary name and is renamed into place. Throws quijibo::Error.
void WriteVdb(const std::string& path, const ScalarGrid& grid, const std::string& name = "sdf");

// Reads the FloatGrid `name` (the first FloatGrid when empty) back onto the grid its active
// voxels span. Needs a uniform linear transform. Throws quijibo::Error.
ScalarGrid ReadVdb(const std::string& path, const std::string& name = "");

}  // namespace quijibo
