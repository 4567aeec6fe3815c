// Shape modulus (2023) and portals (2024): versor polynomials, the map, portals, the Koch snowflake.
#include <gtest/gtest.h>

#include "quijibo_command.h"
#include <sys/wait.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>

#include "util/error.h"
#include "util/image.h"
#include "util/io.h"
#include "quijibo/target.h"
#include "quijibo/frame.h"
#include "util/json_reader.h"
#include "quijibo/quaternion_map.h"
#include "methods/modulus.h"
#include "methods/portal.h"
#include "modulus_fixtures.h"

namespace quijibo {
namespace {

using nlohmann::json;

TEST(VersorPolynomial, GeneratorIsDeterministicAndInRange) {
  VersorGeneratorOptions o{
      .roots = 12, .min_power = 2, .max_power = 5, .box_min = {-0.3, -0.2, -0.1}, .box_max = {0.3, 0.2, 0.1}, .seed = 42};
  const VersorPolynomial a = GenerateVersorPolynomial(o), b = GenerateVersorPolynomial(o);
  EXPECT_EQ(a.roots, b.roots);
  EXPECT_EQ(a.powers, b.powers);
  bool seen_min = false, seen_max = false;
  for (std::size_t i = 0; i < a.roots.size(); ++i) {
    for (int c = 0; c < 3; ++c) {
      EXPECT_GE(a.roots[i][c], o.box_min[c]);
      EXPECT_LT(a.roots[i][c], o.box_max[c]);
    }
    EXPECT_EQ(a.roots[i][3], 0.0);
    EXPECT_EQ(a.powers[i], std::floor(a.powers[i]));
    EXPECT_GE(a.powers[i], 2.0);
    EXPECT_LE(a.powers[i], 5.0);
    seen_min |= a.powers[i] == 2.0;
    seen_max |= a.powers[i] == 5.0;
  }
  EXPECT_TRUE(seen_min && seen_max) << "integer powers cover [min, max] inclusive";
  o.seed = 43;
  EXPECT_NE(GenerateVersorPolynomial(o).roots, a.roots);
  // Pinned first draw, so a change of the generator is noticed.
  o.seed = 1;
  const VersorPolynomial c = GenerateVersorPolynomial(o);
  std::mt19937_64 rng(1);
  EXPECT_EQ(c.roots[0][0], -0.3 + 0.6 * (double(rng() >> 11) * 0x1.0p-53));
}

TEST(VersorPolynomial, JsonRoundTripAndBaselineFormat) {
  VersorGeneratorOptions o;
  o.integer_powers = false;
  o.seed = 7;
  const VersorPolynomial a = GenerateVersorPolynomial(o);
  const VersorPolynomial b = VersorPolynomialFromJson(json::parse(VersorPolynomialToJson(a).dump()), "x.json");
  EXPECT_EQ(a.roots, b.roots);
  EXPECT_EQ(a.powers, b.powers);
  EXPECT_EQ(a.power_scalar, b.power_scalar);
  const VersorPolynomial base = ReadVersorPolynomial(std::string(QUIJIBO_SOURCE_DIR) + "/data/sm-baseline-poly10.json");
  ASSERT_EQ(base.roots.size(), 10u);
  EXPECT_EQ(base.powers[0], 2.0);
  EXPECT_EQ(base.powers[9], 8.0);
  EXPECT_DOUBLE_EQ(base.roots[0][0], 0.03729955302551191);
}

TEST(VersorPolynomial, ErrorsNameThePointer) {
  auto message = [](const std::string& text) {
    try {
      VersorPolynomialFromJson(json::parse(text), "p.json");
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message(R"({"roots":[[0,0,0,0]],"powers":[1,2]})").find("p.json: /powers"), std::string::npos);
  EXPECT_NE(message(R"({"roots":[[0,0]],"powers":[1]})").find("/roots/0"), std::string::npos);
  EXPECT_NE(message(R"({"roots":[[0,0,0]],"powers":[1],"powrs":1})").find("powrs"), std::string::npos);
}

TEST(ShapeModulus, UnitPowerMatchesPolarPower) {
  const Quat d = Quat{0.3, -0.5, 0.7, 0.2} * (1.0 / Quat{0.3, -0.5, 0.7, 0.2}.norm());
  for (double a : {0.0, 1.0, 2.0, 7.0, 12.0, 2.5, -1.5}) {
    const Quat u = UnitPower(d, a), p = pow(d, a);
    EXPECT_NEAR((u - p).norm(), 0.0, 1e-12) << a;
  }
}

TEST(ShapeModulus, DirectionIsTheNormalizedProduct) {
  VersorGeneratorOptions o;
  o.seed = 3;
  o.roots = 5;
  Versor v;
  v.polynomial = GenerateVersorPolynomial(o);
  ShapeModulusOptions so;
  ShapeModulusMap map(AnalyticModulusTarget("sphere"), v, so);
  const Quat q{0.11, -0.23, 0.05, 0.01};
  Quat p{1, 0, 0, 0};
  for (std::size_t i = 0; i < v.polynomial.roots.size(); ++i) {
    const Vec4& r = v.polynomial.roots[i];
    p = p * pow(q - Quat{r[0], r[1], r[2], r[3]}, v.polynomial.powers[i]);
  }
  p = p * (1.0 / p.norm());
  EXPECT_NEAR((map.Direction(q) - p).norm(), 0.0, 1e-12);
  const double phi = std::sqrt(0.11 * 0.11 + 0.23 * 0.23 + 0.05 * 0.05) - kUnitFrameLongestSide / 2;
  EXPECT_NEAR(map.LogModulus(q), 30.0 * phi, 1e-12);  // k is dropped
  EXPECT_NEAR(map.Apply(q).norm(), std::exp(30.0 * phi), 1e-12);
}

TEST(ShapeModulus, RationalMapAdapterMatchesProductForm) {
  const RationalMap m = RandomMap({.top = 4, .bottom = 3, .ln_C = 0.3, .seed = 5});
  RationalQuaternionMap rq(m);
  const Quat q{0.4, -0.2, 0.3, 0.1};
  Quat t{1, 0, 0, 0}, b{1, 0, 0, 0};
  for (int i = 0; i < m.top_count(); ++i) t = t * pow(q - m.top_root<double>(i), m.tau * m.top_exponents[i]);
  for (int i = 0; i < m.bottom_count(); ++i) b = b * pow(q - m.bottom_root<double>(i), m.beta * m.bottom_exponents[i]);
  const Quat r = t * b.inverse() * std::exp(m.ln_C);
  EXPECT_NEAR((rq.Apply(q) - r).norm() / r.norm(), 0.0, 1e-12);
  EXPECT_NEAR(rq.LogModulus(q), std::log(r.norm()), 1e-12);
}

// At high alpha the inside of the Julia set is the inside of the target (2023 §3.3.1).
TEST(ShapeModulus, HighAlphaSetMatchesSphere) {
  const Versor v = testing::PolynomialVersor(11);
  ShapeModulusOptions so;
  so.alpha = 300.0;
  ShapeModulusMap map(AnalyticModulusTarget("sphere:radius=0.4"), v, so);
  IterationOptions jo;
  const int n = 32;
  int both = 0, either = 0;
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const Vec3 p{-0.6 + 1.2 * (i + 0.5) / n, -0.6 + 1.2 * (j + 0.5) / n, -0.6 + 1.2 * (k + 0.5) / n};
        const bool julia = IterateField(map, {p[0], p[1], p[2], 0.0}, jo) < 0;
        const bool target = map.target().phi(p) < 0;
        both += julia && target;
        either += julia || target;
      }
  ASSERT_GT(either, 0);
  EXPECT_GT(double(both) / either, 0.9);
}

// The authors' frame: phi read at (g(z), g(y), g(x)), g(t) = -0.5 + (clamp(t) + 0.5) (nodes - 1) / res.
TEST(AuthorsFrame, SwapsXAndZAndStretches) {
  ModulusTarget t;
  t.phi = [](const Vec3& p) { return p[0] + 2 * p[1] + 4 * p[2]; };
  t.box_min = {-0.4, -0.3, -0.2};
  t.box_max = {0.4, 0.3, 0.2};
  AuthorsFrame f;
  f.sdf_resolution = 10;
  f.nodes = 9;  // stretch 0.8
  const ModulusTarget c = InAuthorsFrame(t, f);
  EXPECT_NEAR(c.phi({0.1, -0.2, 0.3}), 0.14 + 2 * -0.26 + 4 * -0.02, 1e-12);
  EXPECT_NEAR(c.phi({0.9, 0.0, 0.0}), -0.1 + 2 * -0.1 + 4 * 0.3, 1e-12);  // clamped to the box
  EXPECT_NEAR(c.box_min[0], -0.125, 1e-12);
  EXPECT_NEAR(c.box_max[0], 0.375, 1e-12);
  EXPECT_NEAR(c.box_min[2], -0.375, 1e-12);
  EXPECT_NEAR(c.box_max[2], 0.5, 1e-12);  // 0.625 clamped
  f.nodes = 1;
  EXPECT_THROW(InAuthorsFrame(t, f), Error);
}

// On a small lattice: an ellipsoid long in x becomes, at high alpha, a Julia set long in z, stretched
// about the box's min corner; the roots stay put.
TEST(AuthorsFrame, JuliaSetOfAnEllipsoidIsSwappedAndStretched) {
  const Vec3 axes{0.35, 0.2, 0.12};
  auto ellipsoid = [axes](const Vec3& p) {
    const double r = std::sqrt(std::pow(p[0] / axes[0], 2) + std::pow(p[1] / axes[1], 2) + std::pow(p[2] / axes[2], 2));
    return (r - 1) * axes[2];
  };
  ModulusTarget t;
  t.phi = ellipsoid;
  AuthorsFrame f;
  f.sdf_resolution = 100;
  f.nodes = 91;  // stretch 0.9, so that the test sees it (and the origin stays inside)
  const Versor v = testing::PolynomialVersor(5);
  ShapeModulusOptions so;
  so.alpha = 300.0;
  ShapeModulusMap map(InAuthorsFrame(t, f), v, so);
  auto g = [](double x) { return -0.5 + (x + 0.5) * 0.9; };
  const int n = 32;
  int both = 0, either = 0, both_plain = 0, either_plain = 0;
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const Vec3 p{-0.5 + (i + 0.5) / n, -0.5 + (j + 0.5) / n, -0.5 + (k + 0.5) / n};
        const bool julia = IterateField(map, {p[0], p[1], p[2], 0.0}, IterationOptions{}) < 0;
        const bool expected = ellipsoid({g(p[2]), g(p[1]), g(p[0])}) < 0;
        const bool plain = ellipsoid(p) < 0;
        both += julia && expected, either += julia || expected;
        both_plain += julia && plain, either_plain += julia || plain;
      }
  ASSERT_GT(either, 0);
  EXPECT_GT(double(both) / either, 0.85);
  EXPECT_LT(double(both_plain) / either_plain, 0.4);  // 0.23 between the two ellipsoids
}

// Paper's sign: exp(alpha (phi + beta)); the surface is near phi = -beta.
TEST(ShapeModulus, NegativeBetaMovesTheSurfaceOutwards) {
  const Versor v = testing::PolynomialVersor(1);  // the generator's default seed
  auto inside = [&](double beta) {
    ShapeModulusOptions so;
    so.alpha = 300.0;
    so.beta = beta;
    ShapeModulusMap map(AnalyticModulusTarget("sphere:radius=0.3"), v, so);
    int count = 0;
    for (int i = 0; i < 200; ++i) count += IterateField(map, {-0.5 + i / 200.0, 0.01, 0.02, 0}, IterationOptions{}) < 0;
    return count;
  };
  EXPECT_LT(inside(0.05), inside(0.0));
  EXPECT_GT(inside(-0.05), inside(0.0));
  EXPECT_NEAR(inside(-0.05) - inside(0.05), 2 * 0.1 * 200, 6);  // two crossings, 0.1 apart each
}

TEST(ParameterField, CubicBlendBetweenRegions) {
  const ParameterField f = testing::HalfspaceStep();
  EXPECT_DOUBLE_EQ(f({-0.2, 0, 0}), 10.0);
  EXPECT_DOUBLE_EQ(f({0.2, 0, 0}), 300.0);
  EXPECT_DOUBLE_EQ(f({0.0, 0, 0}), 155.0);
  double prev = f({-0.2, 0, 0});
  for (int i = 1; i <= 100; ++i) {
    const double v = f({-0.2 + 0.4 * i / 100, 0, 0});
    EXPECT_GE(v, prev);
    EXPECT_LT(v - prev, 0.03 * 290);  // no jump
    prev = v;
  }
}

// B(x) is 0 on the mask boundary and rises smoothly to 1 at the feather depth, so the portal
// map is continuous across the boundary.
TEST(Portal, FeatheredBlendIsContinuous) {
  const Versor v = testing::PolynomialVersor(1);  // the generator's default seed
  ShapeModulusOptions so;
  so.alpha = 5.0;
  auto base = std::make_shared<ShapeModulusMap>(AnalyticModulusTarget("sphere:radius=0.3"), v, so);
  Portal p;
  p.mask.type = Mask::Type::kSphere;
  p.mask.center = {0.2, 0.1, 0.0};
  p.mask.radius = 0.15;
  p.feather = 0.05;
  p.transform.center = p.mask.center;
  p.transform.scale = 2.0;
  p.transform.angle_deg = 30;
  PortalMap pm(base, {p}, nullptr);
  EXPECT_EQ(pm.Blend({0.2 + 0.16, 0.1, 0, 0}), 0.0);
  EXPECT_EQ(pm.Blend({0.2, 0.1, 0, 0}), 1.0);
  EXPECT_NEAR(pm.Blend({0.2 + 0.15 - 0.025, 0.1, 0, 0}), 0.5, 1e-12);
  // Across the boundary along x: F_F changes by O(step).
  Quat prev = pm.Apply({0.2 + 0.10, 0.1, 0, 0});
  double prev_b = pm.Blend({0.2 + 0.10, 0.1, 0, 0});
  for (int i = 1; i <= 400; ++i) {
    const Quat q{0.2 + 0.10 + 0.1 * i / 400, 0.1, 0, 0};
    const Quat f = pm.Apply(q);
    const double b = pm.Blend(q);
    EXPECT_LT((f - prev).norm(), 0.02) << i;
    EXPECT_LE(b, prev_b + 1e-15);
    EXPECT_LT(std::abs(b - prev_b), 0.03);
    prev = f;
    prev_b = b;
  }
}

// ---- Koch snowflake (2024 Figs. 4, 7) ----

// Our own rasterizer of the level-`level` Koch snowflake on the triangle of side `side` pointing
// up with its centroid at the origin (the hexagram's upward triangle): refine each edge a->b of the
// counter-clockwise polygon into a, a+d, apex, a+2d (apex outwards), then even-odd point tests.
std::vector<std::array<double, 2>> KochPolygon(double side, int level) {
  const double R = side / std::sqrt(3.0);
  std::vector<std::array<double, 2>> poly;
  for (int i = 0; i < 3; ++i) {
    const double a = M_PI / 2 + i * 2 * M_PI / 3;
    poly.push_back({R * std::cos(a), R * std::sin(a)});
  }
  for (int l = 0; l < level; ++l) {
    std::vector<std::array<double, 2>> next;
    for (std::size_t i = 0; i < poly.size(); ++i) {
      const auto a = poly[i], b = poly[(i + 1) % poly.size()];
      const double dx = (b[0] - a[0]) / 3, dy = (b[1] - a[1]) / 3;
      const std::array<double, 2> p1{a[0] + dx, a[1] + dy}, p3{a[0] + 2 * dx, a[1] + 2 * dy};
      // Rotate d by -60 degrees: outwards for a counter-clockwise polygon.
      const double c = 0.5, s = -std::sqrt(3.0) / 2;
      const std::array<double, 2> p2{p1[0] + c * dx - s * dy, p1[1] + s * dx + c * dy};
      next.push_back(a);
      next.push_back(p1);
      next.push_back(p2);
      next.push_back(p3);
    }
    poly = std::move(next);
  }
  return poly;
}

bool InsidePolygon(const std::vector<std::array<double, 2>>& poly, double x, double y) {
  bool in = false;
  for (std::size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++) {
    const auto& a = poly[j];
    const auto& b = poly[i];
    if ((a[1] > y) != (b[1] > y) && x < a[0] + (y - a[1]) * (b[0] - a[0]) / (b[1] - a[1])) in = !in;
  }
  return in;
}

std::shared_ptr<PortalMap> KochMap(double side, double alpha, double feather) {
  VersorGeneratorOptions o;
  o.seed = 1;
  o.box_min = {-0.6, -0.6, 0};
  o.box_max = {0.6, 0.6, 0};
  Versor v;
  v.polynomial = GenerateVersorPolynomial(o);
  ShapeModulusOptions so;
  so.alpha = alpha;
  auto base = std::make_shared<ShapeModulusMap>(AnalyticModulusTarget("hexagram:size=" + std::to_string(side)), v, so);
  auto set = [base](const Quat& q) { return base->LogModulus(q); };
  return std::make_shared<PortalMap>(base, KochPortals(side, feather), set);
}

TEST(Portal, KochSnowflakeIoU) {
  const double side = 1.0;
  auto map = KochMap(side, 3000.0, 0.005);
  View2D view;
  view.x_min = view.y_min = -0.62;
  view.x_max = view.y_max = 0.62;
  view.width = view.height = 300;
  IterationOptions jo;
  jo.iterations = 30;
  const std::vector<double> field = SampleField2D(*map, jo, view);
  const auto koch = KochPolygon(side, 5);
  int both = 0, either = 0;
  for (int py = 0; py < view.height; ++py)
    for (int px = 0; px < view.width; ++px) {
      const double x = view.x_min + (px + 0.5) * (view.x_max - view.x_min) / view.width;
      const double y = view.y_max - (py + 0.5) * (view.y_max - view.y_min) / view.height;
      const bool a = field[std::size_t(py) * view.width + px] < 0, b = InsidePolygon(koch, x, y);
      both += a && b;
      either += a || b;
    }
  const double iou = double(both) / either;
  EXPECT_GE(iou, 0.9);
  std::printf("Koch snowflake IoU at 300^2: %.4f\n", iou);
  // The image is written.
  const auto path = std::filesystem::temp_directory_path() / "quijibo_koch_test.png";
  WritePng(path.string(), FieldImage(field, view, std::log(20.0)));
  EXPECT_GT(std::filesystem::file_size(path), 100u);
  std::filesystem::remove(path);
}

// Portals on QUIJIBO rational maps: tests/methods/modulus_features_test.cpp, Portal.OnAQuijiboMapRepeatsItsSet.

using quijibo::testing::CommandResult;
using quijibo::testing::RunQuijibo;

TEST(ModulusCli, KochImageAndErrors) {
  const auto dir = std::filesystem::temp_directory_path() / "quijibo_modulus_cli";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const std::string png = (dir / "k.png").string(), spec = (dir / "k.json").string();
  CommandResult r = RunQuijibo("portal --koch --png-size 64 -o " + png + " --write-spec " + spec);
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_TRUE(std::filesystem::exists(png));
  // The written spec reproduces the image's inside count.
  const std::string png2 = (dir / "k2.png").string();
  CommandResult r2 = RunQuijibo("portal " + spec + " --png-size 64 -o " + png2);
  EXPECT_EQ(r2.code, 0) << r2.out;
  EXPECT_EQ(json::parse(r.out)["result"]["inside_pixels"], json::parse(r2.out)["result"]["inside_pixels"]);
  // A bad key: one line naming the file and pointer, exit 1, nothing written.
  std::ofstream(dir / "bad.json") << R"({"format":"quijibo-portals","version":1,"target":"hexagram","portals":[{"mask":{"type":"sphere","center":[0,0],"radius":0.1},"feathr":1}]})";
  const std::string out = (dir / "bad.png").string();
  r = RunQuijibo("portal " + (dir / "bad.json").string() + " -o " + out);
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.out.find("/portals/0"), std::string::npos) << r.out;
  EXPECT_FALSE(std::filesystem::exists(out));
  r = RunQuijibo("modulus hexagram -o " + (dir / "x.ply").string());
  EXPECT_EQ(r.code, 1);
  EXPECT_FALSE(std::filesystem::exists(dir / "x.ply"));
  // 2D modulus image of an analytic target, with the generated polynomial written.
  r = RunQuijibo("modulus disc --alpha 40 --png-size 48 --seed 3 --write-poly " + (dir / "p.json").string() + " -o " +
              (dir / "d.png").string());
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_EQ(ReadVersorPolynomial((dir / "p.json").string()).roots.size(), 10u);
  std::filesystem::remove_all(dir);
}

