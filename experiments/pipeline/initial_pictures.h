// Pictures of an initial guess (experiments/pipeline/initial.h): the start's one-step set and the
// potential on the slice z = 0, and the roots as a point cloud.
#pragma once

#include <string>

#include "monopole/bem.h"
#include "quijibo/grid.h"
#include "util/image.h"
#include "quijibo/rational_map.h"

namespace quijibo::pipeline {

// The potential on the slice z = 0 of the fractal frame (through the mesh's centre), grey from 0
// (black) to 1 (white), the target's outline in green, roots within two cells of the slice as
// discs: top roots blue, bottom roots red (the idea of the paper's Fig. 8). `size` pixels a side.
Image PotentialSlice(const monopole::ExteriorPotential& potential, const ScalarGrid& sdf, const RationalMap& map,
                     int size);

// The map's one-step set {L < 0} on the slice z = 0 against the target: both dark grey, set only
// orange, target only blue; roots within two cells of the slice as discs (top blue, bottom red).
Image StartSlice(const ScalarGrid& sdf, const RationalMap& map, int size);

// The roots as a coloured point cloud (top blue, bottom red), binary PLY, atomically; in the user
// frame when `user_frame`.
void WriteRootsPly(const std::string& path, const RationalMap& map, bool user_frame);

}  // namespace quijibo::pipeline
