#include "monopole/bem.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "util/error.h"
#include "test_meshes.h"
#include "thrown_message.h"

namespace quijibo::monopole {
namespace {

using testing::ThrownMessage;

// Brute force: the triangle split into 4^levels pieces, midpoint-free 3-point rule on each.
double BruteForce(const Vec3& x, const Vec3& a, const Vec3& b, const Vec3& c, int levels) {
  if (levels == 0) {
    const Vec3 ab{b[0] - a[0], b[1] - a[1], b[2] - a[2]}, ac{c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    const Vec3 n{ab[1] * ac[2] - ab[2] * ac[1], ab[2] * ac[0] - ab[0] * ac[2],
                 ab[0] * ac[1] - ab[1] * ac[0]};
    const double area = 0.5 * std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    double s = 0.0;
    const double w[3][3] = {{2. / 3, 1. / 6, 1. / 6}, {1. / 6, 2. / 3, 1. / 6}, {1. / 6, 1. / 6, 2. / 3}};
    for (auto& l : w) {
      double d2 = 0.0;
      for (int k = 0; k < 3; ++k) {
        const double y = l[0] * a[k] + l[1] * b[k] + l[2] * c[k];
        d2 += (x[k] - y) * (x[k] - y);
      }
      s += 1.0 / std::sqrt(d2);
    }
    return area * s / 3.0;
  }
  auto mid = [](const Vec3& p, const Vec3& q) {
    return Vec3{(p[0] + q[0]) / 2, (p[1] + q[1]) / 2, (p[2] + q[2]) / 2};
  };
  const Vec3 ab = mid(a, b), bc = mid(b, c), ca = mid(c, a);
  return BruteForce(x, a, ab, ca, levels - 1) + BruteForce(x, ab, b, bc, levels - 1) +
         BruteForce(x, ca, bc, c, levels - 1) + BruteForce(x, ab, bc, ca, levels - 1);
}

TEST(Bem, TriangleIntegralMatchesQuadratureOffThePlane) {
  const Vec3 a{0.1, 0.0, 0.2}, b{1.0, 0.3, -0.1}, c{0.2, 0.9, 0.4};
  for (const Vec3& x : {Vec3{0.4, 0.4, 0.6}, Vec3{2.0, -1.0, 0.5}, Vec3{-0.3, 0.2, 0.0},
                        Vec3{0.45, 0.4, 0.25}}) {
    const double exact = TriangleInverseDistanceIntegral(x, a, b, c);
    const double brute = BruteForce(x, a, b, c, 7);
    EXPECT_NEAR(exact, brute, 2e-5 * std::abs(brute)) << x[0] << " " << x[1] << " " << x[2];
    // Orientation does not matter.
    EXPECT_NEAR(TriangleInverseDistanceIntegral(x, a, c, b), exact, 1e-12 * std::abs(exact));
  }
}

TEST(Bem, TriangleIntegralInPlaneIsTheRadialFormula) {
  // For x inside the triangle in its plane, the integral is sum over edges of
  // h_e * (asinh(s+/h_e) - asinh(s-/h_e)), h_e the distance to the edge line.
  const Vec3 p[3] = {{0, 0, 0}, {2, 0, 0}, {0.5, 1.5, 0}};
  const Vec3 x{0.8, 0.4, 0.0};
  double expected = 0.0;
  for (int e = 0; e < 3; ++e) {
    const Vec3 &u = p[e], &v = p[(e + 1) % 3];
    const double len = std::hypot(v[0] - u[0], v[1] - u[1]);
    const double lx = (v[0] - u[0]) / len, ly = (v[1] - u[1]) / len;
    const double h = std::abs((x[0] - u[0]) * ly - (x[1] - u[1]) * lx);
    const double sm = (u[0] - x[0]) * lx + (u[1] - x[1]) * ly;
    const double sp = (v[0] - x[0]) * lx + (v[1] - x[1]) * ly;
    expected += h * (std::asinh(sp / h) - std::asinh(sm / h));
  }
  EXPECT_NEAR(TriangleInverseDistanceIntegral(x, p[0], p[1], p[2]), expected, 1e-12 * expected);
  // Continuous through the plane.
  EXPECT_NEAR(TriangleInverseDistanceIntegral({0.8, 0.4, 1e-9}, p[0], p[1], p[2]), expected,
              1e-7 * expected);
  // In the plane, outside the triangle, on the extension of an edge: finite and continuous.
  const double on_line = TriangleInverseDistanceIntegral({3.0, 0.0, 0.0}, p[0], p[1], p[2]);
  const double near_line = TriangleInverseDistanceIntegral({3.0, 1e-9, 0.0}, p[0], p[1], p[2]);
  EXPECT_TRUE(std::isfinite(on_line));
  EXPECT_NEAR(on_line, near_line, 1e-7);
}

// P = a / r outside a sphere of radius a: the maximum relative error on the sphere r = 1.2 a.
double SphereShellError(const ExteriorPotential& pot, const Vec3& c, double a) {
  std::mt19937_64 rng(7);
  std::normal_distribution<double> g;
  std::vector<Vec3> pts;
  for (int i = 0; i < 400; ++i) {
    Vec3 d{g(rng), g(rng), g(rng)};
    const double n = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    pts.push_back({c[0] + 1.2 * a * d[0] / n, c[1] + 1.2 * a * d[1] / n, c[2] + 1.2 * a * d[2] / n});
  }
  const std::vector<double> p = pot.Evaluate(pts);
  double worst = 0.0;
  for (double v : p) worst = std::max(worst, std::abs(v - 1.0 / 1.2) * 1.2);
  return worst;
}

TEST(Bem, SpherePotentialIsAOverR) {
  const Vec3 c{0.1, -0.2, 0.3};
  const double a = 1.3;
  const auto mesh = testing::MakeIcosphere(3, c, a);  // 1280 triangles, one element each
  BemSummary s;
  const ExteriorPotential pot = SolveExteriorPotential(mesh.vertices, mesh.triangles, {}, &s);
  EXPECT_EQ(s.elements, 1280);
  EXPECT_LT(s.relative_residual, 1e-10);
  const double err = SphereShellError(pot, c, a);
  std::printf("sphere, 1280 elements: max relative error at 1.2 a = %.3g %%, surface max |P-1| = "
              "%.3g, total charge / (4 pi a) = %.5f\n",
              100 * err, s.surface_max_deviation, s.total_charge / (4 * M_PI * a));
  std::printf("assembly %.3f s, solve %.3f s\n", s.assembly_seconds, s.solve_seconds);
  EXPECT_LT(err, 0.01);
  // Far away the potential is that of the total charge; inside it is 1.
  EXPECT_NEAR(pot({c[0] + 50.0, c[1], c[2]}), a / 50.0, 0.01 * a / 50.0);
  EXPECT_NEAR(pot(c), 1.0, 0.01);
}

TEST(Bem, SpherePotentialWithPatches) {
  const Vec3 c{0.0, 0.0, 0.0};
  const double a = 0.9;
  const auto mesh = testing::MakeIcosphere(4, c, a);  // 5120 triangles
  BemOptions opt;
  opt.max_elements = 900;
  BemSummary s;
  const ExteriorPotential pot = SolveExteriorPotential(mesh.vertices, mesh.triangles, opt, &s);
  EXPECT_LE(s.elements, 900);
  EXPECT_GT(s.elements, 450);
  const double err = SphereShellError(pot, c, a);
  std::printf("sphere, 5120 triangles in %d patches: max relative error at 1.2 a = %.3g %%, "
              "surface max |P-1| = %.3g (rms %.3g)\n",
              s.elements, 100 * err, s.surface_max_deviation, s.surface_rms_deviation);
  EXPECT_LT(err, 0.01);
}

TEST(Bem, BadOptionsAndMeshesAreRejected) {
  const auto mesh = testing::MakeIcosphere(0);
  BemOptions opt;
  opt.max_elements = 2;
  const std::string too_few = ThrownMessage([&] { SolveExteriorPotential(mesh.vertices, mesh.triangles, opt); });
  EXPECT_NE(too_few.find("bem.max_elements"), std::string::npos) << too_few;
  opt = {};
  opt.far_factor = 0.5;
  EXPECT_NE(opt.Validate().find("bem.far_factor"), std::string::npos);
  EXPECT_THROW(SolveExteriorPotential(mesh.vertices, {}, {}), Error);
  auto bad = mesh.triangles;
  bad[3][1] = 99;
  const std::string outside = ThrownMessage([&] { SolveExteriorPotential(mesh.vertices, bad, {}); });
  EXPECT_NE(outside.find("triangle 3 refers to vertex 99"), std::string::npos) << outside;
}

}  // namespace
}  // namespace quijibo::monopole

namespace quijibo::monopole {
namespace {

TEST(Bem, GmresAndLuAgree) {
  const auto mesh = testing::MakeIcosphere(3, {0.0, 0.2, 0.0}, 0.7);
  BemOptions opt;
  opt.max_elements = 500;  // patches: a non-symmetric system
  BemSummary sg, sl;
  const ExteriorPotential pg = SolveExteriorPotential(mesh.vertices, mesh.triangles, opt, &sg);
  opt.solver = BemOptions::Solver::kLU;
  const ExteriorPotential pl = SolveExteriorPotential(mesh.vertices, mesh.triangles, opt, &sl);
  EXPECT_FALSE(sg.used_lu);
  EXPECT_GT(sg.solver_iterations, 0);
  EXPECT_TRUE(sl.used_lu);
  EXPECT_LT(sg.relative_residual, 1e-10);
  for (const Vec3& x : {Vec3{1.0, 0.0, 0.0}, Vec3{0.3, 0.9, -0.4}, Vec3{0.0, 0.2, 0.0}})
    EXPECT_NEAR(pg(x), pl(x), 1e-9);
}

}  // namespace
}  // namespace quijibo::monopole
