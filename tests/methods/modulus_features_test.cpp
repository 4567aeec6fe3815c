// The 2023/2024 controls, each checked for what it is meant to do (issue 16 §3): the origin offset,
// spatially varying alpha, SDF masks, noise-blended portal transforms, 3D portals that repeat the
// set at smaller scales, and portals on a QUIJIBO rational map.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <vector>

#include "util/io.h"
#include "methods/modulus.h"
#include "modulus_fixtures.h"
#include "methods/portal.h"
#include "quijibo/quaternion_map.h"
#include "quijibo_command.h"

namespace quijibo {
namespace {

using nlohmann::json;

using testing::PolynomialVersor;

// Inside flags (field < 0) of `map` on an n^3 grid of cell centres over [lo, hi]^3 (k = 0).
std::vector<char> InsideGrid(const QuaternionMap& map, int n, double lo, double hi, const IterationOptions& jo,
                             std::vector<Vec3>* points = nullptr) {
  std::vector<char> in(std::size_t(n) * n * n);
  if (points) points->resize(in.size());
#pragma omp parallel for schedule(dynamic, 1)
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const Vec3 p{lo + (hi - lo) * (i + 0.5) / n, lo + (hi - lo) * (j + 0.5) / n, lo + (hi - lo) * (k + 0.5) / n};
        const std::size_t c = (std::size_t(k) * n + j) * n + i;
        in[c] = IterateField(map, {p[0], p[1], p[2], 0.0}, jo) < 0;
        if (points) (*points)[c] = p;
      }
  return in;
}

double Iou(const std::vector<char>& a, const std::vector<char>& b) {
  std::int64_t both = 0, either = 0;
  for (std::size_t c = 0; c < a.size(); ++c) both += a[c] && b[c], either += a[c] || b[c];
  return either ? double(both) / double(either) : 0.0;
}

std::int64_t Count(const std::vector<char>& a) {
  std::int64_t n = 0;
  for (char c : a) n += c;
  return n;
}

// ---- origin offset (2023 Fig. 5) ----

// The map with offset o is the map without it read at q - o (phi, alpha, beta and the versor
// move together), bit for bit.
TEST(OriginOffset, MapIsTheUnshiftedMapReadAtTheShiftedPoint) {
  ShapeModulusOptions so;
  so.alpha = 30.0;
  so.beta = -0.02;
  ShapeModulusMap plain(AnalyticModulusTarget("sphere:radius=0.3"), PolynomialVersor(3), so);
  so.origin_offset = {0.11, -0.07, 0.05};
  ShapeModulusMap moved(AnalyticModulusTarget("sphere:radius=0.3"), PolynomialVersor(3), so);
  for (int i = 0; i < 50; ++i) {
    const Quat q{-0.5 + 0.021 * i, 0.3 - 0.013 * i, 0.2 - 0.009 * i, 0.0};
    const Quat shifted{q.w - 0.11, q.x + 0.07, q.y - 0.05, 0.0};
    EXPECT_EQ(moved.LogModulus(q), plain.LogModulus(shifted)) << i;
    const Quat a = moved.Direction(q), b = plain.Direction(shifted);
    EXPECT_EQ(a.w, b.w);
    EXPECT_EQ(a.x, b.x);
    EXPECT_EQ(a.y, b.y);
    EXPECT_EQ(a.z, b.z);
  }
}

// At high alpha, while the attracting origin stays inside the moved target, the set is the target
// moved by the offset; once the origin leaves it, the interior erodes (everything escapes).
TEST(OriginOffset, MovesTheSetWhileTheOriginStaysInsideThenErodesIt) {
  const IterationOptions jo{20, 20.0};
  const int n = 40;
  const double lo = -0.7, hi = 0.7;
  auto set = [&](const Vec3& o) {
    ShapeModulusOptions so;
    so.alpha = 300.0;
    so.origin_offset = o;
    return InsideGrid(ShapeModulusMap(AnalyticModulusTarget("sphere:radius=0.3"), PolynomialVersor(5), so), n, lo, hi, jo);
  };
  auto ball = [&](const Vec3& c) {
    std::vector<char> in(std::size_t(n) * n * n);
    for (int k = 0; k < n; ++k)
      for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
          const double x = lo + (hi - lo) * (i + 0.5) / n - c[0], y = lo + (hi - lo) * (j + 0.5) / n - c[1],
                       z = lo + (hi - lo) * (k + 0.5) / n - c[2];
          in[(std::size_t(k) * n + j) * n + i] = std::sqrt(x * x + y * y + z * z) < 0.3;
        }
    return in;
  };
  const Vec3 o{0.2, 0.1, 0.0};  // |o| = 0.22 < 0.3: the origin is still inside the moved ball
  const auto moved = set(o);
  EXPECT_GT(Iou(moved, ball(o)), 0.9);
  EXPECT_LT(Iou(moved, ball({0, 0, 0})), 0.6);
  // |o| = 0.4 > 0.3: the inside points fall onto the origin, which is now outside, and escape.
  const auto eroded = set({0.4, 0.0, 0.0});
  std::printf("offset: IoU with the moved ball %.4f, with the unmoved ball %.4f; inside %lld, eroded %lld\n",
              Iou(moved, ball(o)), Iou(moved, ball({0, 0, 0})), (long long)Count(moved), (long long)Count(eroded));
  EXPECT_GT(Count(moved), 1000);
  EXPECT_LT(Count(eroded), Count(moved) / 20);
}

