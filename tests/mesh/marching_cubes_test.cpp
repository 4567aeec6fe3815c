// Marching cubes with bisection: closed manifold output, accuracy, dense = sparse, tile seams,
// thread-count independence, PLY round trip.
#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

#include "mesh/marching_cubes.h"
#include "mesh/triangle_mesh.h"
#include "mesh/vdb.h"
#include "mesh_fixtures.h"
#include "util/error.h"

namespace quijibo::mesh {
namespace {

using testing::Lambda;
using testing::TempDir;

double Norm(const Vec3& p) { return std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]); }

BatchField Sphere(double r, Vec3 c = {0.1, -0.05, 0.03}) {
  return Lambda([r, c](const Vec3& p) { return Norm({p[0] - c[0], p[1] - c[1], p[2] - c[2]}) - r; });
}

// A gyroid clipped by a ball: many ambiguous faces, several handles, closed.
BatchField Gyroid() {
  return Lambda([](const Vec3& p) {
    const double g = std::sin(3 * p[0]) * std::cos(3 * p[1]) + std::sin(3 * p[1]) * std::cos(3 * p[2]) +
                     std::sin(3 * p[2]) * std::cos(3 * p[0]);
    return std::max(g + 0.2, Norm(p) - 1.6);
  });
}

std::int64_t Euler(const TriangleMesh& m, const MeshTopology& t) {
  return std::int64_t(m.vertices.size()) - t.edges + std::int64_t(m.triangles.size());
}

using testing::Canonical;

TEST(MarchingCubes, SphereIsClosedManifoldGenusZero) {
  MeshingOptions o;
  o.resolution = 48;
  MeshingSummary s;
  const TriangleMesh m = MeshField(Sphere(1.2), o, &s);
  ASSERT_GT(m.triangles.size(), 1000u);
  const MeshTopology t = AnalyzeTopology(m);
  EXPECT_TRUE(t.closed());
  EXPECT_EQ(t.boundary_edges, 0);
  EXPECT_EQ(t.non_manifold_edges, 0);
  EXPECT_EQ(t.misoriented_edges, 0);
  EXPECT_EQ(Euler(m, t), 2);
  EXPECT_NEAR(t.signed_volume, 4.0 / 3.0 * M_PI * std::pow(1.2, 3), 0.02);  // outward faces
  // Bisection: 6 steps leave at most h / 64 along the edge.
  double worst = 0;
  for (const Vec3& v : m.vertices) worst = std::max(worst, std::abs(Norm({v[0] - 0.1, v[1] + 0.05, v[2] - 0.03}) - 1.2));
  EXPECT_LT(worst, s.spacing / 64 * 1.01);
  EXPECT_EQ(s.vertices, std::int64_t(m.vertices.size()));
  EXPECT_EQ(s.non_finite_values, 0);
  EXPECT_GT(s.bisection_evaluations, 0);
  // No duplicate positions (vertices are shared between cells and tiles).
  std::set<Vec3> unique(m.vertices.begin(), m.vertices.end());
  EXPECT_EQ(unique.size(), m.vertices.size());
}

// A small resolution searches finely enough (here: dense) not to miss a ball that falls between
// the nodes of the default 8-cell search lattice.
TEST(MarchingCubes, SmallResolutionDoesNotMissTheSurface) {
  MeshingOptions o;
  o.resolution = 24;
  MeshingSummary s;
  const TriangleMesh m = MeshField(Sphere(1.0, {0, 0, 0}), o, &s);
  EXPECT_GT(m.triangles.size(), 100u);
  EXPECT_TRUE(AnalyzeTopology(m).closed());
}

TEST(MarchingCubes, MoreBisectionStepsAreMoreAccurate) {
  MeshingOptions o;
  o.resolution = 24;
  o.bisection_steps = 20;
  MeshingSummary s;
  const TriangleMesh m = MeshField(Sphere(1.0, {0, 0, 0}), o, &s);
  for (const Vec3& v : m.vertices) EXPECT_NEAR(Norm(v), 1.0, s.spacing * 2e-6);
}

