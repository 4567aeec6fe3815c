// The offset shell Gamma+ of the 2015 paper (section 4.4), where the monopoles are fitted: the
// cells just outside the iso-surface sdf = offset_cells * h of the target's signed distance field.
//
// As the reference code (quijibo-code.md section 3.2): the shell points are the centres of the
// cells, border layer excluded, with sdf >= offset_cells * h that have a 6-neighbour with
// sdf < offset_cells * h. Unlike the reference we do not need its closest-point extension of the
// potential onto Gamma+ (100 projection steps per cell and a trilinear lookup of a gridded BEM
// field): our BEM evaluates P exactly at the shell points themselves.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "quijibo/grid.h"

namespace quijibo::monopole {

struct ShellOptions {
  double offset_cells = 5.0;  // reference code: 5 (its built-in default 3)

  // Empty string when valid, else what is wrong.
  std::string Validate() const;
};

struct OffsetShell {
  std::vector<Vec3> points;            // cell centres, in grid index order
  std::vector<std::int64_t> cells;     // their grid indices
};

// The offset shell of a signed distance field (negative inside, sampled at cell centres).
// Throws quijibo::Error for invalid options, a grid whose value count does not match its frame,
// or an empty shell (offset beyond the grid).
OffsetShell ComputeOffsetShell(const ScalarGrid& sdf, const ShellOptions& options = {});

}  // namespace quijibo::monopole