// ---- spatially varying alpha (2023 Figs. 7, 13) ----

// alpha = 300 for x > 0, 10 for x < 0 with a cubic ramp of width 0.2: the one-application
// modulus is that of the constant-300 map wherever the ramp has not started (bit for bit), and
// the Julia set is the alpha-300 set on that side and the alpha-10 set on the other.
TEST(VaryingAlpha, ChangesTheSetOnlyWhereItVaries) {
  const ParameterField alpha = testing::HalfspaceStep();
  auto make = [&](const ParameterField& a) {
    ShapeModulusOptions so;
    so.alpha = a;
    return ShapeModulusMap(AnalyticModulusTarget("sphere:radius=0.3"), PolynomialVersor(7), so);
  };
  const ShapeModulusMap varying = make(alpha), high = make(300.0), low = make(10.0);
  for (int i = 0; i <= 16; ++i) {
    const Quat right{0.1 + 0.025 * i, 0.17, -0.05, 0}, left{-0.1 - 0.025 * i, 0.17, -0.05, 0},
        ramp{-0.08 + 0.01 * i, 0.17, -0.05, 0};
    EXPECT_EQ(varying.LogModulus(right), high.LogModulus(right)) << right.w;
    EXPECT_EQ(varying.LogModulus(left), low.LogModulus(left)) << left.w;
    EXPECT_NE(varying.LogModulus(ramp), high.LogModulus(ramp)) << ramp.w;
    EXPECT_NE(varying.LogModulus(ramp), low.LogModulus(ramp)) << ramp.w;
  }
  const IterationOptions jo{3, 20.0};
  const int n = 40;
  std::vector<Vec3> p;
  const auto v = InsideGrid(varying, n, -0.5, 0.5, jo, &p), h = InsideGrid(high, n, -0.5, 0.5, jo),
             l = InsideGrid(low, n, -0.5, 0.5, jo);
  std::int64_t right = 0, right_same = 0, left = 0, left_same = 0, left_low_vs_high = 0;
  for (std::size_t c = 0; c < p.size(); ++c) {
    if (p[c][0] > 0.15) ++right, right_same += v[c] == h[c];
    if (p[c][0] < -0.15) ++left, left_same += v[c] == l[c], left_low_vs_high += l[c] != h[c];
  }
  std::printf("varying alpha: right side = alpha 300 set at %.4f, left side = alpha 10 set at %.4f; 10 vs 300 differ at %.4f\n",
              double(right_same) / right, double(left_same) / left, double(left_low_vs_high) / left);
  EXPECT_GT(double(right_same) / right, 0.99);
  EXPECT_GT(double(left_same) / left, 0.99);
  EXPECT_GT(double(left_low_vs_high) / left, 0.02);  // alpha 10 and 300 do differ there
}

// ---- SDF masks ----

