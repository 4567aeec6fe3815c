#include "monopole/shell.h"

#include <cmath>

#include "util/error.h"

namespace quijibo::monopole {

std::string ShellOptions::Validate() const {
  if (!std::isfinite(offset_cells) || offset_cells < 0.0)
    return "shell.offset_cells must be a non-negative number, found " +
           std::to_string(offset_cells);
  return {};
}

OffsetShell ComputeOffsetShell(const ScalarGrid& sdf, const ShellOptions& options) {
  if (const std::string why = options.Validate(); !why.empty()) throw Error(why);
  if (const std::string why = sdf.frame.Validate(); !why.empty()) throw Error("shell: " + why);
  if (std::int64_t(sdf.values.size()) != sdf.frame.cell_count())
    throw Error("shell: the grid has " + std::to_string(sdf.values.size()) + " values for " +
                std::to_string(sdf.frame.cell_count()) + " cells");
  const double level = options.offset_cells * sdf.frame.spacing;
  const auto& d = sdf.frame.dims;
  OffsetShell shell;
  for (int k = 1; k + 1 < d[2]; ++k)
    for (int j = 1; j + 1 < d[1]; ++j)
      for (int i = 1; i + 1 < d[0]; ++i) {
        if (!(sdf.at(i, j, k) >= level)) continue;
        if (sdf.at(i - 1, j, k) < level || sdf.at(i + 1, j, k) < level ||
            sdf.at(i, j - 1, k) < level || sdf.at(i, j + 1, k) < level ||
            sdf.at(i, j, k - 1) < level || sdf.at(i, j, k + 1) < level) {
          shell.cells.push_back(sdf.frame.index(i, j, k));
          shell.points.push_back(sdf.frame.cell_center(i, j, k));
        }
      }
  if (shell.points.empty())
    throw Error("shell: no cell lies just outside the offset surface sdf = " +
                std::to_string(level) + " (offset too large for the grid, or no surface)");
  return shell;
}

}  // namespace quijibo::monopole
