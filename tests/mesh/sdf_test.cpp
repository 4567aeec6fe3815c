// The signed distance field: accuracy, sign policy for imperfect meshes, VDB export, command.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <random>

#include "mesh/normalize.h"
#include "mesh/sdf.h"
#include "mesh/sdf_command.h"
#include "mesh/vdb.h"
#include "mesh_fixtures.h"
#include "thrown_message.h"
#include "util/error.h"
#include "quijibo/frame.h"
#include "util/io.h"

namespace quijibo::mesh {
namespace {

using testing::Icosphere;
using testing::TempDir;
using testing::ThrownMessage;

double Length(const Vec3& p) { return std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]); }

// Sphere of radius 1.5 (the normalized fractal-frame size) on the 40^3 target grid.
struct SphereCase {
  double radius = 1.5;
  FractalFrame frame;
  GridFrame grid = TargetGridFrame(40, frame);
};

TEST(SdfSphere, WithinHalfACellOfTheAnalyticDistance) {
  SphereCase c;
  const TriangleMesh sphere = Icosphere(4, {0, 0, 0}, c.radius);  // 5120 faces
  SdfSummary summary;
  const ScalarGrid sdf = SignedDistance(sphere, c.grid, {}, &summary);
  double worst = 0.0;
  for (int k = 0; k < 40; ++k)
    for (int j = 0; j < 40; ++j)
      for (int i = 0; i < 40; ++i) {
        const double exact = Length(c.grid.cell_center(i, j, k)) - c.radius;
        worst = std::max(worst, std::abs(sdf.at(i, j, k) - exact));
      }
  RecordProperty("max_error_cells", std::to_string(worst / c.grid.spacing));
  std::printf("sphere 40^3: max |sdf - analytic| = %.4g cells\n", worst / c.grid.spacing);
  EXPECT_LE(worst, 0.5 * c.grid.spacing);
  // Faceting of a level-4 icosphere (sagitta ~0.0017 at radius 1.5) is what remains.
  EXPECT_LE(worst, 0.03 * c.grid.spacing);
  EXPECT_FALSE(summary.flipped_orientation);
  EXPECT_EQ(summary.ambiguous_cells, 0);
  EXPECT_EQ(sdf.frame, c.grid);
}

TEST(SdfSphere, SamplesAtCellCentresOfAnOffCentreGrid) {
  // A non-cubic grid whose corner is not a multiple of the spacing.
  GridFrame grid;
  grid.dims = {17, 9, 12};
  grid.spacing = 0.137;
  grid.min_corner = {-1.31, -0.77, -0.9};
  const Vec3 centre{0.05, -0.1, 0.02};
  const TriangleMesh sphere = Icosphere(5, centre, 0.6);
  const ScalarGrid sdf = SignedDistance(sphere, grid);
  for (int k = 0; k < 12; ++k)
    for (int j = 0; j < 9; ++j)
      for (int i = 0; i < 17; ++i) {
        Vec3 p = grid.cell_center(i, j, k);
        for (int a = 0; a < 3; ++a) p[a] -= centre[a];
        EXPECT_NEAR(sdf.at(i, j, k), Length(p) - 0.6, 2e-3);
      }
}

TEST(SdfSign, InwardFacingMeshIsFlipped) {
  SphereCase c;
  TriangleMesh sphere = Icosphere(3, {0, 0, 0}, c.radius);
  const ScalarGrid a = SignedDistance(sphere, c.grid);
  FlipOrientation(sphere);
  SdfSummary summary;
  const ScalarGrid b = SignedDistance(sphere, c.grid, {}, &summary);
  EXPECT_TRUE(summary.flipped_orientation);
  EXPECT_EQ(a.values, b.values);
}

TEST(SdfSign, SphereWithAHoleKeepsTheRightSign) {
  SphereCase c;
  TriangleMesh sphere = Icosphere(2, {0, 0, 0}, c.radius);  // 320 faces, big ones
  sphere.triangles.erase(sphere.triangles.begin() + 17);
  SdfSummary summary;
  const ScalarGrid sdf = SignedDistance(sphere, c.grid, {}, &summary);
  EXPECT_EQ(summary.topology.boundary_edges, 3);
  std::int64_t wrong = 0;
  for (int k = 0; k < 40; ++k)
    for (int j = 0; j < 40; ++j)
      for (int i = 0; i < 40; ++i) {
        const double r = Length(c.grid.cell_center(i, j, k));
        // Away from the faceted surface (deviation < 0.02 * r) the sign is unambiguous.
        if (std::abs(r - c.radius) > 0.05) wrong += (sdf.at(i, j, k) < 0) != (r < c.radius);
      }
  EXPECT_EQ(wrong, 0);
  EXPECT_GT(summary.inside_cells, 10000);

  SdfOptions strict;
  strict.allow_open = false;
  EXPECT_THROW(SignedDistance(sphere, c.grid, strict), Error);
}

