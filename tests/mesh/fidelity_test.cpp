#include "mesh/fidelity.h"

#include <gtest/gtest.h>

#include <cmath>

#ifdef _OPENMP
#include <omp.h>
#endif

#include "mesh/mesh_fixtures.h"
#include "quijibo/julia_setup.h"
#include "util/error.h"
#include "quijibo/target.h"
#include "tests/ball_map.h"

namespace quijibo::mesh {
namespace {

ScalarGrid SphereTarget(double radius) {
  return AnalyticTarget("sphere:radius=" + std::to_string(radius), TargetGridFrame(60, FractalFrame{}));
}

// `m` as iterated with `detail` in its own frame: the caller makes it (MakeJuliaSetup) and hands it on.
std::shared_ptr<const RationalMap> Iterated(const RationalMap& m, double detail = kSmoothDetail) {
  JuliaSetupOptions s;
  s.detail = detail;
  return std::make_shared<const RationalMap>(MakeJuliaSetup(m, s).map);
}

// The fidelity of BallMap(radius) to the unit sphere, its n-step set after `iterations` (0: none).
Fidelity BallFidelity(double radius, int iterations) {
  FidelityOptions o;
  o.julia.iterations = iterations;
  if (iterations > 0) o.iterated = Iterated(testing::BallMap(radius));
  return MeasureSets(testing::BallMap(radius), SphereTarget(1.0), o);
}

TEST(Fidelity, AMapWhoseSetIsTheTargetScoresOneAndDoesNotLeak) {
  const Fidelity f = BallFidelity(1.0, 0);
  EXPECT_GT(f.one_step.iou, 0.97);
  EXPECT_EQ(f.one_step.leak_nodes, 0);
  EXPECT_FALSE(f.has_n_step);
}

TEST(Fidelity, ASetTooLargeLeaksOutOfTheShapeBox) {
  // The shape box B has half side 1.5 (radius 4, padding 0.125); a ball of radius 1.9 pokes out.
  const Fidelity f = BallFidelity(1.9, 0);
  EXPECT_GT(f.one_step.leak, 0.1);
  EXPECT_LT(f.one_step.iou, 0.2);
  // A smaller set is inside the target: IoU = (0.8 / 1)^3.
  const Fidelity g = BallFidelity(0.8, 0);
  EXPECT_NEAR(g.one_step.iou, 0.512, 0.03);
  EXPECT_EQ(g.one_step.leak_nodes, 0);
}

TEST(Fidelity, VolumeIoUEstimatesTheIoUOfTheVolumes) {
  // BallMap(0.8) inside the unit sphere: the volumes' IoU is 0.8^3.
  const Fidelity f = BallFidelity(0.8, 0);
  EXPECT_NEAR(f.one_step.volume_iou, 0.512, 0.01);
  // The n-step set of a map with its only root at the origin is its one-step set (as in
  // TheNStepSetOfAPowerMapIsTheUnitBall): the same volume, 0.512 again.
  const Fidelity g = BallFidelity(0.8, 2);
  ASSERT_TRUE(g.has_n_step);
  EXPECT_NEAR(g.n_step.volume_iou, 0.512, 0.01);
}

TEST(Fidelity, VolumeIoUIsFreeOfTheLatticesAliasing) {
  // An 8-node lattice over B grown 20 % (half side 2.1): the nodes nearest the centre sit at
  // (+-0.3, +-0.3, +-0.3), 0.52 from it, the next ones 0.99 away. Balls of radius 0.8 and 0.95
  // hold the same 8 nodes, so their node IoU is 1; their volumes' IoU is (0.8 / 0.95)^3 = 0.60.
  FidelityOptions o;
  o.lattice = 8;
  o.julia.iterations = 0;
  const Fidelity f = MeasureSets(testing::BallMap(0.8), SphereTarget(0.95), o);
  EXPECT_DOUBLE_EQ(f.one_step.iou, 1.0);
  EXPECT_LT(f.one_step.volume_iou, 0.85);
  EXPECT_GT(f.one_step.volume_iou, 0.3);
}

TEST(Fidelity, VolumeIoUDependsOnTheSeedNotOnTheThreads) {
  FidelityOptions o;
  o.lattice = 24;
  o.julia.iterations = 0;
  const RationalMap m = testing::BallMap(0.8);
  const ScalarGrid t = SphereTarget(1.0);
  const double a = MeasureSets(m, t, o).one_step.volume_iou;
#ifdef _OPENMP
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  const double one_thread = MeasureSets(m, t, o).one_step.volume_iou;
  omp_set_num_threads(threads);
  EXPECT_EQ(a, one_thread);
#endif
  EXPECT_EQ(a, MeasureSets(m, t, o).one_step.volume_iou);
  o.seed = 2;
  EXPECT_NE(a, MeasureSets(m, t, o).one_step.volume_iou);
}

TEST(Fidelity, TheNStepSetOfAPowerMapIsTheUnitBall) {
  // R(q) = q: every iterate keeps |q|, so the n-step set is the unit ball too.
  const Fidelity f = BallFidelity(1.0, 3);
  ASSERT_TRUE(f.has_n_step);
  EXPECT_NEAR(f.n_step.iou, f.one_step.iou, 0.02);
}

TEST(Fidelity, ChamferAndHausdorffOfTwoConcentricSpheres) {
  const TriangleMesh a = testing::Icosphere(4, {0, 0, 0}, 1.0), b = testing::Icosphere(4, {0, 0, 0}, 1.1);
  FidelityOptions o;
  o.surface_samples = 5000;
  Fidelity f;
  MeasureSurfaceDistances(b, a, o, f);
  const double diagonal = 2.0 * std::sqrt(3.0);  // of a's bounding box
  EXPECT_NEAR(f.chamfer * diagonal, 0.1, 0.01);
  EXPECT_NEAR(f.hausdorff * diagonal, 0.1, 0.015);
  Fidelity self;
  MeasureSurfaceDistances(a, a, o, self);
  EXPECT_LT(self.hausdorff, 1e-9);
}

TEST(Fidelity, ClosingFillsHolesSmallerThanItsCube) {
  // A 20^3 block of a 32^3 lattice with every other node of its interior removed (a sponge): the
  // closing by half side 1 fills it back; by 0 it is the set itself.
  const int n = 32;
  std::vector<char> sponge(std::size_t(n) * n * n, 0), block = sponge;
  for (int k = 6; k < 26; ++k)
    for (int j = 6; j < 26; ++j)
      for (int i = 6; i < 26; ++i) {
        const std::size_t c = std::size_t(i + n * (j + n * k));
        block[c] = 1;
        sponge[c] = (i + j + k) % 2 == 0 || i == 6 || i == 25 || j == 6 || j == 25 || k == 6 || k == 25;
      }
  EXPECT_EQ(Close(sponge, n, 0), sponge);
  EXPECT_EQ(Close(sponge, n, 1), block);
  EXPECT_EQ(Close(block, n, 2), block);
}

TEST(Fidelity, MeshDetailOfASphereIsTwoDimensionalAndGrowsWithWrinkles) {
  const TriangleMesh sphere = testing::Icosphere(5, {0, 0, 0}, 1.0);
  const MeshDetail d = MeasureMeshDetail(sphere, &sphere, 2.0);
  EXPECT_NEAR(d.area, 4 * M_PI, 0.05);
  EXPECT_NEAR(d.area_ratio, 1.0, 1e-12);
  EXPECT_EQ(d.components, 1);
  ASSERT_EQ(d.box_counts.size(), 5u);
  EXPECT_NEAR(d.dimension, 2.0, 0.1);
  // Radial wrinkles of wavelength ~ 1/20 of the side: more area, more boxes at the fine scales.
  TriangleMesh wrinkled = sphere;
  for (Vec3& v : wrinkled.vertices) {
    const double r = 1.0 + 0.08 * std::sin(40 * v[0]) * std::sin(40 * v[1]) * std::sin(40 * v[2]);
    for (double& x : v) x *= r;
  }
  const MeshDetail w = MeasureMeshDetail(wrinkled, &sphere, 2.0);
  EXPECT_GT(w.area_ratio, 1.1);
  EXPECT_GT(w.dimension, d.dimension + 0.05);
  // Two spheres: two components.
  TriangleMesh two = sphere;
  const int offset = int(two.vertices.size());
  for (Vec3 v : sphere.vertices) two.vertices.push_back({v[0] + 3, v[1], v[2]});
  for (auto t : sphere.triangles) two.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
  EXPECT_EQ(MeasureMeshDetail(two, nullptr, 2.0).components, 2);
  EXPECT_LT(MeasureMeshDetail(two, nullptr, 2.0).area_ratio, 0);
  EXPECT_THROW(MeasureMeshDetail(sphere, nullptr, 0.0), Error);
}

TEST(Fidelity, DetailKeepsTheOneStepSetAndChangesTheNStepSet) {
  // Two top roots and a bottom root: a set whose n-step iteration depends on the frame's scale.
  RationalMap m;
  m.top_roots = {{0, 0, 0, 0}, {0.5, 0.2, 0, 0}};
  m.top_exponents = {1.0, 1.5};
  m.bottom_roots = {{-1.2, 0.3, 0.1, 0}};
  m.bottom_exponents = {0.7};
  m.ln_C = 0.3;
  m.tau = m.beta = 60, m.ln_C *= 60;  // steep: |L| leaves 0 fast across the surface
  FidelityOptions o;
  o.lattice = 40;
  o.julia.iterations = 4;
  const ScalarGrid target = SphereTarget(1.0);
  o.iterated = Iterated(m);
  const Fidelity base = MeasureSets(m, target, o);
  o.iterated = Iterated(m, 20.0);
  const Fidelity more = MeasureSets(m, target, o);
  EXPECT_EQ(more.one_step.set_nodes, base.one_step.set_nodes);
  EXPECT_NE(more.n_step.set_nodes, base.n_step.set_nodes);
  // The n-step set is measured on the map as iterated, which the caller makes once: none, an error.
  o.iterated.reset();
  EXPECT_THROW(MeasureSets(m, target, o), Error);
}

TEST(Fidelity, RejectsBadOptions) {
  FidelityOptions o;
  o.lattice = 2;
  EXPECT_THROW(MeasureSets(testing::BallMap(1.0), SphereTarget(1.0), o), Error);
}

}  // namespace
}  // namespace quijibo::mesh
