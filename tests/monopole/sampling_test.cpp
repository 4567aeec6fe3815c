#include "monopole/sampling.h"

#include <gtest/gtest.h>

#include <cmath>

#include "util/error.h"
#include "test_meshes.h"
#include "thrown_message.h"

namespace quijibo::monopole {
namespace {

using testing::ThrownMessage;

double MinPairDistance(const std::vector<Vec3>& p) {
  double best = HUGE_VAL;
  for (std::size_t i = 0; i < p.size(); ++i)
    for (std::size_t j = i + 1; j < p.size(); ++j) {
      const double d = std::sqrt((p[i][0] - p[j][0]) * (p[i][0] - p[j][0]) +
                                 (p[i][1] - p[j][1]) * (p[i][1] - p[j][1]) +
                                 (p[i][2] - p[j][2]) * (p[i][2] - p[j][2]));
      best = std::min(best, d);
    }
  return best;
}

TEST(Sampling, ExactCountOnTheSurfaceAndWellSpread) {
  const auto mesh = testing::MakeIcosphere(3, {0.5, 0.0, 0.0}, 2.0);
  SamplingOptions opt;
  opt.count = 2000;
  const std::vector<Vec3> pts = PoissonDiskSample(mesh.vertices, mesh.triangles, opt);
  ASSERT_EQ(pts.size(), 2000u);
  for (const Vec3& p : pts) {
    const double r = std::sqrt((p[0] - 0.5) * (p[0] - 0.5) + p[1] * p[1] + p[2] * p[2]);
    EXPECT_LE(r, 2.0 + 1e-12);
    EXPECT_GE(r, 2.0 * 0.99);  // icosphere level 3: faces within 0.5 % of the sphere
  }
  // Blue noise: no two points much closer than the densest-packing radius r_max
  // (uniform random points would come within ~1e-3 r_max of each other).
  double area = 0.0;
  for (auto& t : mesh.triangles) {
    const Vec3 &a = mesh.vertices[t[0]], &b = mesh.vertices[t[1]], &c = mesh.vertices[t[2]];
    const Vec3 u{b[0] - a[0], b[1] - a[1], b[2] - a[2]}, v{c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    area += 0.5 * std::sqrt(std::pow(u[1] * v[2] - u[2] * v[1], 2) +
                            std::pow(u[2] * v[0] - u[0] * v[2], 2) +
                            std::pow(u[0] * v[1] - u[1] * v[0], 2));
  }
  const double r_max = std::sqrt(area / (2.0 * std::sqrt(3.0) * 2000));
  const double dmin = MinPairDistance(pts);
  std::printf("min pair distance %.3f r_max\n", dmin / r_max);
  EXPECT_GT(dmin, 1.0 * r_max);
}

TEST(Sampling, DeterministicForASeed) {
  const auto mesh = testing::MakeIcosphere(2);
  SamplingOptions opt;
  opt.count = 500;
  const auto a = PoissonDiskSample(mesh.vertices, mesh.triangles, opt);
  const auto b = PoissonDiskSample(mesh.vertices, mesh.triangles, opt);
  EXPECT_EQ(a, b);
  opt.seed = 99;
  const auto c = PoissonDiskSample(mesh.vertices, mesh.triangles, opt);
  EXPECT_NE(a, c);
}

TEST(Sampling, BadOptionsAreRejected) {
  const auto mesh = testing::MakeIcosphere(0);
  SamplingOptions opt;
  opt.count = 0;
  EXPECT_EQ(ThrownMessage([&] { PoissonDiskSample(mesh.vertices, mesh.triangles, opt); }),
            "sampling.count must be positive, found 0");
  opt = {};
  opt.oversampling = 0.5;
  EXPECT_NE(opt.Validate().find("sampling.oversampling"), std::string::npos);
  EXPECT_THROW(PoissonDiskSample(mesh.vertices, {}, {}), Error);
}

}  // namespace
}  // namespace quijibo::monopole