// A sphere's signed distance on a grid, centred at the grid's origin.
std::shared_ptr<ScalarGrid> SphereGrid(double radius, int n) {
  auto g = std::make_shared<ScalarGrid>();
  g->frame = GridFrame::Cube(n, {0, 0, 0}, 1.0);
  g->values.resize(g->frame.cell_count());
  for (std::int64_t c = 0; c < g->frame.cell_count(); ++c) {
    const Vec3 x = g->frame.cell_center(c);
    g->values[c] = std::sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]) - radius;
  }
  return g;
}

TEST(SdfMask, DistanceIsTheGridPlacedAndScaled) {
  Mask m;
  m.type = Mask::Type::kSdf;
  m.sdf = SphereGrid(0.2, 64);
  m.center = {0.1, -0.05, 0.0};
  m.sdf_scale = 1.5;  // a ball of radius 0.3 about the centre
  ASSERT_EQ(m.Validate(), "");
  for (int i = 0; i < 30; ++i) {
    const Vec3 p{-0.6 + 0.04 * i, 0.1 - 0.01 * i, 0.03 * std::sin(i)};
    const double exact = std::hypot(p[0] - 0.1, p[1] + 0.05, p[2]) - 0.3;
    EXPECT_NEAR(m.distance(p), exact, 0.01) << i;  // trilinear error, extended beyond the grid
  }
}

// beta = +1 (no set) outside an SDF mask, 0 inside it: the set is the target cut by the mask:
// empty outside the mask, unchanged deep inside it.
TEST(SdfMask, MaskedBetaCutsTheSetToTheMask) {
  ParameterField beta(1.0);
  ParameterField::Region r;
  r.mask.type = Mask::Type::kSdf;
  r.mask.sdf = SphereGrid(0.25, 48);
  r.mask.center = {0.12, 0.0, 0.0};
  r.value = 0.0;
  r.feather = 0.06;
  beta.regions.push_back(r);
  ShapeModulusOptions so;
  so.alpha = 300.0;
  const ShapeModulusMap plain(AnalyticModulusTarget("sphere:radius=0.35"), PolynomialVersor(2), so);
  so.beta = beta;
  const ShapeModulusMap cut(AnalyticModulusTarget("sphere:radius=0.35"), PolynomialVersor(2), so);
  const IterationOptions jo{10, 20.0};
  std::vector<Vec3> p;
  const auto a = InsideGrid(plain, 40, -0.5, 0.5, jo, &p), b = InsideGrid(cut, 40, -0.5, 0.5, jo);
  std::int64_t outside_in = 0, deep = 0, deep_same = 0, cut_away = 0;
  for (std::size_t c = 0; c < p.size(); ++c) {
    const double d = r.mask.distance(p[c]);
    if (d > 0.0) outside_in += b[c];  // beta > 0.5 there: phi + beta > 0.15 in the target
    if (d < -0.03) ++deep, deep_same += a[c] == b[c];
    cut_away += a[c] && !b[c];
  }
  std::printf("sdf mask: deep inside %lld points, same %lld; cut away %lld of %lld\n", (long long)deep,
              (long long)deep_same, (long long)cut_away, (long long)Count(a));
  EXPECT_EQ(outside_in, 0);
  ASSERT_GT(deep, 1000);
  EXPECT_EQ(deep_same, deep);
  EXPECT_GT(cut_away, Count(a) / 5);  // the mask did remove part of the sphere
}

// ---- noise-blended portal transforms (2024 §3.3) ----

PortalTransform NoisyTransform(std::uint64_t seed, double amplitude) {
  PortalTransform t;
  t.center = {0.3, 0.1, 0.0};
  t.scale = 3.0;
  t.angle_deg = 20.0;
  t.translation = {0.05, 0.0, 0.0};
  t.noise.seed = seed;
  t.noise.frequency = 8.0;
  t.noise_amplitude = amplitude;
  return t;
}

TEST(NoiseTransform, AddsTheSeededNoiseToTheAffineTransform) {
  const PortalTransform affine = NoisyTransform(4, 0.0), noisy = NoisyTransform(4, 0.02);
  double largest = 0;
  for (int i = 0; i < 40; ++i) {
    const Vec3 x{0.2 + 0.005 * i, 0.05 + 0.003 * i, 0.0};
    const Vec3 a = affine.Apply(x), b = noisy.Apply(x), n = noisy.noise(x);
    for (int k = 0; k < 3; ++k) {
      EXPECT_NEAR(b[k] - a[k], 0.02 * n[k], 1e-15);
      largest = std::max(largest, std::abs(b[k] - a[k]));
    }
  }
  EXPECT_GT(largest, 0.002);
}

