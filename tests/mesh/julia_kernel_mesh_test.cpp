// Meshes from the vectorized Julia kernels (vector and fused) are the scalar kernel's meshes, bit for bit, on the test
// maps (n = 1 to 4, zero roots, root translation, rotation), and do not depend on the thread count.
#include <gtest/gtest.h>
#include <omp.h>

#include "mesh/julia_field.h"
#include "mesh/marching_cubes.h"
#include "mesh_fixtures.h"
#include "quijibo/rational_map.h"

namespace quijibo::mesh {
namespace {

class JuliaKernelMesh : public ::testing::TestWithParam<std::tuple<int, int>> {};

TEST_P(JuliaKernelMesh, VectorAndScalarKernelsGiveTheSameMesh) {
  const auto [iterations, variant] = GetParam();
  const RationalMap map = testing::SmallSetMap(variant == 1);
  JuliaOptions j;
  j.iterations = iterations;
  if (variant == 2) {
    j.root_translation = {0.05, -0.1, 0.02, 0.1};
    j.placement = SampleTransform::AxisAngle({0, 1, 1}, 25, {0, 0, 0});
  }
  JuliaFieldStats vs, ss;
  const BatchField vector = MakeJuliaField(map, j, 0.0, Precision::kDouble, &vs, JuliaKernel::kVector);
  const BatchField scalar = MakeJuliaField(map, j, 0.0, Precision::kDouble, &ss, JuliaKernel::kScalar);
  MeshingOptions o;
  o.resolution = 64;
  o.tile_cells = 16;
  o.search_min_cells = 8;
  MeshingSummary sv, sc;
  const TriangleMesh mv = MeshField(vector, o, &sv);
  const TriangleMesh mc = MeshField(scalar, o, &sc);
  ASSERT_GT(mc.triangles.size(), 200u);
  EXPECT_EQ(mv.vertices, mc.vertices);
  EXPECT_EQ(mv.triangles, mc.triangles);
  EXPECT_EQ(sv.nodes_evaluated, sc.nodes_evaluated);
  EXPECT_EQ(sv.bisection_evaluations, sc.bisection_evaluations);
  EXPECT_EQ(vs.escaped.load(), ss.escaped.load());
  EXPECT_EQ(vs.non_finite.load(), ss.non_finite.load());
  EXPECT_EQ(vs.applications.load(), ss.applications.load());
  if (iterations > 1) {
    EXPECT_GT(vs.escaped.load(), 0);
  }
  // The fused kernel (vector_math.h): values within its bounds of the others', and so far the same mesh.
  const TriangleMesh mf = MeshField(MakeJuliaField(map, j, 0.0, Precision::kDouble, nullptr, JuliaKernel::kFused), o);
  EXPECT_EQ(mf.triangles, mc.triangles);
  EXPECT_EQ(mf.vertices, mc.vertices);

  // One thread: the same mesh (a node's value does not depend on its batch).
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  const TriangleMesh one = MeshField(vector, o);
  omp_set_num_threads(threads);
  EXPECT_EQ(testing::Canonical(one), testing::Canonical(mv));
  EXPECT_EQ(one.vertices, mv.vertices);
}

// n = 1..4; variant 0: plain, 1: zero roots, 2: root translation and a rotated box.
INSTANTIATE_TEST_SUITE_P(Maps, JuliaKernelMesh, ::testing::Combine(::testing::Range(1, 5), ::testing::Range(0, 3)));

}  // namespace
}  // namespace quijibo::mesh
