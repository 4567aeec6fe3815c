// Map kind "polynomial" (methods/maps/polynomial.cpp): q^d + c as the engine draws it, against the
// complex dynamics it reduces to on the complex plane.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>

#include "methods/map_kind.h"
#include "tests/thrown_message.h"

namespace quijibo {
namespace {

KindMap Polynomial(const nlohmann::json& doc) { return ReadKindMap(JsonReader(doc, "test"), "", ""); }

// Whether z stays within `escape` for n steps of z^2 + c: the filled Julia set's test, in complex
// arithmetic (independent of the quaternion code).
bool Bounded(std::complex<double> z, std::complex<double> c, int n, double escape) {
  for (int k = 0; k < n && std::abs(z) < escape; ++k) z = z * z + c;
  return std::abs(z) < escape;
}

TEST(PolynomialMap, BasilicaSliceMatchesComplexMembership) {
  const KindMap km = Polynomial({{"kind", "polynomial"}, {"c", {-1.0, 0.0}}});
  ASSERT_EQ(km.kind->name, "polynomial");
  IterationOptions it = km.kind->iteration;
  it.iterations = 200;
  View2D v;
  v.x_min = -1.8, v.x_max = 1.8, v.y_min = -1.0, v.y_max = 1.0;
  v.width = 181, v.height = 101;
  const std::vector<double> field = SampleField2D(*km.map, it, v);
  int mismatches = 0, inside = 0;
  for (int py = 0; py < v.height; ++py)
    for (int px = 0; px < v.width; ++px) {
      const std::complex<double> z{v.x_min + (px + 0.5) * (v.x_max - v.x_min) / v.width,
                                   v.y_max - (py + 0.5) * (v.y_max - v.y_min) / v.height};
      const bool in = Bounded(z, {-1.0, 0.0}, it.iterations, it.escape_radius);
      inside += in;
      mismatches += in != (field[std::size_t(py) * v.width + px] < 0);
    }
  EXPECT_EQ(mismatches, 0);
  // The basilica's area is about 1.50: a fifth of the 3.6 x 2 view.
  EXPECT_NEAR(double(inside) / field.size() * 3.6 * 2.0, 1.50, 0.1);
  // On the real axis the set is [-phi, phi], phi the golden ratio (z^2 - 1 maps it onto itself);
  // 0 and -1 are the super-attracting 2-cycle.
  const double phi = (1 + std::sqrt(5.0)) / 2;
  for (double x : {0.0, -1.0, 1.0, 1.2, -1.5, phi - 0.01, -(phi - 0.01)})
    EXPECT_LT(IterateField(*km.map, Quat{x, 0, 0, 0}, it), 0) << x;
  for (double x : {phi + 0.01, -(phi + 0.01), 2.0})
    EXPECT_GT(IterateField(*km.map, Quat{x, 0, 0, 0}, it), 0) << x;
}

TEST(PolynomialMap, ZeroConstantGivesTheUnitDisc) {
  const KindMap km = Polynomial({{"kind", "polynomial"}, {"c", {0.0, 0.0, 0.0, 0.0}}});
  const IterationOptions it = km.kind->iteration;  // the kind's defaults
  int tested = 0;
  for (int i = 0; i < 64; ++i)
    for (int j = 0; j < 64; ++j)
      for (int k = 0; k < 8; ++k) {
        const Quat q{-1.5 + 3.0 * (i + 0.5) / 64, -1.5 + 3.0 * (j + 0.5) / 64, -1.5 + 3.0 * (k + 0.5) / 8, 0};
        const double r = q.norm();
        if (std::abs(r - 1) < 1e-4) continue;
        ++tested;
        EXPECT_EQ(IterateField(*km.map, q, it) < 0, r < 1) << q.w << " " << q.x << " " << q.y;
      }
  EXPECT_GT(tested, 30000);
}

TEST(PolynomialMap, DouadyRabbitCriticalOrbitHasPeriodThree) {
  // The centre of the rabbit's hyperbolic component: 0 is periodic with period 3.
  const Quat c{-0.12256116687665361, 0.74486176661974424, 0, 0};
  const KindMap km = Polynomial({{"kind", "polynomial"}, {"c", {c.w, c.x}}});
  Quat z{0, 0, 0, 0};
  std::vector<Quat> orbit{z};
  for (int k = 0; k < 9; ++k) orbit.push_back(z = km.map->Apply(z));
  for (int k = 0; k + 3 < int(orbit.size()); ++k) EXPECT_LT((orbit[k + 3] - orbit[k]).norm(), 1e-9) << k;
  for (int p : {1, 2}) EXPECT_GT((orbit[p] - orbit[0]).norm(), 0.1) << p;
  EXPECT_LT((orbit[1] - c).norm(), 1e-15);
  // The critical value c is in the filled set, and the orbit stays in the complex plane.
  EXPECT_LT(IterateField(*km.map, c, km.kind->iteration), 0);
  for (const Quat& q : orbit) EXPECT_EQ(q.y * q.y + q.z * q.z, 0.0);
}

TEST(PolynomialMap, HigherDegreeAndBadInput) {
  const KindMap cubic = Polynomial({{"kind", "polynomial"}, {"c", {0.1, 0.2, 0.3, 0.4}}, {"degree", 3}});
  const Quat q{0.3, -0.2, 0.1, 0.5};
  const Quat expected = q * q * q + Quat{0.1, 0.2, 0.3, 0.4};
  EXPECT_LT((cubic.map->Apply(q) - expected).norm(), 1e-15);
  EXPECT_NE(testing::ThrownMessage([] { Polynomial({{"kind", "polynomial"}, {"c", {1.0, 2.0, 3.0}}}); }).find("/c: expected 2"), std::string::npos);
  EXPECT_NE(testing::ThrownMessage([] { Polynomial({{"kind", "polynomial"}, {"c", {1.0, 2.0}}, {"degree", 1}}); }).find("/degree"), std::string::npos);
  EXPECT_NE(testing::ThrownMessage([] { Polynomial({{"kind", "polynomial"}, {"c", {1.0, 2.0}}, {"power", 2}}); }).find("power"), std::string::npos);
  EXPECT_NE(testing::ThrownMessage([] { Polynomial({{"kind", "polynomal"}, {"c", {1.0, 2.0}}}); }).find("expected one of"), std::string::npos);
}

}  // namespace
}  // namespace quijibo