// The Koch snowflake with noise-blended transforms: the picture is a function of the seed
// (identical twice, different for another seed), differs from the unblended snowflake, and one
// application of F_F is untouched outside the portals.
TEST(NoiseTransform, DeterministicUnderItsSeedAndDifferentFromUnblended) {
  auto koch = [](std::uint64_t seed, double amplitude) {
    ShapeModulusOptions so;
    so.alpha = 3000.0;
    VersorGeneratorOptions g;
    g.box_min = {-0.6, -0.6, 0};
    g.box_max = {0.6, 0.6, 0};
    Versor v;
    v.polynomial = GenerateVersorPolynomial(g);
    auto base = std::make_shared<ShapeModulusMap>(AnalyticModulusTarget("hexagram:size=1"), v, so);
    std::vector<Portal> portals = KochPortals(1.0, 0.005);
    for (Portal& p : portals) {
      p.transform.noise.seed = seed;
      p.transform.noise.frequency = 10.0;
      p.transform.noise_amplitude = amplitude;
    }
    return std::make_shared<PortalMap>(base, portals, [base](const Quat& q) { return base->LogModulus(q); });
  };
  View2D view;
  view.x_min = view.y_min = -0.62;
  view.x_max = view.y_max = 0.62;
  view.width = view.height = 120;
  const IterationOptions jo{30, 20.0};
  auto inside = [&](const QuaternionMap& m) {
    std::vector<char> in;
    for (double f : SampleField2D(m, jo, view)) in.push_back(f < 0);
    return in;
  };
  const auto plain_map = koch(1, 0.0), noisy_map = koch(1, 0.05);
  const auto a = inside(*noisy_map), b = inside(*koch(1, 0.05)), c = inside(*koch(2, 0.05)), plain = inside(*plain_map);
  EXPECT_EQ(a, b);
  std::int64_t seed_diff = 0, plain_diff = 0;
  for (std::size_t i = 0; i < a.size(); ++i) seed_diff += a[i] != c[i], plain_diff += a[i] != plain[i];
  std::printf("noise transforms: %lld pixels differ from seed 2, %lld from the unblended snowflake (of %zu)\n",
              (long long)seed_diff, (long long)plain_diff, a.size());
  EXPECT_GT(seed_diff, 20);
  EXPECT_GT(plain_diff, 20);
  // The portal discs lie between radii 0.19 and 0.58 about the origin: sample inside and beyond.
  for (int i = 0; i < 200; ++i) {
    const double radius = i % 2 ? 0.15 : 0.6, angle = 0.0314 * i;
    const Quat q{radius * std::cos(angle), radius * std::sin(angle), 0, 0};
    const Quat f = noisy_map->Apply(q), g = plain_map->Apply(q);
    EXPECT_EQ(f.w, g.w);
    EXPECT_EQ(f.x, g.x);
  }
}

// ---- 3D portals: the set repeated at smaller scales ----

// The inside intervals of the set along the x axis (y = z = 0), sampled at `samples` points.
std::vector<std::pair<double, double>> Intervals(const QuaternionMap& m, double x0, double x1, int samples,
                                                 const IterationOptions& jo) {
  std::vector<std::pair<double, double>> out;
  bool in = false;
  for (int i = 0; i < samples; ++i) {
    const double x = x0 + (x1 - x0) * (i + 0.5) / samples;
    const bool now = IterateField(m, {x, 0, 0, 0}, jo) < 0;
    if (now && !in) out.push_back({x, x});
    if (now) out.back().second = x;
    in = now;
  }
  return out;
}