TEST(SdfSign, SelfIntersectingUnionIsInsideInTheOverlap) {
  TriangleMesh a = Icosphere(3, {-0.4, 0, 0}, 0.8);
  const TriangleMesh b = Icosphere(3, {0.4, 0, 0}, 0.8);
  const int offset = int(a.vertices.size());
  a.vertices.insert(a.vertices.end(), b.vertices.begin(), b.vertices.end());
  for (auto t : b.triangles) a.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
  const GridFrame grid = GridFrame::Cube(41, {0, 0, 0}, 3.0);
  const ScalarGrid sdf = SignedDistance(a, grid);
  EXPECT_LT(sdf.at(20, 20, 20), -0.3);  // centre: inside both spheres
  for (int k = 0; k < 41; ++k)
    for (int j = 0; j < 41; ++j)
      for (int i = 0; i < 41; ++i) {
        const Vec3 p = grid.cell_center(i, j, k);
        const double d = std::min(Length({p[0] + 0.4, p[1], p[2]}), Length({p[0] - 0.4, p[1], p[2]}));
        if (std::abs(d - 0.8) > 0.02) {
          EXPECT_EQ(sdf.at(i, j, k) < 0, d < 0.8) << i << " " << j << " " << k;
        }
      }
}

TEST(SdfSign, RefusesWhatItCannotSign) {
  SphereCase c;
  TriangleMesh sphere = Icosphere(2, {0, 0, 0}, c.radius);
  // Inconsistent orientation: a band of faces flipped.
  TriangleMesh mixed = sphere;
  for (size_t t = 0; t < mixed.triangles.size(); t += 3) std::swap(mixed.triangles[t][1], mixed.triangles[t][2]);
  const std::string flipped = ThrownMessage([&] { SignedDistance(mixed, c.grid, SdfOptions{.name = "mixed.obj"}); });
  EXPECT_NE(flipped.find("mixed.obj: "), std::string::npos) << flipped;
  EXPECT_NE(flipped.find("opposite orientation"), std::string::npos) << flipped;
  // An open surface that bounds nothing: a hemisphere.
  TriangleMesh half = sphere;
  std::erase_if(half.triangles, [&](const auto& t) {
    return half.vertices[t[0]][2] + half.vertices[t[1]][2] + half.vertices[t[2]][2] < 0;
  });
  EXPECT_THROW(SignedDistance(half, c.grid), Error);
  // A single triangle.
  TriangleMesh tri;
  tri.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  tri.triangles = {{0, 1, 2}};
  EXPECT_THROW(SignedDistance(tri, c.grid), Error);
}

TEST(SdfWinding, HierarchicalMatchesExact) {
  const TriangleMesh bunny = ReadMesh(QUIJIBO_SOURCE_DIR "/data/bunny.obj");
  const FractalFrame frame = NormalizationFor(bunny);
  const TriangleMesh mesh = ToFractalFrame(bunny, frame);
  // Compare the full field's sign with exact winding numbers on a coarse grid.
  const GridFrame grid = TargetGridFrame(24, frame);
  const ScalarGrid sdf = SignedDistance(mesh, grid);
  std::vector<Vec3> points;
  for (std::int64_t c = 0; c < grid.cell_count(); ++c) points.push_back(grid.cell_center(c));
  const std::vector<double> w = WindingNumbersExact(mesh, points);
  for (std::int64_t c = 0; c < grid.cell_count(); ++c) {
    EXPECT_LT(std::min(std::abs(w[c]), std::abs(w[c] - 1)), 1e-6) << c;  // closed mesh
    EXPECT_EQ(sdf.values[c] < 0, w[c] > 0.5) << c;
  }
}

