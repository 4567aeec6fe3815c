// Regular 3D grids sampled at cell centres, and the `.qgrid` file that stores them.
//
// Convention (one for the whole toolkit): a grid of dims (nx, ny, nz) with spacing h and
// minimum corner m holds the value of cell (i, j, k) at the cell centre
//     x(i, j, k) = m + h * (i + 1/2, j + 1/2, k + 1/2),
// and stores values with i fastest, then j, then k: index = i + nx * (j + ny * k).
// The signed distance field, the weight field and the energy grid all use these same sample
// points, so nothing is shifted by half a cell between stages (the reference code is).
// Coordinates are in the fractal frame (see frame.h) unless a file says otherwise.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace quijibo {

using Vec3 = std::array<double, 3>;

// Where the samples of a grid are. Cubic cells, uniform spacing.
struct GridFrame {
  std::array<int, 3> dims{0, 0, 0};
  Vec3 min_corner{0.0, 0.0, 0.0};
  double spacing = 0.0;

  // A cubic grid of n^3 cells covering [center - side/2, center + side/2]^3.
  static GridFrame Cube(int n, const Vec3& center, double side);

  std::int64_t cell_count() const {
    return std::int64_t(dims[0]) * dims[1] * dims[2];
  }
  std::int64_t index(int i, int j, int k) const {
    return i + std::int64_t(dims[0]) * (j + std::int64_t(dims[1]) * k);
  }
  Vec3 cell_center(int i, int j, int k) const {
    return {min_corner[0] + spacing * (i + 0.5), min_corner[1] + spacing * (j + 0.5),
            min_corner[2] + spacing * (k + 0.5)};
  }
  Vec3 cell_center(std::int64_t index) const;
  Vec3 center() const;
  // Side lengths of the box the grid covers.
  Vec3 extent() const {
    return {spacing * dims[0], spacing * dims[1], spacing * dims[2]};
  }
  // Same box, n cells along the longest axis (used for coarse optimization levels).
  GridFrame resampled(int n) const;
  // Empty string when valid, else what is wrong.
  std::string Validate() const;
  // Also under this name: optim/, the energy evaluators and the Python module call it so.
  bool operator==(const GridFrame&) const = default;
};

// Values on a GridFrame. `quantity` says what they are ("signed-distance", "weight", ...).
struct ScalarGrid {
  GridFrame frame;
  std::vector<double> values;
  std::string quantity = "signed-distance";
  std::string coordinates = "fractal";  // "fractal" or "normalized" (the unit cube)

  double& at(int i, int j, int k) { return values[frame.index(i, j, k)]; }
  double at(int i, int j, int k) const { return values[frame.index(i, j, k)]; }
  // Trilinear interpolation between cell centres, clamped at the border (in double, unlike
  // the reference, which interpolates with float weights).
  double sample(const Vec3& p) const;
};

// The `.qgrid` file (documented in docs/formats.md):
//   bytes 0..7   magic "QJBGRID1"
//   bytes 8..11  uint32 little-endian length H of the header
//   H bytes      UTF-8 JSON header: {"dims":[nx,ny,nz], "min_corner":[x,y,z], "spacing":h,
//                "sample":"cell-center", "order":"x-fastest", "value_type":"float64-le",
//                "quantity":..., "coordinates":...}
//   then nx*ny*nz float64 little-endian values, x fastest.
// Writing goes to a temporary file renamed into place, so a failure leaves no partial file.
// Reading throws quijibo::Error naming the file and what is wrong.
void WriteGrid(const std::string& path, const ScalarGrid& grid);
ScalarGrid ReadGrid(const std::string& path);

// Signed distance of a ScalarGrid (fractal or any frame) extended beyond its box by the distance
// to the box: clamp-to-edge sampling plus |p - clamp(p)|, so the field keeps growing outside
// (the authors' code clamps only, so a far point sees the border value).
double ExtendedSample(const ScalarGrid& grid, const Vec3& p);

}  // namespace quijibo
