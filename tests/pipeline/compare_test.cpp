// The compare stage returns its figures and writes nothing; `quijibo compare` (the face) writes
// them, the same figures, and they are the ones `compare` wrote when the stage wrote its own files.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <nlohmann/json.hpp>

#include "experiments/pipeline/compare.h"
#include "util/io.h"
#include "quijibo/iou.h"
#include "quijibo_command.h"

namespace quijibo::pipeline {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using testing::RunQuijibo;

// A sphere target (20^3) and a seeded random map, made by the command line, and the options of
// `quijibo compare --alpha 300 --beta 0 -r 16 --samples 2000 --png-size 32` on them.
struct CompareCase {
  fs::path dir;
  CompareOptions options;
  std::string flags;
};

CompareCase MakeCase(const std::string& name) {
  CompareCase c;
  c.dir = fs::temp_directory_path() / (name + "_" + std::to_string(::getpid()));
  fs::remove_all(c.dir);
  fs::create_directories(c.dir);
  const std::string target = (c.dir / "s.qgrid").string(), map = (c.dir / "map.json").string();
  EXPECT_EQ(RunQuijibo("target sphere -r 20 -o " + target).code, 0);
  EXPECT_EQ(RunQuijibo("map random --top 4 --bottom 2 -o " + map).code, 0);
  c.options.target = target;
  c.options.map = map;
  c.options.modulus.shape.alpha = 300;
  c.options.modulus.shape.beta = 0;
  c.options.resolution = 16;
  c.options.samples = 2000;
  c.options.png_size = 32;
  c.flags = "--target " + target + " --map " + map + " --alpha 300 --beta 0 -r 16 --samples 2000 --png-size 32";
  return c;
}

// What `quijibo compare` wrote for this case when the stage wrote its own files.
constexpr std::size_t kQuijiboTriangles = 204, kModulusTriangles = 824;
constexpr double kQuijiboPsi1 = -0.07341659569071692, kQuijiboPsiN = -0.012882118269193523,
                 kQuijiboIou = 0.02612330198537095, kQuijiboChamfer = 1.0718928117399722;
constexpr double kModulusPsi1 = -0.9901127627550621, kModulusPsiN = -0.9995405182481639,
                 kModulusIou = 0.9989047097480832, kModulusChamfer = 0.08232603010073722;

// The report without the clocks.
json WithoutTimes(json report) {
  for (json& m : report["methods"]) m.erase("mesh_seconds"), m.erase("mesh_cpu_seconds"), m.erase("fit_seconds");
  return report;
}

TEST(Compare, ReturnsTheFiguresTheCommandWrites) {
  const CompareCase c = MakeCase("quijibo_compare_stage");
  const auto files = [&] { return std::distance(fs::recursive_directory_iterator(c.dir), {}); };
  const auto before = files();
  const CompareResult r = Compare(c.options);
  EXPECT_EQ(files(), before) << "Compare wrote files";
  ASSERT_EQ(r.report["methods"].size(), 2u);
  EXPECT_EQ(r.report["methods"][0]["triangles"].get<std::size_t>(), r.quijibo.mesh.triangles.size());
  EXPECT_EQ(r.report["methods"][1]["triangles"].get<std::size_t>(), r.modulus.mesh.triangles.size());
  EXPECT_EQ(r.quijibo.picture.width, 32);

  // The command line writes what the stage returns.
  const std::string out = (c.dir / "out").string();
  const auto cmd = RunQuijibo("compare " + c.flags + " -o " + out);
  ASSERT_EQ(cmd.code, 0) << cmd.out;
  const json written = json::parse(ReadFile(out + "/compare.json"));
  EXPECT_EQ(WithoutTimes(written), WithoutTimes(r.report));
  for (const char* f : {"compare.md", "quijibo.png", "modulus.png", "quijibo.ply", "modulus.ply"})
    EXPECT_TRUE(fs::exists(out + "/" + f)) << f;

  // The figures `quijibo compare` wrote before the stage returned values (same inputs and options).
  const json& q = r.report["methods"][0];
  const json& s = r.report["methods"][1];
  EXPECT_EQ(q["triangles"].get<std::size_t>(), kQuijiboTriangles);
  EXPECT_EQ(s["triangles"].get<std::size_t>(), kModulusTriangles);
  EXPECT_DOUBLE_EQ(q["psi_one_application"].get<double>(), kQuijiboPsi1);
  EXPECT_DOUBLE_EQ(q["psi_iterated"].get<double>(), kQuijiboPsiN);
  EXPECT_DOUBLE_EQ(q["iou"].get<double>(), kQuijiboIou);
  EXPECT_DOUBLE_EQ(q["chamfer"]["chamfer"].get<double>(), kQuijiboChamfer);
  EXPECT_DOUBLE_EQ(s["psi_one_application"].get<double>(), kModulusPsi1);
  EXPECT_DOUBLE_EQ(s["psi_iterated"].get<double>(), kModulusPsiN);
  EXPECT_DOUBLE_EQ(s["iou"].get<double>(), kModulusIou);
  EXPECT_DOUBLE_EQ(s["chamfer"]["chamfer"].get<double>(), kModulusChamfer);
  fs::remove_all(c.dir);
}

TEST(Compare, WriteCompareWritesAllOrNothing) {
  const CompareCase c = MakeCase("quijibo_compare_write");
  const CompareResult r = Compare(c.options);
  const std::string out = (c.dir / "out").string();
  WriteCompare(r, out);
  EXPECT_EQ(ReadFile(out + "/compare.json"), r.report.dump(1) + "\n");
  EXPECT_EQ(ReadFile(out + "/compare.md"), r.markdown);
  // A folder that cannot be written: an error, and no file of the comparison left behind.
  const std::string blocked = (c.dir / "blocked").string();
  fs::create_directories(blocked + "/compare.md");  // a folder where the last file goes
  EXPECT_ANY_THROW(WriteCompare(r, blocked));
  EXPECT_FALSE(fs::exists(blocked + "/compare.json"));
  EXPECT_FALSE(fs::exists(blocked + "/quijibo.png"));
  fs::remove_all(c.dir);
}

// The IoU of two fields' insides, as compare measures its sets against the target.
TEST(Compare, InsideIouIsTheOneIou) {
  const std::vector<double> a{-1, -1, 1, 1, std::nan("")}, b{-1, 1, -1, 1, -1};
  EXPECT_DOUBLE_EQ(InsideIntersectionOverUnion(a, b), IntersectionOverUnion(1, 4));
  const std::vector<double> outside{1, 2};
  EXPECT_DOUBLE_EQ(InsideIntersectionOverUnion(outside, outside), 1.0);
}

}  // namespace
}  // namespace quijibo::pipeline
