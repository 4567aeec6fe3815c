// The .vdb volumes artists use (issue 16): read back with OpenVDB itself.
#include <gtest/gtest.h>
#include <openvdb/io/Stream.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/Interpolation.h>

#include <cmath>
#include <fstream>
#include <set>

#include "mesh/marching_cubes.h"
#include "mesh/triangle_mesh.h"
#include "mesh/vdb.h"
#include "mesh_fixtures.h"
#include "util/error.h"

namespace quijibo::mesh {
namespace {

using testing::TempDir;

openvdb::GridPtrVecPtr ReadGrids(const std::string& path) {
  openvdb::initialize();
  std::ifstream in(path, std::ios::binary);
  return openvdb::io::Stream(in).getGrids();
}

openvdb::FloatGrid::Ptr Find(const openvdb::GridPtrVecPtr& grids, const std::string& name) {
  for (const auto& g : *grids)
    if (g->getName() == name) return openvdb::gridPtrCast<openvdb::FloatGrid>(g);
  return nullptr;
}

TEST(VdbVolumes, LevelSetAndDensityOfAMeshedBall) {
  // A ball of radius 1.1 off the lattice's symmetry, meshed at 48^3 on [-2, 2]^3.
  BatchField field;
  field.evaluate = [](const Vec3* p, std::size_t n, double* v) {
    for (std::size_t i = 0; i < n; ++i)
      v[i] = std::sqrt((p[i][0] - 0.1) * (p[i][0] - 0.1) + p[i][1] * p[i][1] + (p[i][2] + 0.05) * (p[i][2] + 0.05)) - 1.1;
  };
  MeshingOptions o;
  o.resolution = 48;
  MeshingSummary s;
  FieldBand band;
  const TriangleMesh mesh = MeshField(field, o, &s, &band);
  ASSERT_TRUE(AnalyzeTopology(mesh).closed());
  TempDir dir;
  // The PLY a user would load next to the volume (float coordinates).
  WritePly(dir.file("ball.ply"), mesh);
  const TriangleMesh ply = ReadMesh(dir.file("ball.ply"));

  VdbVolumeOptions vo;
  vo.voxel_size = s.spacing;
  vo.half_width = 3.0;
  vo.coordinates = "fractal";
  VdbRawField raw;
  raw.origin = band.lattice.origin;
  raw.spacing = band.lattice.spacing;
  raw.voxels = &band.nodes;
  raw.values = &band.values;
  raw.background = 1e30f;
  raw.name = "julia";
  raw.quantity = "distance";
  WriteVdbVolumes(dir.file("ball.vdb"), mesh, vo, &raw);
  const auto grids = ReadGrids(dir.file("ball.vdb"));
  ASSERT_EQ(grids->size(), 3u);

  const auto surface = Find(grids, "surface");
  ASSERT_TRUE(surface);
  EXPECT_EQ(surface->getGridClass(), openvdb::GRID_LEVEL_SET);
  const float w = float(3.0 * s.spacing);
  EXPECT_NEAR(surface->background(), w, 1e-6 * w);
  EXPECT_NEAR(surface->voxelSize()[0], s.spacing, 1e-12);
  openvdb::tools::GridSampler<openvdb::FloatGrid, openvdb::tools::BoxSampler> phi(*surface);
  EXPECT_LT(phi.wsSample(openvdb::Vec3d(0.1, 0, -0.05)), 0.0f);  // deep inside: -background
  EXPECT_NEAR(phi.wsSample(openvdb::Vec3d(0.1, 0, -0.05)), -w, 1e-6 * w);
  EXPECT_GT(phi.wsSample(openvdb::Vec3d(1.9, 1.9, 1.9)), 0.0f);
  // Signed distance in the mesh's units: a voxel 1.5 voxels outside the ball reads about +1.5 voxels.
  EXPECT_NEAR(phi.wsSample(openvdb::Vec3d(0.1 + 1.1 + 1.5 * s.spacing, 0, -0.05)), 1.5 * s.spacing, 0.3 * s.spacing);
  // The zero crossing is within a voxel of every PLY vertex.
  double worst = 0;
  for (const Vec3& v : ply.vertices) worst = std::max(worst, double(std::abs(phi.wsSample(openvdb::Vec3d(v[0], v[1], v[2])))));
  EXPECT_LT(worst, s.spacing);

  const auto density = Find(grids, "density");
  ASSERT_TRUE(density);
  EXPECT_EQ(density->getGridClass(), openvdb::GRID_FOG_VOLUME);
  EXPECT_EQ(density->background(), 0.0f);
  openvdb::tools::GridSampler<openvdb::FloatGrid, openvdb::tools::BoxSampler> rho(*density);
  EXPECT_EQ(rho.wsSample(openvdb::Vec3d(0.1, 0, -0.05)), 1.0f);
  EXPECT_EQ(rho.wsSample(openvdb::Vec3d(1.9, 1.9, 1.9)), 0.0f);
  for (const Vec3& v : ply.vertices) EXPECT_NEAR(rho.wsSample(openvdb::Vec3d(v[0], v[1], v[2])), 0.5, 0.5 / 3 + 0.02);

  const auto julia = Find(grids, "julia");
  ASSERT_TRUE(julia);
  std::set<std::array<int, 3>> nodes(band.nodes.begin(), band.nodes.end());  // seam nodes come once per tile
  EXPECT_EQ(julia->activeVoxelCount(), openvdb::Index64(nodes.size()));

  // Bad options: no grid written.
  vo.voxel_size = 0;
  EXPECT_THROW(WriteVdbVolumes(dir.file("bad.vdb"), mesh, vo), Error);
  EXPECT_FALSE(std::filesystem::exists(dir.file("bad.vdb")));
}

}  // namespace
}  // namespace quijibo::mesh
