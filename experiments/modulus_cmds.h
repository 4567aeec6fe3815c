// Pieces of `quijibo modulus` / `quijibo portal` that `quijibo run` also uses to check an
// experiment before running it (experiments/modulus_cmds.cpp).
#pragma once

#include <memory>
#include <string>

#include "quijibo/grid.h"
#include "quijibo/mask.h"
#include "quijibo/modulus.h"

namespace quijibo::cli {

// The grid of an "sdf" mask: a .qgrid as is; a mesh (.obj/.ply/.stl/.off) normalized like a mesh
// target (bounding box centred at the origin, longest side 100/110) with its signed distance on
// [-0.5, 0.5]^3 at `sdf_resolution` cells, so a mask made from the target's own mesh lines up with
// it. Meshes are read once per loader (cached by path).
MaskGridLoader MakeMaskGridLoader(int sdf_resolution);

// A --params file: {"alpha": A, "beta": B, "origin_offset": [ox, oy, oz]}, A and B numbers or
// parameter fields (quijibo/mask.h). Keys present override `so`. Throws quijibo::Error naming the
// file and JSON pointer.
void ReadModulusParams(const std::string& path, ShapeModulusOptions& so, int sdf_resolution);

}  // namespace quijibo::cli