double TimeSdf(const std::string& file, int n, SdfSummary* summary) {
  const TriangleMesh user = ReadMesh(file);
  const FractalFrame frame = NormalizationFor(user);
  const TriangleMesh mesh = ToFractalFrame(user, frame);
  const auto t0 = std::chrono::steady_clock::now();
  SignedDistance(mesh, TargetGridFrame(n, frame), {}, summary);
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

TEST(SdfShippedMeshes, BunnyAndToothAreClosedAndConsistentlySigned) {
  for (const char* name : {"bunny", "tooth"}) {
    SdfSummary s;
    const double seconds = TimeSdf(std::string(QUIJIBO_SOURCE_DIR "/data/") + name + ".obj", 97, &s);
    std::printf("%s 97^3: %.2f s, %lld inside, %lld winding evaluations, closed %d\n", name,
                seconds, (long long)s.inside_cells, (long long)s.winding_evaluations,
                int(s.topology.closed()));
    RecordProperty(std::string(name) + "_seconds", std::to_string(seconds));
    EXPECT_TRUE(s.topology.closed());
    EXPECT_EQ(s.topology.misoriented_edges, 0);
    EXPECT_FALSE(s.flipped_orientation);
    EXPECT_EQ(s.ambiguous_cells, 0);
  }
}

TEST(SdfVdb, RoundTripKeepsCellCentres) {
  TempDir dir;
  GridFrame grid;
  grid.dims = {5, 4, 3};
  grid.spacing = 0.25;
  grid.min_corner = {-0.6, 0.1, 2.0};
  ScalarGrid g;
  g.frame = grid;
  for (std::int64_t c = 0; c < grid.cell_count(); ++c) g.values.push_back(0.5 * double(c) - 7.0);
  WriteVdb(dir.file("g.vdb"), g, "sdf");
  EXPECT_EQ(dir.count(), 1u);
  const ScalarGrid back = ReadVdb(dir.file("g.vdb"), "sdf");
  EXPECT_EQ(back.frame.dims, grid.dims);
  EXPECT_NEAR(back.frame.spacing, grid.spacing, 1e-15);
  for (int a = 0; a < 3; ++a) EXPECT_NEAR(back.frame.min_corner[a], grid.min_corner[a], 1e-12);
  EXPECT_EQ(back.values, g.values);  // exactly representable in float
  EXPECT_EQ(back.quantity, "signed-distance");
  EXPECT_THROW(ReadVdb(dir.file("g.vdb"), "other"), Error);
  EXPECT_THROW(ReadVdb(dir.write("bad.vdb", "not a vdb")), Error);
}

TEST(SdfCommand, WritesFieldFrameAndVdb) {
  TempDir dir;
  SdfCommandOptions o;
  o.input = QUIJIBO_SOURCE_DIR "/data/bunny.obj";
  o.output = dir.file("bunny.qgrid");
  o.vdb_output = dir.file("bunny.vdb");
  o.target.resolution = 25;
  o.quiet = true;
  RunSdfCommand(o);
  EXPECT_EQ(dir.count(), 3u);
  const FractalFrame frame = ReadFrameJson(dir.file("bunny.frame.json"));
  EXPECT_EQ(FrameJsonPathFor(o.output), dir.file("bunny.frame.json"));
  // The frame file is read strictly, with suggestions for misspelt keys.
  nlohmann::json edited = nlohmann::json::parse(ReadFile(dir.file("bunny.frame.json")));
  edited["fractal_raduis"] = edited["fractal_radius"];
  edited.erase("fractal_radius");
  const std::string bad = dir.write("bad.frame.json", edited.dump());
  try {
    ReadFrameJson(bad);
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()), bad + ": /fractal_raduis: unknown key (did you mean \"fractal_radius\"?)");
  }
  const FractalFrame expected = NormalizationFor(ReadMesh(o.input));
  EXPECT_EQ(frame.scale, expected.scale);
  EXPECT_EQ(frame.translation, expected.translation);
  const ScalarGrid field = ReadGrid(o.output);
  EXPECT_EQ(field.frame, TargetGridFrame(25, frame, TargetBox::kUnitCube));
  const ScalarGrid vdb = ReadVdb(o.vdb_output);
  EXPECT_EQ(vdb.frame.dims, field.frame.dims);
  for (int a = 0; a < 3; ++a) EXPECT_NEAR(vdb.frame.min_corner[a], field.frame.min_corner[a], 1e-9);
  for (size_t c = 0; c < field.values.size(); ++c)
    EXPECT_NEAR(vdb.values[c], field.values[c], 1e-6);
}

TEST(SdfCommand, FailureLeavesNoOutput) {
  TempDir dir;
  SdfCommandOptions o;
  o.output = dir.file("out.qgrid");
  o.vdb_output = dir.file("out.vdb");
  o.target.resolution = 20;
  o.quiet = true;
  // Unreadable input, a mesh that bounds nothing, and an output folder that cannot be created.
  o.input = dir.write("in.xyz", "v 0 0 0\n");
  EXPECT_THROW(RunSdfCommand(o), Error);
  o.input = dir.write("open.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0.2\nf 1 2 3\nf 2 4 3\n");
  EXPECT_THROW(RunSdfCommand(o), Error);
  EXPECT_EQ(dir.count(), 2u);  // just the two inputs
  o.input = QUIJIBO_SOURCE_DIR "/data/bunny.obj";
  o.vdb_output = dir.file("in.xyz/out.vdb");
  EXPECT_THROW(RunSdfCommand(o), Error);
  EXPECT_EQ(dir.count(), 2u);
  // Output names the formats written do not match.
  auto message = [&] {
    try {
      RunSdfCommand(o);
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  o.vdb_output.clear();
  o.output = dir.file("new/a.stl");
  EXPECT_EQ(message(), "sdf: " + o.output + ": the output must end in .qgrid (the grid format written)");
  o.output = dir.file("new/a.qgrid");
  o.vdb_output = dir.file("new/a.ply");
  EXPECT_EQ(message(), "sdf: " + o.vdb_output + ": --vdb must end in .vdb");
  EXPECT_EQ(dir.count(), 2u);
  o.target.resolution = 1;
  o.vdb_output.clear();
  EXPECT_THROW(RunSdfCommand(o), Error);
}

}  // namespace
}  // namespace quijibo::mesh
