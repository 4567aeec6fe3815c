// `quijibo monopoles` as a user meets it: the files it promises, and nothing on failure.
#include <gtest/gtest.h>

#include "quijibo_command.h"
#include <sys/wait.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "quijibo/grid.h"
#include "quijibo/rational_map.h"

namespace quijibo::monopole {
namespace {

int RunQuijibo(const std::string& args, std::string* out = nullptr) {
  const testing::CommandResult r = testing::RunQuijibo("monopoles " + args);
  if (out) *out = r.out;
  return r.code;
}

std::filesystem::path FreshDir(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() / ("quijibo_monopoles_" + name);
  std::filesystem::remove_all(dir);
  return dir;
}

TEST(MonopolesCommand, TheLogKernelStartOfTheBunnyIsCloseAndNotInverted) {
  const auto dir = FreshDir("bunny_kernel");
  std::string out;
  ASSERT_EQ(RunQuijibo(std::string(QUIJIBO_SOURCE_DIR) + "/data/bunny.obj -o " + dir.string() +
                    " -r 40 --roots 160 --png-size 64",
                &out),
            0)
      << out;
  for (const char* f : {"map.json", "target.qgrid", "target.frame.json", "roots.ply", "start.png", "monopoles.json"})
    EXPECT_TRUE(std::filesystem::exists(dir / f)) << f;
  const nlohmann::json summary = nlohmann::json::parse(std::ifstream(dir / "monopoles.json"));
  EXPECT_EQ(summary["initializer"], "log-kernel");
  EXPECT_FALSE(summary["start"]["inverted"].get<bool>());
  EXPECT_GT(summary["start"]["iou"].get<double>(), 0.85);
  const RationalMap map = ReadMap((dir / "map.json").string());
  // The origin was placed inside the shape, and the target grid is the unit cube about the box centre.
  EXPECT_FALSE(map.frame.default_origin());
  EXPECT_EQ(map.top_roots.at(0), (Vec4{0, 0, 0, 0}));  // the origin root
  const ScalarGrid target = ReadGrid((dir / "target.qgrid").string());
  EXPECT_LT(target.sample({0, 0, 0}), -2 * target.frame.spacing);
  EXPECT_NEAR(target.frame.spacing * 40, map.frame.fractal_radius, 1e-12);
  std::filesystem::remove_all(dir);
}

TEST(MonopolesCommand, WritesTheInitialGuessOfTheBunny) {
  const auto dir = FreshDir("bunny");
  std::string out;
  ASSERT_EQ(RunQuijibo(std::string(QUIJIBO_SOURCE_DIR) + "/data/bunny.obj -o " + dir.string() +
                    " -r 25 --initializer monopoles --target-box reference --origin center"
                    " --candidates 10000 --bem-elements 600 --png-size 64 --amplitude 50"
                    " --epsilon 0.04 --no-both-signs --hollow-roots 0 --attract-roots 0",
                &out),
            0)
      << out;
  for (const char* f : {"map.json", "target.qgrid", "target.frame.json", "roots.ply", "potential.png", "monopoles.json"})
    EXPECT_TRUE(std::filesystem::exists(dir / f)) << f;
  const RationalMap map = ReadMap((dir / "map.json").string());
  const nlohmann::json summary = nlohmann::json::parse(std::ifstream(dir / "monopoles.json"));
  // The origin root (the IoU scan's, in place of the reference's two zero roots) plus one root per monopole.
  EXPECT_EQ(map.top_count() + map.bottom_count(), summary["monopoles"].get<int>() + 1);
  EXPECT_LE(summary["relative_residual"].get<double>(), 0.04);
  EXPECT_TRUE(std::isfinite(map.ln_C));
  for (double e : map.top_exponents) EXPECT_GT(e, 0.0);
  for (double e : map.bottom_exponents) EXPECT_GT(e, 0.0);
  const ScalarGrid target = ReadGrid((dir / "target.qgrid").string());
  EXPECT_EQ(target.frame.dims, (std::array<int, 3>{25, 25, 25}));
  // The roots sit on the surface: within a cell or so of the SDF's zero level.
  for (std::size_t i = 1; i < map.top_roots.size(); ++i) {
    const Vec3 p{map.top_roots[i][0], map.top_roots[i][1], map.top_roots[i][2]};
    EXPECT_LT(std::abs(target.sample(p)), 2.0 * target.frame.spacing);
  }
  std::filesystem::remove_all(dir);
}

TEST(MonopolesCommand, FailureLeavesNoOutput) {
  const auto dir = FreshDir("bad");
  std::string out;
  EXPECT_NE(RunQuijibo("/nonexistent/mesh.obj -o " + dir.string(), &out), 0);
  EXPECT_NE(out.find("mesh.obj"), std::string::npos) << out;
  EXPECT_FALSE(std::filesystem::exists(dir));
  EXPECT_NE(RunQuijibo(std::string(QUIJIBO_SOURCE_DIR) + "/data/bunny.obj -o " + dir.string() + " --epsilon 1.5", &out), 0);
  EXPECT_NE(out.find("epsilon"), std::string::npos) << out;
  EXPECT_FALSE(std::filesystem::exists(dir));
}

}  // namespace
}  // namespace quijibo::monopole