// --bisection-interpolate: the same triangles as plain bisection (connectivity depends only on the
// node signs), every vertex on its edge, and on a sphere 3 steps + interpolation are closer to the
// surface than 6 plain steps; 0 steps is plain marching cubes interpolation.
TEST(MarchingCubes, BisectionInterpolationMovesOnlyVertices) {
  MeshingOptions o;
  o.resolution = 24;
  const BatchField sphere = Sphere(1.0, {0.02, -0.01, 0.03});
  MeshingSummary s6, s3;
  const TriangleMesh plain = MeshField(sphere, o, &s6);
  o.bisection_steps = 3;
  o.bisection_interpolate = true;
  const TriangleMesh interp = MeshField(sphere, o, &s3);
  ASSERT_EQ(plain.triangles, interp.triangles);
  ASSERT_EQ(plain.vertices.size(), interp.vertices.size());
  EXPECT_LT(s3.bisection_evaluations, s6.bisection_evaluations);
  const Vec3 c{0.02, -0.01, 0.03};
  double worst_plain = 0, worst_interp = 0, moved = 0;
  for (std::size_t v = 0; v < plain.vertices.size(); ++v) {
    const Vec3 &a = plain.vertices[v], &b = interp.vertices[v];
    worst_plain = std::max(worst_plain, std::abs(Norm({a[0] - c[0], a[1] - c[1], a[2] - c[2]}) - 1.0));
    worst_interp = std::max(worst_interp, std::abs(Norm({b[0] - c[0], b[1] - c[1], b[2] - c[2]}) - 1.0));
    moved = std::max(moved, Norm({a[0] - b[0], a[1] - b[1], a[2] - b[2]}));
  }
  EXPECT_LT(worst_interp, worst_plain);
  EXPECT_LE(moved, s6.spacing / 8 + 1e-12);  // both within their last bracket of h / 8
  o.bisection_steps = 0;
  EXPECT_EQ(MeshField(sphere, o).triangles, plain.triangles);
  o.bisection_interpolate = false;
  EXPECT_THROW(MeshField(sphere, o), Error);  // 0 steps only with interpolation
}

// --secant-steps (false position after bisection, then interpolation): the same triangles as plain
// bisection, fewer evaluations than 6 plain steps, and on a curved field (the log of the distance,
// like log|q_n|) every vertex at least as close to the 10-step plain bisection's as 6 plain steps'
// vertices are (these are within h/64 + h/1024 of it); with 0 bisection steps too (Illinois).
// Tile size does not change the vertices (seam edges get the same brackets from both tiles).
TEST(MarchingCubes, FalsePositionStepsAreAsCloseWithFewerEvaluations) {
  const Vec3 c{0.02, -0.01, 0.03};
  const BatchField field = Lambda([c](const Vec3& p) { return std::log(Norm({p[0] - c[0], p[1] - c[1], p[2] - c[2]}) / 0.8); });
  MeshingOptions o;
  o.resolution = 32;
  o.bisection_steps = 10;
  MeshingSummary s10;
  const TriangleMesh reference = MeshField(field, o, &s10);
  auto worst = [&](const TriangleMesh& m) {
    EXPECT_EQ(m.triangles, reference.triangles);
    double w = 0;
    for (std::size_t v = 0; v < m.vertices.size(); ++v) {
      const Vec3 &a = m.vertices[v], &b = reference.vertices[v];
      w = std::max(w, Norm({a[0] - b[0], a[1] - b[1], a[2] - b[2]}));
    }
    return w / s10.spacing;  // cells
  };
  o.bisection_steps = 6;
  MeshingSummary s6;
  const double plain = worst(MeshField(field, o, &s6));
  EXPECT_LE(plain, 1.0 / 64 + 1.0 / 1024 + 1e-9);  // the last midpoint: within h / 2^steps of the root
  for (const auto& [bisection, secant] : std::vector<std::pair<int, int>>{{3, 1}, {2, 2}, {0, 3}}) {
    SCOPED_TRACE(std::to_string(bisection) + " + " + std::to_string(secant));
    o.bisection_steps = bisection;
    o.secant_steps = secant;
    MeshingSummary s;
    const TriangleMesh m = MeshField(field, o, &s);
    EXPECT_LT(s.bisection_evaluations, s6.bisection_evaluations);
    EXPECT_LE(worst(m), plain);
    o.tile_cells = 8;
    EXPECT_EQ(MeshField(field, o).vertices, m.vertices);
    o.tile_cells = MeshingOptions{}.tile_cells;
  }
  o.secant_steps = 9;
  EXPECT_THROW(MeshField(field, o), Error);
  o.secant_steps = -1;
  EXPECT_THROW(MeshField(field, o), Error);
}

