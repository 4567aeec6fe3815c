// The target stage's fractal frame: the trap scale (mesh/normalize.h ScaleToTrap, docs/fidelity.md §3b).
#include <gtest/gtest.h>

#include <cmath>

#include "experiments/pipeline/initial.h"
#include "experiments/pipeline/target.h"
#include "tests/mesh/mesh_fixtures.h"
#include "mesh/normalize.h"
#include "mesh/sdf.h"
#include "util/error.h"
#include "quijibo/rational_map.h"

namespace quijibo::pipeline {
namespace {

using mesh::FrameScale;
using mesh::NormalizationFor;
using mesh::ParseFrameScale;
using mesh::FrameScaleName;
using mesh::PlaceOriginInside;
using mesh::ScaleToTrap;
using mesh::ToFractalFrame;
using mesh::TriangleMesh;
using mesh::UnsignedDistance;
using mesh::WriteObj;

// A flat ellipsoid: semi-axes 1, 1, 0.1 (user units), a plate 20 times thinner than it is wide.
TriangleMesh Plate() {
  TriangleMesh m = testing::Icosphere(4);
  for (Vec3& v : m.vertices) v[2] *= 0.1;
  return m;
}

double DepthOfTheOrigin(const TriangleMesh& user, const FractalFrame& frame) {
  return UnsignedDistance(ToFractalFrame(user, frame), {Vec3{0.0, 0.0, 0.0}})[0];
}

TEST(FrameScale, TheTrapBallJustFitsInsideTheShape) {
  const TriangleMesh plate = Plate();
  const FractalFrame fixed = PlaceOriginInside(plate, NormalizationFor(plate), "plate");
  const double depth = DepthOfTheOrigin(plate, fixed);
  // The longest side 2 spans 0.75 of the unit cube and fractal_radius is 4: the plate's half
  // thickness 0.1 is about 0.15 deep at the origin (the deepest 48^3 cell centre).
  ASSERT_GT(depth, 0.1);
  ASSERT_LT(depth, 0.16);
  const FractalFrame trap = ScaleToTrap(plate, fixed, "plate");
  EXPECT_NEAR(trap.fractal_radius, fixed.fractal_radius / depth, 1e-12);
  EXPECT_NEAR(DepthOfTheOrigin(plate, trap), 1.0, 1e-9);
  // Only the scale changes: the origin and the normalization stay.
  EXPECT_EQ(trap.origin, fixed.origin);
  EXPECT_EQ(trap.scale, fixed.scale);
  EXPECT_EQ(ScaleToTrap(plate, fixed, "plate", 10.0).fractal_radius, 10.0);
  EXPECT_EQ(ParseFrameScale(FrameScaleName(FrameScale::kTrap)), FrameScale::kTrap);
  EXPECT_THROW(ParseFrameScale("big"), Error);
}

// The one-step set does not depend on the scale: the log-kernel fit works in cells and ln C
// absorbs the scale, so the trap frame's start is the fixed frame's, cell for cell.
TEST(FrameScale, TheStartsOneStepSetDoesNotDependOnTheScale) {
  const testing::TempDir dir;
  const std::string path = dir.file("plate.obj");
  WriteObj(path, Plate());
  TargetOptions fixed_options;
  fixed_options.mesh = path;
  fixed_options.resolution = 24;
  fixed_options.frame_scale = FrameScale::kFixed;
  TargetOptions trap_options = fixed_options;
  trap_options.frame_scale = FrameScale::kTrap;
  const TargetResult fixed = Target(fixed_options), trap = Target(trap_options);
  const double s = trap.frame.fractal_radius / fixed.frame.fractal_radius;
  ASSERT_GT(s, 4.0);  // the plate is thin: the trap frame is several times larger
  ASSERT_EQ(fixed.grid.values.size(), trap.grid.values.size());
  for (std::size_t i = 0; i < fixed.grid.values.size(); ++i)
    ASSERT_NEAR(trap.grid.values[i], s * fixed.grid.values[i], 1e-9 * s) << i;

  InitialGuessStageOptions guess;
  guess.kernel.roots = guess.kernel.max_roots = 40;
  guess.kernel.thin_walls = AutoSwitch::kOff;  // 40 roots as set: the thin-wall rule has tests of its own
  const RationalMap a = InitialGuess(fixed, guess).map, b = InitialGuess(trap, guess).map;
  std::int64_t cells = 0, same = 0, inside = 0;
  for (std::int64_t c = 0; c < fixed.grid.frame.cell_count(); ++c) {
    const bool in_a = OneStepLogModulus(a, fixed.grid.frame.cell_center(c)) < 0;
    const bool in_b = OneStepLogModulus(b, trap.grid.frame.cell_center(c)) < 0;
    ++cells, same += in_a == in_b, inside += in_a;
  }
  ASSERT_GT(inside, 0);
  EXPECT_GE(double(same), 0.999 * double(cells)) << same << " of " << cells;
}

}  // namespace
}  // namespace quijibo::pipeline
