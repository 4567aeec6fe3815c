// mesh/decimate.h: the budget is met, a mesh under it is kept, the shape stays where it was.
#include "mesh/decimate.h"

#include <gtest/gtest.h>

#include <cmath>

#include "mesh/mesh_fixtures.h"

namespace quijibo::mesh {
namespace {

double MaxRadiusError(const TriangleMesh& m, double radius) {
  double worst = 0;
  for (const Vec3& v : m.vertices) worst = std::max(worst, std::abs(std::hypot(v[0], v[1], v[2]) - radius));
  return worst;
}

TEST(Decimate, MeetsTheBudgetAndKeepsTheShape) {
  const TriangleMesh sphere = testing::Icosphere(6);  // 81,920 triangles
  DecimateSummary s;
  const TriangleMesh d = Decimate(sphere, {.max_triangles = 5000}, &s);
  EXPECT_EQ(s.triangles_in, 81920);
  EXPECT_LE(s.triangles_out, 5000);
  EXPECT_GT(s.triangles_out, 2500);  // the simplifier stops near the budget, not far below
  EXPECT_EQ(std::int64_t(d.triangles.size()), s.triangles_out);
  EXPECT_FALSE(s.clustered);
  EXPECT_LT(MaxRadiusError(d, 1.0), 0.02);  // vertices stay on the sphere
  const MeshTopology t = AnalyzeTopology(d);
  EXPECT_EQ(t.boundary_edges, 0);  // still closed
  for (const auto& tri : d.triangles)
    for (int v : tri) ASSERT_LT(std::size_t(v), d.vertices.size());
}

TEST(Decimate, WhereCollapsesStopClusteringReachesTheBudget) {
  // 400 small separate spheres, a budget of one triangle each and an error bound (0.1 % of the
  // extent) that stops the edge collapses long before it: clustering takes the rest.
  TriangleMesh many;
  for (int i = 0; i < 400; ++i) {
    const TriangleMesh s = testing::Icosphere(2, {double(i % 20), double(i / 20), 0.0}, 0.3);
    const int base = int(many.vertices.size());
    many.vertices.insert(many.vertices.end(), s.vertices.begin(), s.vertices.end());
    for (auto t : s.triangles) many.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
  }
  DecimateSummary s;
  const TriangleMesh d = Decimate(many, {.max_triangles = 400, .max_relative_error = 0.001}, &s);
  EXPECT_LE(s.triangles_out, 400);
  EXPECT_GT(s.triangles_out, 0);
  EXPECT_TRUE(s.clustered);
}

TEST(Decimate, UnderTheBudgetIsKept) {
  const TriangleMesh sphere = testing::Icosphere(2);
  DecimateSummary s;
  const TriangleMesh d = Decimate(sphere, {.max_triangles = 100000}, &s);
  EXPECT_EQ(d.triangles.size(), sphere.triangles.size());
  EXPECT_EQ(d.vertices.size(), sphere.vertices.size());
  EXPECT_EQ(s.triangles_out, s.triangles_in);
  EXPECT_LT(MaxRadiusError(d, 1.0), 1e-6);
}

}  // namespace
}  // namespace quijibo::mesh
