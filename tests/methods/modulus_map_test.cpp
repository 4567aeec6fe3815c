// Map kind "modulus" (methods/maps/modulus.cpp): the shape modulus as a map object, read inline or
// from what the modulus stage writes (its report's "map"), draws the stage's own set.
#include <gtest/gtest.h>

#include <cmath>

#include "experiments/pipeline/julia_set.h"
#include "experiments/pipeline/modulus.h"
#include "methods/map_kind.h"
#include "methods/modulus_target.h"
#include "tests/mesh/mesh_fixtures.h"
#include "tests/methods/modulus_fixtures.h"
#include "tests/thrown_message.h"
#include "util/io.h"

namespace quijibo {
namespace {

using nlohmann::json;

KindMap ReadModulusDoc(const json& doc, const std::string& dir = "") { return ReadKindMap(JsonReader(doc, "test"), "", dir); }

// Every sample of a lattice over `box` (3D: 9^3; 2D: 33^2 in the plane k = j = 0), iterated by both
// maps: identical doubles (the same arithmetic, not merely close).
void ExpectSameModulusField(const QuaternionMap& a, const QuaternionMap& b, const std::vector<double>& box,
                     const IterationOptions& it) {
  const bool two_d = box.size() == 4;
  const int n = two_d ? 33 : 9, dims = two_d ? 2 : 3;
  int inside = 0, total = 0;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < (two_d ? 1 : n); ++k) {
        double x[3] = {0, 0, 0};
        const int idx[3] = {i, j, k};
        for (int d = 0; d < dims; ++d) x[d] = box[d] + (box[dims + d] - box[d]) * (idx[d] + 0.5) / n;
        const Quat q{x[0], x[1], x[2], 0};
        const double fa = IterateField(a, q, it), fb = IterateField(b, q, it);
        ASSERT_EQ(fa, fb) << x[0] << " " << x[1] << " " << x[2];
        inside += fa < 0;
        ++total;
      }
  // A set neither empty nor the whole box: the comparison saw both sides of the surface.
  EXPECT_GT(inside, 0);
  EXPECT_LT(inside, total);
}

TEST(ModulusMap, InlineObjectIsTheShapeModulusMapBuiltDirectly) {
  const KindMap km = ReadModulusDoc({{"kind", "modulus"},
                           {"target", "sphere"},
                           {"alpha", 30.0},
                           {"beta", -0.02},
                           {"origin_offset", {0.05, 0.0, -0.03}},
                           {"versor", {{"generate", {{"roots", 6}, {"seed", 7}}}}}});
  ASSERT_EQ(km.kind->name, "modulus");
  // The modulus stage's defaults: 3 iterations, escape radius 20, inside |q_n| < 1.
  EXPECT_EQ(km.iteration->iterations, 3);
  EXPECT_EQ(km.iteration->escape_radius, 20.0);
  EXPECT_FALSE(km.iteration->bounded);

  const ModulusTarget target = AnalyticModulusTarget("sphere");
  VersorGeneratorOptions g;
  g.roots = 6;
  g.seed = 7;
  g.box_min = target.box_min;
  g.box_max = target.box_max;
  Versor v;
  v.polynomial = GenerateVersorPolynomial(g);
  ShapeModulusOptions so;
  so.alpha = 30.0;
  so.beta = -0.02;
  so.origin_offset = {0.05, 0.0, -0.03};
  const ShapeModulusMap direct(target, v, so);
  // The region: the target's box grown by 15 % of its longest side (the stage's).
  const std::vector<double> box = km.Region(false);
  ASSERT_EQ(box.size(), 6u);
  for (int a = 0; a < 3; ++a) {
    const double longest = target.box_max[0] - target.box_min[0];
    EXPECT_DOUBLE_EQ(box[a], target.box_min[a] - 0.15 * longest);
    EXPECT_DOUBLE_EQ(box[3 + a], target.box_max[a] + 0.15 * longest);
  }
  ExpectSameModulusField(*km.map, direct, box, *km.iteration);
  // exclude_base's signed function: phi + beta at the offset point.
  const Quat q{0.1, 0.2, -0.1, 0};
  EXPECT_EQ(km.base_set(q), target.phi({0.1 - 0.05, 0.2, -0.1 + 0.03}) - 0.02);
}

// The stage's own map against the kind reading what the stage wrote (the report through a file,
// as `quijibo julia modulus.json` reads it): a mesh target, a --params field, an offset, 3D.
TEST(ModulusMap, ReadsTheModulusStagesReportAsTheStagesOwnMap) {
  const testing::TempDir dir;
  const std::string obj = dir.file("sphere.obj");
  mesh::WriteObj(obj, testing::Icosphere(2, {1.0, 2.0, 3.0}, 2.0));
  const std::string params = dir.write(
      "params.json",
      json{{"beta", {{"value", -0.02}, {"regions", {{{"mask", {{"type", "halfspace"}, {"normal", {1, 0, 0}}, {"offset", 0.0}}},
                                                   {"value", 0.01}, {"feather", 0.1}}}}}}}
          .dump());
  pipeline::ModulusStageOptions o;
  o.sdf_resolution = 16;
  o.shape.alpha = 25.0;
  o.offset = std::vector<double>{0.02, -0.01, 0.0};
  o.params = params;
  o.versor.generate.seed = 3;
  o.output.meshing.resolution = 20;
  const pipeline::ModulusStageResult r = pipeline::Modulus(obj, o, dir.file("julia.ply"));
  ASSERT_TRUE(r.report.contains("map"));
  const std::string report = dir.write("modulus.json", r.report.dump(1) + "\n");  // as the run writes it

  const KindMap km = ReadModulusDoc({{"kind", "modulus"}, {"file", "modulus.json"}}, dir.file(""));
  ExpectSameModulusField(*km.map, *r.map, km.Region(false), *km.iteration);

  // `quijibo julia modulus.json -o julia.ply`: the stage's mesh, vertex for vertex.
  pipeline::JuliaSetStageOptions j;
  j.map_file = report;
  j.output.format = "ply";
  j.output.meshing.resolution = 20;
  const pipeline::JuliaSetStageResult jr = pipeline::JuliaSet(j);
  EXPECT_EQ(jr.report.at("kind"), "modulus");
  EXPECT_EQ(jr.product.report.at("box"), r.product.report.at("box"));
  ASSERT_GT(r.product.mesh.triangles.size(), 0u);
  EXPECT_EQ(jr.product.mesh.vertices, r.product.mesh.vertices);
  EXPECT_EQ(jr.product.mesh.triangles, r.product.mesh.triangles);
}

// 2D: the stage's picture of a 3D target is the complex plane's map (the versor's roots kept to
// the plane); its report's map says so ("dimension": 2) and draws the same pixels.
TEST(ModulusMap, TwoDimensionalStagePictureIsDrawnAlike) {
  const testing::TempDir dir;
  pipeline::ModulusStageOptions o;
  o.shape.alpha = 40.0;
  o.output.view.width = 48;
  const pipeline::ModulusStageResult r = pipeline::Modulus("sphere", o, dir.file("julia.png"));
  EXPECT_EQ(r.report.at("map").at("dimension"), 2);
  const KindMap km = ReadModulusDoc(json::parse(r.report.dump()).at("map"));
  ExpectSameModulusField(*km.map, *r.map, km.Region(true), *km.iteration);
  pipeline::JuliaSetStageOptions j;
  j.map_inline = r.report.at("map");
  j.output.view.width = 48;
  const pipeline::JuliaSetStageResult jr = pipeline::JuliaSet(j);
  EXPECT_EQ(jr.product.report.at("view"), r.product.report.at("view"));
  ASSERT_EQ(jr.product.image.pixels.size(), r.product.image.pixels.size());
  int differ = 0;
  for (std::size_t i = 0; i < r.product.image.pixels.size(); ++i) {
    const Rgb &a = jr.product.image.pixels[i], &b = r.product.image.pixels[i];
    differ += a.r != b.r || a.g != b.g || a.b != b.b;
  }
  EXPECT_EQ(differ, 0);
}

TEST(ModulusMap, BadKeysNameTheirJsonPointer) {
  auto message = [](const json& doc) { return testing::ThrownMessage([&] { ReadModulusDoc(doc); }); };
  EXPECT_NE(message({{"kind", "modulus"}, {"target", "sphere"}, {"alpah", 3}}).find("alpah"), std::string::npos);
  EXPECT_NE(message({{"kind", "modulus"}, {"target", "sphere"}, {"dimension", 4}}).find("/dimension: expected 2"),
            std::string::npos);
  EXPECT_NE(message({{"kind", "modulus"}, {"target", "sphere"}, {"versor", {{"generate", {{"roots", 0}}}}}})
                .find("/versor/generate"),
            std::string::npos);
  EXPECT_NE(message({{"kind", "modulus"}, {"target", "sphere"}, {"alpha", "thin"}}).find("/alpha"), std::string::npos);
  EXPECT_NE(message({{"kind", "modulus"}, {"file", "m.json"}, {"alpha", 3}}).find("/alpha: expected no other key"),
            std::string::npos);
  EXPECT_NE(message({{"kind", "modulus"}, {"target", "sphere"}, {"sdf_resolution", 4}}).find("/sdf_resolution"),
            std::string::npos);
  EXPECT_NE(message({{"kind", "modulus"}}).find("/target"), std::string::npos);
  // A file holding a map names the map, not a file again (which could be itself).
  const testing::TempDir dir;
  dir.write("self.json", json{{"kind", "modulus"}, {"file", "self.json"}}.dump());
  const std::string self =
      testing::ThrownMessage([&] { ReadModulusDoc({{"kind", "modulus"}, {"file", "self.json"}}, dir.file("")); });
  EXPECT_NE(self.find("self.json: /file: expected the map itself"), std::string::npos) << self;
  dir.write("poly.json", json{{"kind", "polynomial"}, {"c", {0.0, 0.0}}}.dump());
  EXPECT_NE(testing::ThrownMessage([&] { ReadModulusDoc({{"kind", "modulus"}, {"file", "poly.json"}}, dir.file("")); })
                .find("expected a shape modulus map"),
            std::string::npos);
}

}  // namespace
}  // namespace quijibo