// A ball of radius 0.3 and a hard portal, the ball B(c, 0.15) with c = (0.5, 0, 0), taking
// T(x) = 4 (x - c) (the whole scene around the origin, 4 times smaller, into the portal). The
// portal's image B(0, 0.6) holds the ball and part of the portal, so the copy holds a copy:
// along the x axis the set is [-0.3, 0.3], then c + [-0.3, 0.3]/4 = [0.425, 0.575], then
// c + [0.425, 0.575]/4 = [0.60625, 0.64375]: lengths 0.6, 0.15, 0.0375. In volume, the first copy
// is the ball's volume / 64.
TEST(Portal3D, RepeatsTheSetAtSmallerScales) {
  ShapeModulusOptions so;
  so.alpha = 3000.0;
  auto base = std::make_shared<ShapeModulusMap>(AnalyticModulusTarget("sphere:radius=0.3"), PolynomialVersor(8), so);
  Portal p;
  p.mask.type = Mask::Type::kSphere;
  p.mask.center = {0.5, 0, 0};
  p.mask.radius = 0.15;
  p.transform.center = p.mask.center;
  p.transform.scale = 4.0;
  const PortalMap pm(base, {p}, nullptr);
  const IterationOptions jo{30, 20.0};
  const auto iv = Intervals(pm, -0.5, 0.7, 24000, jo);
  ASSERT_EQ(iv.size(), 3u);
  const double expected[3][2] = {{-0.3, 0.3}, {0.425, 0.575}, {0.60625, 0.64375}};
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(iv[i].first, expected[i][0], 2e-3) << i;
    EXPECT_NEAR(iv[i].second, expected[i][1], 2e-3) << i;
  }
  // Volume inside the portal ball, first copy only (the second lies beyond x = 0.59).
  const int n = 60;
  std::int64_t in = 0;
  const double side = 0.3, h = side / n;
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const Vec3 x{0.35 + h * (i + 0.5), -0.15 + h * (j + 0.5), -0.15 + h * (k + 0.5)};
        if (x[0] > 0.59) continue;
        in += IterateField(pm, {x[0], x[1], x[2], 0}, jo) < 0;
      }
  const double volume = double(in) * h * h * h, ball = 4.0 / 3.0 * M_PI * 0.3 * 0.3 * 0.3;
  std::printf("3D portal: first copy's volume / (ball / 64) = %.4f\n", volume / (ball / 64.0));
  EXPECT_NEAR(volume / (ball / 64.0), 1.0, 0.05);
}

// ---- portals on a QUIJIBO rational map ----

// R(q) = q^2, written as a QUIJIBO map (one top root at 0 with exponent 2): its Julia set is the
// unit ball, and log|R| = 2 log|q|. A hard portal B(c, 0.6), c = (1.5, 0, 0), T(x) = 4 (x - c),
// cut by the base set (exclude_base), so [0.9, 1] stays in the ball. The real axis is invariant.
// On [-1.05, 2.2] the set's pieces longer than 0.02 are, by hand:
//   [-1, 1]                          the ball (the part of the portal inside it included)
//   [1.25, 1.75] = T^-1([-1, 1])     the ball 4 times smaller
//   [1.8125, 1.9375], [1.953125, 1.984375]   copies of copies, x -> c + x/4, towards T's fixed point 2
//   [1.5 - sqrt(1.75)/4, 1.5 - sqrt(1.25)/4]  a copy reached through the base map: T(x) = -sqrt(y)
//                                    squares onto y in [1.25, 1.75] (the paper's spontaneous copies)
// and the rest is dust (pieces of 0.0128 and less).
TEST(Portal, OnAQuijiboMapRepeatsItsSet) {
  RationalMap m;
  m.top_roots = {{0, 0, 0, 0}};
  m.top_exponents = {2.0};
  ASSERT_EQ(m.Validate(), "");
  auto rm = std::make_shared<RationalQuaternionMap>(m);
  Portal p;
  p.mask.center = {1.5, 0, 0};
  p.mask.radius = 0.6;
  p.exclude_base = true;
  p.transform.center = p.mask.center;
  p.transform.scale = 4.0;
  const PortalMap pm(rm, {p}, [rm](const Quat& q) { return rm->LogModulus(q); });
  const Quat q{1.6, 0.1, 0.05, 0.0};
  EXPECT_NEAR((pm.Apply(q) - Quat{0.4, 0.4, 0.2, 0.0}).norm(), 0.0, 1e-12);  // T(q), q outside the unit ball
  const Quat far{3, 0, 0, 0}, near{0.5, 0.2, 0, 0};
  EXPECT_NEAR((pm.Apply(far) - rm->Apply(far)).norm(), 0.0, 1e-12);
  EXPECT_NEAR((pm.Apply(near) - rm->Apply(near)).norm(), 0.0, 1e-12);
  std::vector<std::pair<double, double>> pieces;
  for (const auto& v : Intervals(pm, -1.05, 2.2, 65000, IterationOptions{60, 1e6}))
    if (v.second - v.first > 0.02) pieces.push_back(v);
  ASSERT_EQ(pieces.size(), 5u);
  const double expected[5][2] = {{-1.0, 1.0},
                                 {1.5 - std::sqrt(1.75) / 4, 1.5 - std::sqrt(1.25) / 4},
                                 {1.25, 1.75},
                                 {1.8125, 1.9375},
                                 {1.953125, 1.984375}};
  for (int i = 0; i < 5; ++i) {
    EXPECT_NEAR(pieces[i].first, expected[i][0], 1e-4) << i;
    EXPECT_NEAR(pieces[i].second, expected[i][1], 1e-4) << i;
  }
}

