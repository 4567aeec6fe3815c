#include "mesh/fidelity.h"

#include <gtest/gtest.h>

#include <cmath>

#include "mesh/mesh_fixtures.h"
#include "quijibo/error.h"
#include "quijibo/target.h"

namespace quijibo::mesh {
namespace {

// One top root at the centre: L = ln C + log|q|, the one-step set is the ball of radius e^-lnC.
RationalMap Ball(double radius) {
  RationalMap m;
  m.top_roots = {{0, 0, 0, 0}};
  m.top_exponents = {1.0};
  m.ln_C = -std::log(radius);
  return m;
}

ScalarGrid SphereTarget(double radius) {
  return AnalyticTarget("sphere:radius=" + std::to_string(radius), TargetGridFrame(60, FractalFrame{}));
}

TEST(Fidelity, AMapWhoseSetIsTheTargetScoresOneAndDoesNotLeak) {
  FidelityOptions o;
  o.julia.iterations = 0;
  const Fidelity f = MeasureSets(Ball(1.0), SphereTarget(1.0), o);
  EXPECT_GT(f.one_step.iou, 0.97);
  EXPECT_EQ(f.one_step.leak_nodes, 0);
  EXPECT_FALSE(f.has_n_step);
}

TEST(Fidelity, ASetTooLargeLeaksOutOfTheShapeBox) {
  // The shape box B has half side 1.5 (radius 4, padding 0.125); a ball of radius 1.9 pokes out.
  FidelityOptions o;
  o.julia.iterations = 0;
  const Fidelity f = MeasureSets(Ball(1.9), SphereTarget(1.0), o);
  EXPECT_GT(f.one_step.leak, 0.1);
  EXPECT_LT(f.one_step.iou, 0.2);
  // A smaller set is inside the target: IoU = (0.8 / 1)^3.
  const Fidelity g = MeasureSets(Ball(0.8), SphereTarget(1.0), o);
  EXPECT_NEAR(g.one_step.iou, 0.512, 0.03);
  EXPECT_EQ(g.one_step.leak_nodes, 0);
}

TEST(Fidelity, TheNStepSetOfAPowerMapIsTheUnitBall) {
  // R(q) = q: every iterate keeps |q|, so the n-step set is the unit ball too.
  FidelityOptions o;
  o.julia.iterations = 3;
  const Fidelity f = MeasureSets(Ball(1.0), SphereTarget(1.0), o);
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

TEST(Fidelity, RejectsBadOptions) {
  FidelityOptions o;
  o.lattice = 2;
  EXPECT_THROW(MeasureSets(Ball(1.0), SphereTarget(1.0), o), Error);
}

}  // namespace
}  // namespace quijibo::mesh
