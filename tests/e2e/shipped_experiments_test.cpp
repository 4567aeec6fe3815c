// Every shipped experiment (experiments/*.json) validates with `quijibo run --check` and runs end to
// end at a small scale: its resolved form (every default filled in, every path absolute) with grids,
// pictures and per-pass iteration caps made small (the target grid 20^3, levels in proportion), the structure (method, initial guess, every
// optimizer run with its evaluator, precision and schedule of levels and passes, mesh, pictures,
// plot) unchanged. So every stage of every method in what we ship runs in CI.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "quijibo_command.h"

namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using quijibo::testing::RunQuijibo;

std::string Slurp(const std::string& p) {
  std::ifstream in(p);
  return std::string((std::istreambuf_iterator<char>(in)), {});
}

std::vector<std::string> ShippedExperiments() {
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(std::string(QUIJIBO_SOURCE_DIR) + "/experiments"))
    if (e.path().extension() == ".json") names.push_back(e.path().stem().string());
  std::sort(names.begin(), names.end());
  return names;
}

// The small copy of a resolved experiment (see the top of the file).
json Shrink(json e) {
  for (const char* k : {"format", "version", "experiment"}) e.erase(k);
  constexpr int kTarget = 20;
  double scale = 1;
  if (e.contains("target")) {
    e["target"].erase("kind");
    if (e["target"].contains("resolution")) {
      scale = double(kTarget) / e["target"]["resolution"].get<int>();
      e["target"]["resolution"] = kTarget;
    }
  }
  if (e.contains("initial")) {
    json& in = e["initial"];
    for (const char* k : {"png_size"})
      if (in.contains(k)) in[k] = 32;
    if (in["kind"] == "monopoles") {
      in["candidates"] = std::min(in["candidates"].get<int>(), 2000);
      in["bem_elements"] = 300;
      in["scan_resolution"] = std::min(in["scan_resolution"].get<int>(), 16);
    }
  }
  if (e.contains("optimizer"))
    for (json& o : e["optimizer"]) {
      o["checkpoint_every"] = 2;
      o["absolute_every"] = 2;
      o["schedule"].erase("notation");  // the levels say it
      for (json& level : o["schedule"]["levels"]) {
        level["resolution"] = std::max(4, int(std::lround(level["resolution"].get<int>() * scale)));
        // A tolerance of 0: a pass stops early only when its gradient is exactly 0 (or on its line search).
        for (json& p : level["passes"]) {
          p["max_iterations"] = std::min(p["max_iterations"].get<int>(), 3);
          p["tolerance"] = 0.0;
        }
      }
    }
  if (e.contains("mesh")) e["mesh"]["resolution"] = 24;
  if (e.contains("intricate")) e["intricate"]["resolution"] = 24;
  if (e.contains("pictures")) {
    e["pictures"]["slice_size"] = 32;
    e["pictures"]["render_size"] = 32;
    e["pictures"]["triptych_size"] = 64;
  }
  for (const char* method : {"modulus", "portal"})
    if (e.contains(method)) {
      e[method]["sdf_resolution"] = 16;
      e[method]["output"]["resolution"] = 24;
      e[method]["output"]["png_size"] = 48;
    }
  return e;
}

// The stages a run of `e` (resolved) must record, in order (experiments/cli/run.cpp).
std::vector<std::string> ExpectedStages(const json& e) {
  const std::string method = e["method"];
  if (method != "quijibo") {
    std::vector<std::string> s = {method};
    if (e["pictures"]["enabled"].get<bool>() && e[method]["output"]["format"] == "ply") s.push_back("pictures");
    return s;
  }
  std::vector<std::string> s = {"initial"};
  for (const json& o : e["optimizer"]) s.push_back("optimize " + o["name"].get<std::string>());
  if (e["outputs"]["plot"].get<bool>()) s.push_back("plot");
  if (e["mesh"]["enabled"].get<bool>()) s.push_back("mesh");
  if (e["intricate"]["enabled"].get<bool>()) s.push_back("mesh (intricate surface)");
  if (e["pictures"]["enabled"].get<bool>()) s.push_back("pictures");
  s.push_back("fidelity");  // report.md's Quality figures
  if (e["pictures"]["enabled"].get<bool>() && e["pictures"]["triptych"].get<bool>()) s.push_back("triptych");
  return s;
}

