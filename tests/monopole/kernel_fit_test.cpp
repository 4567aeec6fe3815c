#include "monopole/kernel_fit.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <utility>

#include "monopole/test_meshes.h"
#include "util/error.h"

namespace quijibo::monopole {
namespace {

// The exact signed distance of a union of two spheres (a dumbbell without a bar), and the
// triangles of both spheres as the surface.
struct TwoSpheres {
  std::vector<Vec3> vertices;
  std::vector<std::array<int, 3>> triangles;
  ScalarGrid sdf;
};

TwoSpheres MakeTwoSpheres(double r1, double r2) {
  TwoSpheres t;
  const Vec3 c1{-0.9, 0, 0}, c2{0.9, 0, 0};
  for (auto [c, r] : {std::pair{c1, r1}, std::pair{c2, r2}}) {
    const auto m = testing::MakeIcosphere(3, c, r);
    const int base = int(t.vertices.size());
    t.vertices.insert(t.vertices.end(), m.vertices.begin(), m.vertices.end());
    for (auto f : m.triangles) t.triangles.push_back({f[0] + base, f[1] + base, f[2] + base});
  }
  t.sdf.frame = GridFrame::Cube(40, {0, 0, 0}, 4.0);
  t.sdf.values.resize(std::size_t(t.sdf.frame.cell_count()));
  for (std::int64_t c = 0; c < t.sdf.frame.cell_count(); ++c) {
    const Vec3 p = t.sdf.frame.cell_center(c);
    auto d = [&](const Vec3& q, double r) {
      return std::sqrt((p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) + (p[2] - q[2]) * (p[2] - q[2])) - r;
    };
    t.sdf.values[std::size_t(c)] = std::min(d(c1, r1), d(c2, r2));
  }
  return t;
}

// The log-kernel fit of the two spheres in the fractal frame with `o`; its summary into *s if given.
RationalMap Fit(const TwoSpheres& t, const KernelFitOptions& o, KernelFitSummary* s = nullptr) {
  return KernelFitMap(t.vertices, t.triangles, t.sdf, FractalFrame{}, o, s);
}

struct SummarizedFit {
  RationalMap map;
  KernelFitSummary summary;
};

// The fits of t with `o` and with `o` as `change` leaves it (o keeps the change): what one option
// does.
template <class Change>
std::pair<SummarizedFit, SummarizedFit> FitBeforeAndAfter(const TwoSpheres& t, KernelFitOptions& o, Change change) {
  std::pair<SummarizedFit, SummarizedFit> fits;
  fits.first.map = Fit(t, o, &fits.first.summary);
  change(o);
  fits.second.map = Fit(t, o, &fits.second.summary);
  return fits;
}

TEST(KernelFit, StartsCloseOnTwoSpheresOfDifferentSize) {
  // A small sphere beside a large one: a fit that only captures the bulk loses the small one.
  const TwoSpheres t = MakeTwoSpheres(0.7, 0.3);
  KernelFitOptions o;
  o.roots = 120;
  o.origin_root = false;  // the origin lies between the spheres, outside the shape
  KernelFitSummary s;
  const RationalMap m = Fit(t, o, &s);
  const StartCheck c = CheckStart(m, t.sdf);
  EXPECT_FALSE(c.inverted);
  EXPECT_LT(c.median_inside, 0);
  EXPECT_GT(c.median_outside, 0);
  EXPECT_GT(c.iou, 0.85);
  EXPECT_GT(s.exponent_sum, 0);  // the set is bounded
  // Both spheres' centres are in the one-step set, the point between them is not.
  EXPECT_LT(OneStepLogModulus(m, {-0.9, 0, 0}), 0);
  EXPECT_LT(OneStepLogModulus(m, {0.9, 0, 0}), 0);
  EXPECT_GT(OneStepLogModulus(m, {0.25, 0, 0}), 0);
  EXPECT_GT(OneStepLogModulus(m, {0, 1.8, 0}), 0);
  // Far outside the grid, L is positive (the far-field rows).
  EXPECT_GT(OneStepLogModulus(m, {10, 3, -7}), 0);
  EXPECT_EQ(m.top_count() + m.bottom_count(), s.top + s.bottom);
}

TEST(KernelFit, TheOriginRootMakesTheOriginAZeroAndTheFitAccountsForIt) {
  // Spheres centred on the origin's two sides of a wide ellipsoid-like union: the origin inside.
  TwoSpheres t = MakeTwoSpheres(1.0, 1.0);
  KernelFitOptions o;
  o.roots = 120;
  const RationalMap m = Fit(t, o);
  ASSERT_GE(m.top_count(), 1);
  EXPECT_EQ(m.top_roots[0], (Vec4{0, 0, 0, 0}));
  EXPECT_EQ(m.top_exponents[0], 1.0);
  EXPECT_EQ(OneStepLogModulus(m, {0, 0, 0}), -std::numeric_limits<double>::infinity());
  const StartCheck c = CheckStart(m, t.sdf);
  EXPECT_GT(c.iou, 0.85);
  EXPECT_GT(OneStepLogModulus(m, {0, 1.6, 0}), 0);
}

TEST(KernelFit, RefinementAddsRootsWhereTheFitIsWrong) {
  // Few roots for a small sphere beside a large one: the first fit misses cells, refinement adds
  // pairs there and the start does not get worse.
  const TwoSpheres t = MakeTwoSpheres(0.7, 0.25);
  KernelFitOptions o;
  o.roots = 16;
  o.origin_root = false;
  o.thin_walls = AutoSwitch::kOff;  // few roots as set: the thin-wall rule has its own test
  const auto [plain, refined] = FitBeforeAndAfter(t, o, [](KernelFitOptions& x) { x.refine_rounds = 2; });
  EXPECT_EQ(plain.summary.refine_rounds, 0);
  EXPECT_GE(refined.summary.refine_rounds, 1);
  EXPECT_GT(refined.map.root_count(), plain.map.root_count());
  EXPECT_GE(CheckStart(refined.map, t.sdf).iou, CheckStart(plain.map, t.sdf).iou - 1e-9);
}

TEST(KernelFit, IsDeterministic) {
  const TwoSpheres t = MakeTwoSpheres(0.6, 0.4);
  KernelFitOptions o;
  o.roots = 60;
  const RationalMap a = Fit(t, o);
  const RationalMap b = Fit(t, o);
  EXPECT_EQ(a.top_exponents, b.top_exponents);
  EXPECT_EQ(a.bottom_exponents, b.bottom_exponents);
  EXPECT_EQ(a.ln_C, b.ln_C);
}

TEST(KernelFit, CheckStartDetectsAnInvertedMap) {
  const TwoSpheres t = MakeTwoSpheres(0.7, 0.5);
  KernelFitOptions o;
  o.roots = 60;
  RationalMap m = Fit(t, o);
  std::swap(m.top_roots, m.bottom_roots);
  std::swap(m.top_exponents, m.bottom_exponents);
  m.ln_C = -m.ln_C;
  const StartCheck c = CheckStart(m, t.sdf);
  EXPECT_TRUE(c.inverted);
  EXPECT_LT(c.iou, 0.2);
}

// A sphere of radius 0.7 at (-0.9, 0, 0) and a plate 0.3 thick at x = 0.9 (3 cells of the grid),
// with their exact signed distance.
TwoSpheres MakeSphereAndPlate() {
  TwoSpheres t;
  const auto m = testing::MakeIcosphere(3, {-0.9, 0, 0}, 0.7);
  t.vertices = m.vertices;
  t.triangles = m.triangles;
  const Vec3 c{0.9, 0, 0}, e{0.15, 0.6, 0.6};  // the plate's centre and half extents
  const int base = int(t.vertices.size());
  for (int k = 0; k < 8; ++k)
    t.vertices.push_back({c[0] + (k & 1 ? e[0] : -e[0]), c[1] + (k & 2 ? e[1] : -e[1]), c[2] + (k & 4 ? e[2] : -e[2])});
  for (auto [a, b, cc, d] : {std::array{0, 2, 6, 4}, std::array{1, 5, 7, 3}, std::array{0, 4, 5, 1},
                             std::array{2, 3, 7, 6}, std::array{0, 1, 3, 2}, std::array{4, 6, 7, 5}}) {
    t.triangles.push_back({base + a, base + b, base + cc});
    t.triangles.push_back({base + a, base + cc, base + d});
  }
  t.sdf.frame = GridFrame::Cube(40, {0, 0, 0}, 4.0);
  t.sdf.values.resize(std::size_t(t.sdf.frame.cell_count()));
  for (std::int64_t k = 0; k < t.sdf.frame.cell_count(); ++k) {
    const Vec3 p = t.sdf.frame.cell_center(k);
    const double sphere = std::sqrt((p[0] + 0.9) * (p[0] + 0.9) + p[1] * p[1] + p[2] * p[2]) - 0.7;
    double q[3], outside = 0, inside = -1e9;
    for (int a = 0; a < 3; ++a) {
      q[a] = std::abs(p[a] - c[a]) - e[a];
      outside += std::max(q[a], 0.0) * std::max(q[a], 0.0);
      inside = std::max(inside, q[a]);
    }
    const double plate = std::sqrt(outside) + std::min(inside, 0.0);
    t.sdf.values[std::size_t(k)] = std::min(sphere, plate);
  }
  return t;
}

TEST(KernelFit, ThinPartsGetDenserRootPairsAndTheSpacingRuleSetsTheCount) {
  const TwoSpheres t = MakeSphereAndPlate();
  const double sphere_area = 4 * M_PI * 0.7 * 0.7, plate_area = 2 * (4 * 0.15 * 0.6 + 4 * 0.15 * 0.6 + 4 * 0.6 * 0.6);
  KernelFitOptions o;
  o.offset_cells = 4;  // the plate, 3 cells thick, shortens its pairs' offsets below 1.5 cells
  o.origin_root = false;
  o.roots = o.max_roots = 200;
  o.thin_walls = AutoSwitch::kOff;  // the spacing rule as set: the thin-wall rule has its own test
  const RationalMap m = Fit(t, o);
  EXPECT_EQ(m.root_count(), 200);
  int near_plate = 0;
  for (const auto* roots : {&m.top_roots, &m.bottom_roots})
    for (const Vec4& r : *roots) near_plate += r[0] > 0.3;
  const double plate_density = near_plate / plate_area, sphere_density = (200 - near_plate) / sphere_area;
  EXPECT_GT(plate_density, 3 * sphere_density);  // uniform sampling would give 1

  // The rule sets the count: halving the spacing (in units of the 0.4 offset) asks for about four
  // times the pairs.
  o.roots = 16;
  o.max_roots = 1000;
  o.spacing = 2;
  const auto [wide, narrow] = FitBeforeAndAfter(t, o, [](KernelFitOptions& x) { x.spacing = 1; });
  EXPECT_EQ(wide.summary.spacing, 2);
  EXPECT_EQ(narrow.summary.spacing, 1);
  EXPECT_GT(narrow.map.root_count(), 2.5 * wide.map.root_count());
  EXPECT_LT(narrow.map.root_count(), 5.5 * wide.map.root_count());
  // And the bound binds: the spacing grows until the count fits.
  o.max_roots = narrow.map.root_count() / 4 * 2;  // even: pairs
  KernelFitSummary capped;
  const RationalMap c = Fit(t, o, &capped);
  EXPECT_EQ(c.root_count(), o.max_roots);
  EXPECT_GT(capped.spacing, 1.2);
}

// thin_walls: on a thin-walled target (two spheres 4 cells in radius: the inside's 90th percentile
// depth 2.1 cells) auto spaces the pairs 0.6 times as far and doubles max_roots, so more roots;
// on a thick one (9 cells) auto is off and the fit is the one without the rule.
TEST(KernelFit, ThinWallsDensifyThePairsOnAThinWalledTargetOnly) {
  KernelFitOptions o;
  o.roots = 16;
  o.max_roots = 400;
  o.thin_walls = AutoSwitch::kOff;
  const TwoSpheres thin = MakeTwoSpheres(0.4, 0.4);
  EXPECT_LT(WallDepthCells(thin.sdf), kThinWallDepthCells);
  const auto [off, on] = FitBeforeAndAfter(thin, o, [](KernelFitOptions& x) { x.thin_walls = AutoSwitch::kAuto; });
  EXPECT_FALSE(off.summary.thin_walls);
  EXPECT_TRUE(on.summary.thin_walls);
  EXPECT_DOUBLE_EQ(on.summary.spacing, 0.6 * off.summary.spacing);
  EXPECT_GT(on.map.root_count(), 2 * off.map.root_count());
  EXPECT_NEAR(on.summary.wall_depth_cells, WallDepthCells(thin.sdf), 0.0);

  o.thin_walls = AutoSwitch::kOff;
  const TwoSpheres thick = MakeTwoSpheres(0.9, 0.9);
  EXPECT_GT(WallDepthCells(thick.sdf), kThinWallDepthCells);
  const auto [plain, automatic] =
      FitBeforeAndAfter(thick, o, [](KernelFitOptions& x) { x.thin_walls = AutoSwitch::kAuto; });
  EXPECT_FALSE(automatic.summary.thin_walls);
  EXPECT_EQ(automatic.map.variables(), plain.map.variables());
  EXPECT_EQ(automatic.map.top_roots, plain.map.top_roots);
}

TEST(KernelFit, RejectsBadOptions) {
  const TwoSpheres t = MakeTwoSpheres(0.7, 0.5);
  KernelFitOptions o;
  o.roots = 2;
  EXPECT_THROW(Fit(t, o), Error);
  o = {};
  o.band_cells = -1;
  EXPECT_THROW(Fit(t, o), Error);
  o = {};
  o.spacing = 0.5;
  EXPECT_THROW(Fit(t, o), Error);
}

}  // namespace
}  // namespace quijibo::monopole