// ---- the commands ----

using quijibo::testing::RunQuijibo;

// An "sdf" mask given as a mesh is normalized like the mesh target, so the target's own mesh as a
// mask lines up with it: cutting beta outside it keeps most of the set; the same mask moved
// sideways cuts most of it away. Runs `quijibo modulus` on the bunny's z = 0 slice.
TEST(SdfMaskCli, MeshMaskLinesUpWithTheTarget) {
  const auto dir = std::filesystem::temp_directory_path() / "quijibo_sdf_mask_cli";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const std::string bunny = std::string(QUIJIBO_SOURCE_DIR) + "/data/bunny.obj";
  auto params = [&](const std::string& name, const std::string& center) {
    const std::string path = (dir / name).string();
    std::ofstream(path) << R"({"alpha": 300, "beta": {"value": 1, "regions": [{"mask": {"type": "sdf", "file": ")"
                        << bunny << R"(", "center": )" << center << R"(}, "value": 0, "feather": 0.02}]}})";
    return path;
  };
  auto inside = [&](const std::string& extra) {
    const auto r = RunQuijibo("modulus " + bunny + " --sdf-resolution 48 --png-size 96 " + extra + " -o " +
                              (dir / "m.png").string());
    EXPECT_EQ(r.code, 0) << r.out;
    return r.code == 0 ? json::parse(r.out)["result"]["inside_pixels"].get<double>() : -1.0;
  };
  const double plain = inside("--alpha 300"), aligned = inside("--params " + params("a.json", "[0, 0, 0]")),
               moved = inside("--params " + params("b.json", "[0.3, 0, 0]"));
  std::printf("mesh mask: inside pixels %g plain, %g aligned mask, %g moved mask\n", plain, aligned, moved);
  ASSERT_GT(plain, 500);
  EXPECT_GT(aligned / plain, 0.8);
  EXPECT_LT(aligned, plain);
  EXPECT_LT(moved / plain, 0.6);
  std::filesystem::remove_all(dir);
}

// An experiment's "params" file is read and checked by `quijibo run --check`: a wrong key in a
// region's mask fails with the params file and the JSON pointer, before anything runs.
TEST(ModulusExperiment, ParamsAreCheckedUpFront) {
  const auto dir = std::filesystem::temp_directory_path() / "quijibo_modulus_params_check";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const std::string exp = (dir / "e.json").string(), params = (dir / "p.json").string();
  std::ofstream(exp) << R"({"method": "modulus", "target": {"analytic": "disc"},
    "modulus": {"params": "p.json", "output": {"format": "png", "png_size": 32}}})";
  std::ofstream(params) << R"({"alpha": {"value": 30, "regions": [{"mask": {"type": "sphere", "center": [0, 0], "radius": 0.1}, "value": 5, "feather": 0.1}]}})";
  auto r = RunQuijibo("run " + exp + " --check");
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_EQ(json::parse(r.out)["modulus"]["params"], params);
  std::ofstream(params) << R"({"alpha": {"value": 30, "regions": [{"mask": {"type": "sphere", "centre": [0, 0], "radius": 0.1}, "value": 5, "feather": 0.1}]}})";
  r = RunQuijibo("run " + exp + " --check");
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.out.find("p.json"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("/alpha/regions/0/mask"), std::string::npos) << r.out;
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace quijibo