TEST(MarchingCubes, GyroidIsClosedAndManifold) {
  MeshingOptions o;
  o.resolution = 64;
  o.tile_cells = 16;
  const TriangleMesh m = MeshField(Gyroid(), o);
  const MeshTopology t = AnalyzeTopology(m);
  EXPECT_EQ(t.boundary_edges, 0);
  EXPECT_EQ(t.non_manifold_edges, 0);
  EXPECT_EQ(t.misoriented_edges, 0);
  EXPECT_GT(t.signed_volume, 0);
  EXPECT_EQ(Euler(m, t) % 2, 0);
}

// A sphere with one inside node and one outside node far from it (a speck and a bubble smaller
// than a cell): the mesher drops both one-node components unless asked to keep them, and keeps a
// two-node speck.
TEST(MarchingCubes, OneNodeSpecksAreRemovedUnlessKept) {
  MeshingOptions o;  // box [-2, 2]^3, 32 cells: nodes at multiples of 0.125
  o.resolution = 32;
  o.tile_cells = 16;
  o.sparse = false;
  auto at = [](const Vec3& p, double x, double y, double z) {
    return std::abs(p[0] - x) < 1e-9 && std::abs(p[1] - y) < 1e-9 && std::abs(p[2] - z) < 1e-9;
  };
  const BatchField field = Lambda([&](const Vec3& p) {
    if (at(p, 1.5, 1.5, 1.5)) return -1.0;                          // a one-node speck outside the ball
    if (at(p, 0.0, 0.0, 0.0)) return 1.0;                           // a one-node bubble inside it
    if (at(p, -1.5, -1.5, 1.5) || at(p, -1.375, -1.5, 1.5)) return -1.0;  // a two-node speck
    return Norm(p) - 1.0;
  });
  MeshingSummary removed, kept;
  const TriangleMesh clean = MeshField(field, o, &removed);
  o.remove_specks = false;
  const TriangleMesh all = MeshField(field, o, &kept);
  EXPECT_EQ(removed.specks_removed, 2);
  EXPECT_EQ(kept.specks_removed, 0);
  EXPECT_EQ(all.vertices.size() - clean.vertices.size(), 12u);
  EXPECT_EQ(all.triangles.size() - clean.triangles.size(), 16u);
  for (const Vec3& v : clean.vertices) EXPECT_GT(Norm(v), 0.5) << "the bubble is gone";
  bool two_node = false;
  for (const Vec3& v : clean.vertices) two_node |= v[0] < -1.2 && v[1] < -1.2 && v[2] > 1.2;
  EXPECT_TRUE(two_node) << "a speck of two nodes is not a one-node speck";
  const MeshTopology t = AnalyzeTopology(clean);
  EXPECT_EQ(t.boundary_edges, 0);
  EXPECT_EQ(t.non_manifold_edges, 0);
}

TEST(MarchingCubes, DenseAndSparseAgree) {
  MeshingOptions o;
  o.resolution = 64;
  o.tile_cells = 16;
  o.search_min_cells = 8;  // a sparse search at this small resolution
  MeshingSummary ss, sd;
  const TriangleMesh sparse = MeshField(Gyroid(), o, &ss);
  o.sparse = false;
  const TriangleMesh dense = MeshField(Gyroid(), o, &sd);
  EXPECT_EQ(ss.search_stride, 8);
  EXPECT_EQ(sd.search_stride, 0);
  EXPECT_LT(ss.nodes_evaluated, sd.nodes_evaluated);
  EXPECT_LT(ss.tiles_meshed, ss.tiles_total + 1);
  EXPECT_EQ(sparse.vertices, dense.vertices);  // sorted by edge id in both
  EXPECT_EQ(Canonical(sparse), Canonical(dense));
}

