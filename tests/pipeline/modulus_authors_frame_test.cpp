// `--authors-frame` (docs/modulus-portals.md): the node count it assumes and the authors' a, b
// (distances in the mesh file's own units, exp(a (d - b))) turned into this toolkit's alpha, beta.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "experiments/pipeline/modulus.h"
#include "methods/modulus_target.h"
#include "util/error.h"
#include "methods/modulus.h"
#include "tests/mesh/mesh_fixtures.h"

namespace quijibo::pipeline {
namespace {

// A sphere of radius 5 about (3, -2, 7) in the file's units, so that s is far from 1.
constexpr double kRadius = 5.0;
const Vec3 kCentre{3.0, -2.0, 7.0};
constexpr int kRes = 20;

// Written into the test's own folder: ctest runs the tests of this file in parallel.
std::string SphereObj(const testing::TempDir& dir) {
  const std::string path = dir.file("sphere.obj");
  mesh::WriteObj(path, testing::Icosphere(3, kCentre, kRadius));
  return path;
}

double ExpectedScale() {
  const mesh::BoundingBox bb = mesh::ComputeBoundingBox(testing::Icosphere(3, kCentre, kRadius));
  double longest = 0;
  for (int a = 0; a < 3; ++a) longest = std::max(longest, bb.max[a] - bb.min[a]);
  return kUnitFrameLongestSide / longest;
}

TEST(AuthorsFrameUnits, TheStageConvertsTheirAlphaAndBetaAndAssumesResNodes) {
  const testing::TempDir dir;
  const std::string obj = SphereObj(dir);
  const double s = ExpectedScale();
  ModulusStageOptions o;
  o.sdf_resolution = kRes;
  o.authors_frame = {kRes};
  o.shape.alpha = 3.0;  // their a and b, file units
  o.shape.beta = 0.5;
  o.output.meshing.resolution = 12;
  const ModulusStageResult r = Modulus(obj, o, "unused.ply");
  const nlohmann::json& af = r.report.at("authors_frame");
  EXPECT_EQ(af.at("nodes").get<int>(), kRes);  // RES nodes unless told otherwise
  EXPECT_EQ(af.at("sdf_resolution").get<int>(), kRes);
  EXPECT_NEAR(af.at("unit_scale").get<double>(), s, 1e-12);
  EXPECT_DOUBLE_EQ(af.at("their_alpha").get<double>(), 3.0);
  EXPECT_DOUBLE_EQ(af.at("their_beta").get<double>(), 0.5);
  EXPECT_NEAR(r.report.at("alpha").get<double>(), 3.0 / s, 1e-9);
  EXPECT_NEAR(r.report.at("beta").get<double>(), -0.5 * s, 1e-12);

  o.authors_frame = {kRes, kRes - 1};
  EXPECT_EQ(Modulus(obj, o, "unused.ply").report.at("authors_frame").at("nodes").get<int>(), kRes - 1);
  o.authors_frame = {kRes, 1};
  EXPECT_THROW(Modulus(obj, o, "unused.ply"), Error);
  o.authors_frame = {kRes};
  o.two_d = true;
  EXPECT_THROW(Modulus(obj, o, "unused.png"), Error);
}

// Their modulus, computed independently: the reader's position p is the point
// u = (g(p_z), g(p_y), g(p_x)) of the unit frame, g(t) = -0.5 + (t + 0.5) (RES - 1) / RES (RES nodes),
// which is the file's point u / s + centre, where their SDF holds d = |x - centre| - R; and their
// log-modulus is a (d - b). The converted map must give it (within the SDF's sampling error), and
// the conversion must equal passing a / s and -b s directly.
TEST(AuthorsFrameUnits, ConvertedParametersGiveTheirModulus) {
  const testing::TempDir dir;
  const std::string obj = SphereObj(dir);
  mesh::LoadedTarget lt = mesh::LoadModulusTarget(obj, kRes);
  const double s = ExpectedScale();
  ASSERT_NEAR(lt.unit_per_source, s, 1e-12);
  AuthorsFrame af;
  af.sdf_resolution = kRes;
  af.unit_scale = lt.unit_per_source;
  ASSERT_EQ(af.node_count(), kRes);
  const ModulusTarget target = InAuthorsFrame(lt.target, af);
  ShapeModulusOptions theirs;
  const double a = 3.0, b = 0.5;
  theirs.alpha = a;
  theirs.beta = b;
  Versor v;
  v.polynomial = GenerateVersorPolynomial(VersorGeneratorOptions{});
  const ShapeModulusMap converted(target, v, AuthorsParameters(theirs, af));
  ShapeModulusOptions direct;
  direct.alpha = a / s;
  direct.beta = -b * s;
  const ShapeModulusMap by_hand(target, v, direct);
  auto g = [](double t) { return -0.5 + (t + 0.5) * (kRes - 1) / double(kRes); };
  const double cell_in_file_units = 1.0 / kRes / s;
  int checked = 0;
  for (double x = -0.35; x <= 0.35; x += 0.07)
    for (double y = -0.35; y <= 0.35; y += 0.07)
      for (double z = -0.35; z <= 0.35; z += 0.07) {
        const Quat q{x, y, z, 0.0};
        EXPECT_DOUBLE_EQ(converted.LogModulus(q), by_hand.LogModulus(q));
        const Vec3 u{g(z), g(y), g(x)};
        const double r = std::sqrt(std::pow(u[0] / s, 2) + std::pow(u[1] / s, 2) + std::pow(u[2] / s, 2));
        if (r < kRadius / 2) continue;  // the distance's kink at the centre, which trilinear sampling rounds off
        // Trilinear sampling of a sphere's distance and the icosphere's facets: well under a cell
        // (one node too few or too many shifts the sample by up to 0.9 cell).
        EXPECT_NEAR(converted.LogModulus(q), a * (r - kRadius - b), a * 0.15 * cell_in_file_units)
            << x << " " << y << " " << z;
        ++checked;
      }
  EXPECT_GT(checked, 500);
}

// Fields convert value by value (the blend is affine in the values), masks untouched.
TEST(AuthorsFrameUnits, ParameterFieldsConvertValueByValue) {
  ShapeModulusOptions theirs;
  theirs.alpha.value = 6.0;
  theirs.alpha.regions.push_back({Mask{}, 12.0, 0.1});
  theirs.beta = 0.0;
  AuthorsFrame af;
  af.unit_scale = 0.25;
  const ShapeModulusOptions ours = AuthorsParameters(theirs, af);
  EXPECT_DOUBLE_EQ(ours.alpha.value, 24.0);
  ASSERT_EQ(ours.alpha.regions.size(), 1u);
  EXPECT_DOUBLE_EQ(ours.alpha.regions[0].value, 48.0);
  EXPECT_DOUBLE_EQ(ours.alpha.regions[0].feather, 0.1);
  EXPECT_FALSE(std::signbit(ours.beta.value));  // 0, not -0
  af.unit_scale = 0;
  EXPECT_THROW(AuthorsParameters(theirs, af), Error);
}

}  // namespace
}  // namespace quijibo::pipeline
