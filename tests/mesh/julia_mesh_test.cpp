// Meshing a real Julia set: dense = sparse, thread-count independence, no NaN, manifold.
#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <set>

#include "mesh/julia_field.h"
#include "mesh/marching_cubes.h"
#include "mesh/pictures.h"
#include "mesh_fixtures.h"
#include "quijibo/rational_map.h"

namespace quijibo::mesh {
namespace {

using testing::Canonical;

// n = 3 and 4 have specks smaller than a cell next to the surface, which a search on corner signs
// alone missed (4 triangles of ~30,000); the value margin keeps their blocks.
class JuliaMeshIterations : public ::testing::TestWithParam<std::tuple<int, int>> {};

TEST_P(JuliaMeshIterations, DenseAndSparseAgreeAndThreadsDoNotMatter) {
  const auto [iterations, search_stride] = GetParam();
  const RationalMap map = testing::SmallSetMap();
  JuliaOptions j;
  j.iterations = iterations;
  JuliaFieldStats stats;
  const BatchField field = MakeJuliaField(map, j, 0.0, Precision::kDouble, &stats);
  MeshingOptions o;
  o.resolution = 64;
  o.tile_cells = 16;
  o.search_stride = search_stride;
  o.search_min_cells = 8;  // a sparse search at this small resolution
  MeshingSummary ss, sd;
  const TriangleMesh sparse = MeshField(field, o, &ss);
  ASSERT_GT(sparse.triangles.size(), 500u);
  EXPECT_EQ(ss.search_stride, search_stride);
  EXPECT_LT(ss.nodes_evaluated, 65 * 65 * 65);
  EXPECT_GT(stats.escaped.load(), 0);
  o.sparse = false;
  const TriangleMesh dense = MeshField(field, o, &sd);
  EXPECT_EQ(sparse.triangles.size(), dense.triangles.size());
  EXPECT_EQ(sparse.vertices, dense.vertices);
  EXPECT_EQ(Canonical(sparse), Canonical(dense));
  for (const Vec3& v : sparse.vertices)
    for (double c : v) ASSERT_TRUE(std::isfinite(c));
  const MeshTopology t = AnalyzeTopology(sparse);
  EXPECT_EQ(t.non_manifold_edges, 0);
  EXPECT_EQ(t.misoriented_edges, 0);
  EXPECT_EQ(ss.non_finite_values, 0);
  // Watertight away from the box faces (surface following), in both modes; the summary counts open
  // edges like AnalyzeTopology.
  EXPECT_EQ(ss.open_edges, t.boundary_edges);
  EXPECT_EQ(ss.open_edges_inside, 0);
  EXPECT_EQ(sd.open_edges_inside, 0);
  EXPECT_EQ(ss.components, sd.components);

  // With speck removal off the two modes still give the same mesh, bit for bit: the search found
  // every one-node speck of this map too.
  o.remove_specks = false;
  MeshingSummary ks, kd;
  const TriangleMesh dense_all = MeshField(field, o, &kd);
  o.sparse = true;
  const TriangleMesh sparse_all = MeshField(field, o, &ks);
  EXPECT_EQ(sparse_all.vertices, dense_all.vertices);
  EXPECT_EQ(sparse_all.triangles, dense_all.triangles);
  EXPECT_EQ(ks.specks_removed, 0);
  EXPECT_EQ(kd.triangles - sd.triangles, 8 * sd.specks_removed);
  EXPECT_EQ(ks.open_edges_inside, 0);
  o.remove_specks = true;

  o.sparse = true;
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  const TriangleMesh one = MeshField(field, o);
  omp_set_num_threads(threads);
  EXPECT_EQ(one.vertices, sparse.vertices);
  EXPECT_EQ(one.triangles, sparse.triangles);
}

INSTANTIATE_TEST_SUITE_P(JuliaMesh, JuliaMeshIterations,
                         ::testing::Combine(::testing::Values(2, 3, 4), ::testing::Values(4, 8)));

TEST(JuliaMesh, PicturesHaveTheRightSizeAndColours) {
  const RationalMap map = testing::SmallSetMap();
  JuliaOptions j;
  j.iterations = 1;
  SliceView v;
  v.size = 64;
  v.max_corner = {2, 1, 2};  // 4 x 3: 64 x 48 pixels on the x-y plane
  const Image img = ModulusVersorSlice(map, j, v);
  EXPECT_EQ(img.width, 2 * 64 + 8);
  EXPECT_EQ(img.height, 48);
  // Against a target: a ball of radius 0.3 at the origin inside the set gives both-inside pixels.
  ScalarGrid target;
  target.frame = GridFrame::Cube(16, {0, 0, 0}, 4.0);
  target.values.resize(target.frame.cell_count());
  for (std::int64_t c = 0; c < target.frame.cell_count(); ++c) {
    const Vec3 p = target.frame.cell_center(c);
    target.values[c] = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]) - 0.3;
  }
  SliceAgreement a;
  const Image s = SliceAgainstTarget(MakeJuliaField(map, j), target, v, &a);
  EXPECT_EQ(s.width, 64);
  EXPECT_GT(a.both_inside, 0);
  EXPECT_EQ(a.both_inside + a.both_outside + a.julia_only + a.target_only, 64 * 48);
  const Image r = RenderMesh(MeshField(MakeJuliaField(map, j), MeshingOptions{.resolution = 32}), 64, 3);
  EXPECT_EQ(r.width, 192);
  int shaded = 0;
  for (const Rgb& p : r.pixels) shaded += !(p.r == 255 && p.g == 255 && p.b == 255);
  EXPECT_GT(shaded, 100);
}

}  // namespace
}  // namespace quijibo::mesh