TEST(MarchingCubes, TileSizeAndThreadsDoNotChangeTheMesh) {
  MeshingOptions o;
  o.resolution = 50;  // not a multiple of the tiles: partial tiles at the far side
  o.min_corner = {-1.9, -1.7, -1.8};
  o.max_corner = {1.8, 1.9, 1.7};
  o.tile_cells = 8;
  o.search_min_cells = 4;
  const TriangleMesh small = MeshField(Gyroid(), o);
  o.tile_cells = 32;
  const TriangleMesh large = MeshField(Gyroid(), o);
  EXPECT_EQ(small.vertices, large.vertices);
  EXPECT_EQ(Canonical(small), Canonical(large));
  std::set<Vec3> unique(small.vertices.begin(), small.vertices.end());
  EXPECT_EQ(unique.size(), small.vertices.size());

  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  const TriangleMesh one = MeshField(Gyroid(), o);
  omp_set_num_threads(3);
  const TriangleMesh three = MeshField(Gyroid(), o);
  omp_set_num_threads(threads);
  EXPECT_EQ(one.vertices, large.vertices);
  EXPECT_EQ(one.triangles, large.triangles);
  EXPECT_EQ(three.vertices, large.vertices);
  EXPECT_EQ(three.triangles, large.triangles);
}

TEST(MarchingCubes, NonFiniteValuesCountAsOutside) {
  MeshingOptions o;
  o.resolution = 32;
  MeshingSummary s;
  // NaN beyond x > 1: a ball of radius 1.5 cut there (open where the field is NaN).
  const TriangleMesh m = MeshField(Lambda([](const Vec3& p) {
                                     return p[0] > 1.0 ? std::nan("") : Norm(p) - 1.5;
                                   }),
                                   o, &s);
  EXPECT_GT(s.non_finite_values, 0);
  EXPECT_GT(m.triangles.size(), 100u);
  for (const Vec3& v : m.vertices)
    for (double c : v) EXPECT_TRUE(std::isfinite(c));
  const MeshTopology t = AnalyzeTopology(m);
  EXPECT_EQ(t.boundary_edges, 0);  // NaN is outside: the cap closes the ball
  EXPECT_EQ(t.misoriented_edges, 0);
}

TEST(MarchingCubes, PlyRoundTrip) {
  TempDir dir;
  MeshingOptions o;
  o.resolution = 24;
  const TriangleMesh m = MeshField(Sphere(1.0), o);
  WritePly(dir.file("s.ply"), m);  // float32: what viewers (and assimp) read
  const TriangleMesh back = ReadMesh(dir.file("s.ply"));
  EXPECT_EQ(back.triangles.size(), m.triangles.size());
  EXPECT_EQ(back.vertices.size(), m.vertices.size());
  const MeshTopology t = AnalyzeTopology(back);
  EXPECT_TRUE(t.closed());
  EXPECT_GT(t.signed_volume, 0);
}

TEST(MarchingCubes, BandHoldsTheSurfaceNodes) {
  MeshingOptions o;
  o.resolution = 32;
  FieldBand band;
  MeshField(Sphere(1.0), o, nullptr, &band);
  ASSERT_FALSE(band.nodes.empty());
  ASSERT_EQ(band.nodes.size(), band.values.size());
  for (std::size_t i = 0; i < band.values.size(); ++i) EXPECT_LT(std::abs(band.values[i]), 2 * band.lattice.spacing);
  // Through OpenVDB and back: voxel (i, j, k) is node (i, j, k).
  TempDir dir;
  WriteVdbSparse(dir.file("b.vdb"), band.lattice.origin, band.lattice.spacing, band.nodes, band.values, 1e30f, 0.0,
                 "julia", "test", "fractal");
  const ScalarGrid back = ReadVdb(dir.file("b.vdb"));
  EXPECT_NEAR(back.frame.spacing, band.lattice.spacing, 1e-12);
  const Vec3 node = band.lattice.node(band.nodes[0][0], band.nodes[0][1], band.nodes[0][2]);
  EXPECT_NEAR(back.sample(node), band.values[0], 1e-6);
}

TEST(MarchingCubes, InvalidOptionsThrow) {
  MeshingOptions o;
  o.resolution = 1;
  EXPECT_THROW(MeshField(Sphere(1), o), Error);
  o = {};
  o.tile_cells = 31;
  EXPECT_THROW(MeshField(Sphere(1), o), Error);
  o = {};
  o.max_corner[1] = o.min_corner[1];
  EXPECT_THROW(MeshField(Sphere(1), o), Error);
  o = {};
  BatchField none;
  EXPECT_THROW(MeshField(none, o), Error);
}

}  // namespace
}  // namespace quijibo::mesh