TEST(ShippedExperiments, TheListIsTheDocumentedOne) {
  const std::vector<std::string> expected = {"bunny-193",           "bunny-demo",           "bunny-ear-portals",
                                             "bunny-intricate",     "bunny-modulus",        "bunny-origin-offset",
                                             "bunny-paper",         "bunny-varying-alpha",  "elephant-intricate",   "hexagram-bunny-mask",
                                             "koch-noise-portals",  "koch-portal",          "precision-comparison",
                                             "tooth-intricate",     "tooth-paper"};
  EXPECT_EQ(ShippedExperiments(), expected) << "a new shipped experiment: add it to docs/benchmarks.md §10";
}

class ShippedExperiment : public ::testing::TestWithParam<std::string> {};

TEST_P(ShippedExperiment, ChecksAndRunsEveryStageAtASmallScale) {
  const std::string name = GetParam();
  const std::string source = std::string(QUIJIBO_SOURCE_DIR) + "/experiments/" + name + ".json";
  // Per process: runs of the suite side by side (two build trees) must not share a folder.
  const std::string dir =
      (fs::temp_directory_path() / ("quijibo_shipped_" + name + "_" + std::to_string(::getpid()))).string();
  fs::remove_all(dir);
  fs::create_directories(dir);
  // The shipped file validates as it is.
  const auto check = RunQuijibo("run " + source + " --check > " + dir + "/resolved.json");
  ASSERT_EQ(check.code, 0) << Slurp(dir + "/resolved.json");
  const json resolved = json::parse(Slurp(dir + "/resolved.json"));
  EXPECT_EQ(resolved["name"], name);

  const json small = Shrink(resolved);
  const std::string exp = dir + "/" + name + "-small.json", out = dir + "/results";
  std::ofstream(exp) << small.dump(1);
  const auto run = RunQuijibo("run " + exp + " --out " + out);
  ASSERT_EQ(run.code, 0) << run.out << "\n" << small.dump(1);

  const json record = json::parse(Slurp(out + "/run.json"));
  std::vector<std::string> stages;
  for (const json& s : record["stages"]) {
    stages.push_back(s["stage"]);
    EXPECT_EQ(s["status"], "ran") << s;
  }
  const json ran = json::parse(Slurp(out + "/experiment.resolved.json"));
  EXPECT_EQ(stages, ExpectedStages(ran));
  EXPECT_TRUE(fs::exists(out + "/report.md"));
  // Every pass of every optimizer run ran (or says why it could not move).
  if (ran["method"] == "quijibo") {
    for (const json& o : ran["optimizer"]) {
      const std::string folder = out + "/" + o["name"].get<std::string>();
      const json summary = json::parse(Slurp(folder + "/summary.json"));
      EXPECT_TRUE(summary["complete"].get<bool>());
      EXPECT_EQ(summary["evaluator"], o["evaluator"]);
      EXPECT_EQ(summary["precision"], o["precision"]);
      std::size_t passes = 0;
      for (const json& level : o["schedule"]["levels"]) passes += level["passes"].size();
      ASSERT_EQ(summary["passes"].size(), passes) << folder;
      for (const json& p : summary["passes"])
        EXPECT_TRUE(p["iterations"].get<int>() > 0 || !p["stall_reason"].get<std::string>().empty()) << p;
      EXPECT_TRUE(std::isfinite(summary["absolute_end"].get<double>()));
      EXPECT_LE(summary["absolute_end"].get<double>(), summary["absolute_start"].get<double>());
    }
    EXPECT_TRUE(fs::exists(out + "/initial/map.json"));
    if (ran["mesh"]["enabled"].get<bool>()) {
      EXPECT_TRUE(fs::exists(out + "/mesh/summary.json"));
    }
    if (ran["outputs"]["plot"].get<bool>()) {
      EXPECT_TRUE(fs::exists(out + "/plot/convergence.png") || fs::exists(out + "/plot/no-plot.txt"));
    }
  } else {
    const std::string method = ran["method"];
    const std::string ext = ran[method]["output"]["format"];
    EXPECT_TRUE(fs::exists(out + "/" + method + "/julia." + ext));
  }
  fs::remove_all(dir);
}

INSTANTIATE_TEST_SUITE_P(All, ShippedExperiment, ::testing::ValuesIn(ShippedExperiments()),
                         [](const ::testing::TestParamInfo<std::string>& info) {
                           std::string n = info.param;
                           std::replace(n.begin(), n.end(), '-', '_');
                           return n;
                         });

}  // namespace
