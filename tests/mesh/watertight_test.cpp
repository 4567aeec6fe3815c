// Surface following (issue 16): the sparse mesher leaves no open edge away from the box faces, and
// the summary's open-edge and component counts are right.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <set>

#include "mesh/marching_cubes.h"
#include "mesh/triangle_mesh.h"
#include "mesh_fixtures.h"
#include "quijibo_command.h"

namespace quijibo::mesh {
namespace {

using testing::Lambda;

// A ball and a capsule thinner than a cell poking out of it: the capsule's axis runs along a
// lattice line of odd index, so no node of the search (stride 2 and coarser) is inside it, and
// the coarse search only reaches the part near the ball.
// Box [-2, 2]^3 at 64 cells: nodes at -2 + i / 16; the axis is y = z = -2 + 33 / 16.
double BallAndCapsule(const Vec3& p) {
  const double y0 = -2 + 33.0 / 16, z0 = y0, r = 0.3 / 16;
  const double ball = std::sqrt((p[0] + 1) * (p[0] + 1) + p[1] * p[1] + p[2] * p[2]) - 0.5;
  const double x = std::clamp(p[0], -1.0, 1.5);
  const double capsule = std::sqrt((p[0] - x) * (p[0] - x) + (p[1] - y0) * (p[1] - y0) + (p[2] - z0) * (p[2] - z0)) - r;
  return std::min(ball, capsule);
}

MeshingOptions SmallSparse() {
  MeshingOptions o;
  o.resolution = 64;
  o.tile_cells = 16;
  o.search_min_cells = 8;
  return o;
}

TEST(Watertight, SurfaceFollowingClosesWhatTheCoarseSearchCut) {
  const BatchField field = Lambda(BallAndCapsule);
  MeshingOptions o = SmallSparse();
  // The coarse search alone cuts the capsule open where it leaves the ball's neighbourhood ...
  o.follow_surface = false;
  MeshingSummary cut;
  const TriangleMesh open = MeshField(field, o, &cut);
  EXPECT_GT(cut.open_edges_inside, 0) << "the fixture must defeat the coarse search";
  EXPECT_EQ(cut.open_edges_inside, AnalyzeTopology(open).boundary_edges);
  EXPECT_EQ(cut.blocks_followed, 0);
  // ... surface following meshes all of it: closed, and the same mesh as dense meshing.
  o.follow_surface = true;
  MeshingSummary s, d;
  const TriangleMesh sparse = MeshField(field, o, &s);
  EXPECT_GT(s.blocks_followed, 0);
  EXPECT_GT(s.follow_evaluations, 0);
  EXPECT_EQ(s.open_edges, 0);
  EXPECT_EQ(s.open_edges_inside, 0);
  EXPECT_EQ(s.components, 1);
  EXPECT_TRUE(AnalyzeTopology(sparse).closed());
  o.sparse = false;
  const TriangleMesh dense = MeshField(field, o, &d);
  EXPECT_EQ(d.blocks_followed, 0);
  EXPECT_EQ(sparse.vertices, dense.vertices);
  EXPECT_EQ(sparse.triangles, dense.triangles);
  // The capsule reaches x = 1.5: far beyond what the search found.
  double max_x = -2;
  for (const Vec3& v : sparse.vertices) max_x = std::max(max_x, v[0]);
  EXPECT_GT(max_x, 1.5);
}

// A surface cut by the box: open edges there are counted, but not as inside ones; components are
// counted.
TEST(Watertight, OpenEdgesOnTheBoxFacesAreSeparated) {
  // Two balls, one cut by the face x = 2 of the box.
  const BatchField field = Lambda([](const Vec3& p) {
    const double a = std::sqrt((p[0] - 1.9) * (p[0] - 1.9) + p[1] * p[1] + p[2] * p[2]) - 0.6;
    const double b = std::sqrt((p[0] + 1) * (p[0] + 1) + p[1] * p[1] + p[2] * p[2]) - 0.5;
    return std::min(a, b);
  });
  for (bool sparse : {true, false}) {
    MeshingOptions o = SmallSparse();
    o.sparse = sparse;
    MeshingSummary s;
    const TriangleMesh m = MeshField(field, o, &s);
    const MeshTopology t = AnalyzeTopology(m);
    EXPECT_GT(s.open_edges, 0);
    EXPECT_EQ(s.open_edges, t.boundary_edges);
    EXPECT_EQ(s.open_edges_inside, 0);
    EXPECT_EQ(s.components, 2);
    for (const auto& tri : m.triangles)  // every open edge lies on x = 2 (sanity of the fixture)
      for (int c = 0; c < 3; ++c) ASSERT_LT(m.vertices[tri[c]][0], 2.0 + 1e-12);
  }
}

using nlohmann::json;
using testing::CommandResult;
using testing::RunQuijibo;

// The shape modulus of the bunny (the baseline's polynomial and parameters) at 128^3, speck removal
// off: neither mesh has an open edge away from the box faces, and the sparse mesh is the dense one
// minus whole components (specks whose neighbourhood the search never reaches: 34 of 499 here,
// docs/benchmarks.md §9), every sparse triangle being a dense triangle. `modulus` takes the
// mesher's shared options.
TEST(ModulusCli, BunnyModulusMeshIsWatertightAndSparseIsDenseMinusComponents) {
  const auto dir = std::filesystem::temp_directory_path() / "quijibo_modulus_watertight";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const std::string src = QUIJIBO_SOURCE_DIR;
  const std::string base = "modulus " + src + "/data/bunny.obj --poly " + src +
                           "/data/sm-baseline-poly10.json --alpha 30 --beta -0.02 --box -0.5 -0.5 -0.5 0.5 0.5 0.5 "
                           "-r 128 --sdf-resolution 64 --speck-removal off -o ";
  const std::string sparse = (dir / "s.ply").string(), dense = (dir / "d.ply").string();
  const CommandResult rs = RunQuijibo(base + sparse);
  ASSERT_EQ(rs.code, 0) << rs.out;
  const CommandResult rd = RunQuijibo(base + dense + " --dense");
  ASSERT_EQ(rd.code, 0) << rd.out;
  const json s = json::parse(rs.out)["result"], d = json::parse(rd.out)["result"];
  EXPECT_TRUE(s["sparse"].get<bool>());
  EXPECT_FALSE(d["sparse"].get<bool>());
  EXPECT_FALSE(s["speck_removal"].get<bool>());
  EXPECT_EQ(s["specks_removed"], 0);
  EXPECT_GT(s["triangles"].get<int>(), 100000);
  EXPECT_EQ(s["open_edges_inside"], 0);
  EXPECT_EQ(d["open_edges_inside"], 0);
  EXPECT_LE(s["components"].get<int>(), d["components"].get<int>());
  EXPECT_GE(s["components"].get<int>(), d["components"].get<int>() * 9 / 10);
  // Every sparse triangle (as its corner positions) is a dense triangle.
  auto key = [](const TriangleMesh& m, const std::array<int, 3>& t) {
    std::array<Vec3, 3> p{m.vertices[t[0]], m.vertices[t[1]], m.vertices[t[2]]};
    std::rotate(p.begin(), std::min_element(p.begin(), p.end()), p.end());
    return p;
  };
  const TriangleMesh ms = ReadMesh(sparse), md = ReadMesh(dense);
  std::set<std::array<Vec3, 3>> all;
  for (const auto& t : md.triangles) all.insert(key(md, t));
  std::int64_t missing = 0;
  for (const auto& t : ms.triangles) missing += !all.count(key(ms, t));
  EXPECT_EQ(missing, 0);
  EXPECT_EQ(std::int64_t(ms.triangles.size()), s["triangles"].get<std::int64_t>());
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace quijibo::mesh