// `compare` end to end on a small sphere target and a random map (needs the mesher).
TEST(ModulusCli, CompareWritesTableAndJson) {
  const auto dir = std::filesystem::temp_directory_path() / "quijibo_modulus_compare";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  auto path = [&](const std::string& n) { return (dir / n).string(); };
  ScalarGrid g = AnalyticTarget("sphere", TargetGridFrame(20, FractalFrame{}));
  WriteGrid(path("s.qgrid"), g);
  RandomMapOptions ro;
  ro.top = 4;
  ro.bottom = 2;
  WriteMap(path("map.json"), RandomMap(ro));
  CommandResult r = RunQuijibo("compare --target " + path("s.qgrid") + " --map " + path("map.json") +
                     " --alpha 300 --beta 0 -r 16 --samples 2000 --png-size 32 -o " + path("out"));
  ASSERT_EQ(r.code, 0) << r.out;
  const json j = json::parse(ReadFile(path("out/compare.json")));
  ASSERT_EQ(j["methods"].size(), 2u);
  EXPECT_GT(j["methods"][1]["iou"].get<double>(), 0.8);  // the shape modulus hugs the sphere
  EXPECT_LT(j["methods"][1]["psi_one_application"].get<double>(), -0.5);
  EXPECT_TRUE(std::filesystem::exists(path("out/compare.md")));
  EXPECT_TRUE(std::filesystem::exists(path("out/modulus.png")));
  // A missing map: exit 1, no output folder content.
  r = RunQuijibo("compare --target " + path("s.qgrid") + " --map " + path("nope.json") + " -o " + path("out2"));
  EXPECT_EQ(r.code, 1);
  EXPECT_FALSE(std::filesystem::exists(path("out2/compare.json")));
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace quijibo
