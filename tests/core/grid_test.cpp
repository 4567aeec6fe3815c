#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>

#include "util/error.h"
#include "quijibo/grid.h"

namespace quijibo {
namespace {

TEST(Grid, CellCentresAndIndexing) {
  const GridFrame f = GridFrame::Cube(4, {0, 0, 0}, 2.0);
  EXPECT_DOUBLE_EQ(f.spacing, 0.5);
  const Vec3 c = f.cell_center(0, 0, 0);
  EXPECT_DOUBLE_EQ(c[0], -0.75);
  const Vec3 d = f.cell_center(f.index(3, 2, 1));
  EXPECT_DOUBLE_EQ(d[0], 0.75);
  EXPECT_DOUBLE_EQ(d[1], 0.25);
  EXPECT_DOUBLE_EQ(d[2], -0.25);
}

TEST(Grid, TrilinearSampleIsExactOnLinearFields) {
  ScalarGrid g;
  g.frame = GridFrame::Cube(5, {0.1, -0.2, 0.3}, 3.0);
  g.values.resize(g.frame.cell_count());
  for (std::int64_t c = 0; c < g.frame.cell_count(); ++c) {
    const Vec3 p = g.frame.cell_center(c);
    g.values[c] = 2 * p[0] - p[1] + 0.5 * p[2];
  }
  const Vec3 p{0.33, 0.1, -0.4};
  EXPECT_NEAR(g.sample(p), 2 * p[0] - p[1] + 0.5 * p[2], 1e-12);
}

TEST(Grid, FileRoundTripAndErrors) {
  const std::string path = (std::filesystem::temp_directory_path() / "quijibo_grid_test.qgrid");
  ScalarGrid g;
  g.frame = GridFrame::Cube(3, {0, 0, 0}, 1.0);
  g.values.resize(27);
  for (int c = 0; c < 27; ++c) g.values[c] = c * 0.25 - 1;
  WriteGrid(path, g);
  const ScalarGrid r = ReadGrid(path);
  EXPECT_EQ(r.frame, g.frame);
  EXPECT_EQ(r.values, g.values);
  // Truncated file: a clear error naming the file.
  std::filesystem::resize_file(path, std::filesystem::file_size(path) - 8);
  try {
    ReadGrid(path);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("truncated"), std::string::npos);
  }
  std::filesystem::remove(path);
  EXPECT_THROW(ReadGrid(path), Error);
}

}  // namespace
}  // namespace quijibo
