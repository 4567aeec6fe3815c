// Every default is written once: the experiment schema's defaults are the stages' Options structs
// (a minimal experiment resolves to each stage's Options{}.ToJson()), and each subcommand's --help
// shows the struct's default for every option bound to a setting.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "experiments/pipeline/compare.h"
#include "experiments/pipeline/experiment.h"
#include "experiments/pipeline/plot.h"
#include "quijibo_command.h"

namespace quijibo::pipeline {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

const std::string kBunny = std::string(QUIJIBO_SOURCE_DIR) + "/data/bunny.obj";

json Resolve(const json& doc) {
  const fs::path dir = fs::temp_directory_path() / ("quijibo_schema_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const std::string path = (dir / "experiment.json").string();
  std::ofstream(path) << doc.dump();
  const json resolved = Experiment::FromFile(path).ToJson();
  fs::remove_all(dir);
  return resolved;
}

TEST(ExperimentSchema, AMinimalQuijiboExperimentResolvesToTheOptionsDefaults) {
  const json r = Resolve({{"target", {{"mesh", kBunny}}}});
  TargetOptions target;
  target.mesh = kBunny;
  EXPECT_EQ(r["target"], target.ToJson());
  EXPECT_EQ(r["initial"], InitialGuessStageOptions().ToJson());  // log-kernel for a mesh target
  ASSERT_EQ(r["optimizer"].size(), 1u);
  json optimizer = optim::OptimizeOptions().ToJson();
  optimizer["name"] = "optimized";
  EXPECT_EQ(r["optimizer"][0], optimizer);
  MeshStageOptions mesh;
  mesh.optimizer = "optimized";
  EXPECT_EQ(r["mesh"], mesh.ToJson());
  EXPECT_EQ(r["pictures"], PicturesOptions().ToJson());
  EXPECT_EQ(r["outputs"], json({{"plot", true}, {"report", true}, {"report_html", true}}));
  EXPECT_EQ(r["seed"], json(kDefaultSeed));
  // The values the documentation promises, from the structs that own them.
  EXPECT_EQ(r["target"]["padding"], FractalFrame{}.padding);
  EXPECT_EQ(r["mesh"]["resolution"], mesh::MeshingOptions{}.resolution);
  EXPECT_EQ(r["mesh"]["iterations"], JuliaOptions{}.iterations);
  EXPECT_EQ(r["initial"]["roots"], monopole::KernelFitOptions{}.roots);
}

TEST(ExperimentSchema, EachKindOfInitialGuessResolvesToItsDefaults) {
  for (const char* kind : {"log-kernel", "monopoles"}) {
    const json r = Resolve({{"target", {{"mesh", kBunny}}}, {"initial", {{"kind", kind}}}});
    InitialGuessStageOptions o;
    o.kind = kind;
    EXPECT_EQ(r["initial"], o.ToJson()) << kind;
  }
  const json r = Resolve({{"target", {{"analytic", "torus"}}}});
  InitialGuessStageOptions random;
  random.kind = "random";
  EXPECT_EQ(r["initial"], random.ToJson());
  EXPECT_EQ(r["initial"]["top"], RandomMapOptions{}.top);
  // The monopole fit's target: P, as the paper's text (MonopoleOptions owns it).
  EXPECT_EQ(Resolve({{"target", {{"mesh", kBunny}}}, {"initial", {{"kind", "monopoles"}}}})["initial"]["fit_target"],
            "potential");
  // The top-level seed is the default of every seed.
  const json seeded = Resolve({{"seed", 7}, {"target", {{"mesh", kBunny}}}, {"initial", {{"kind", "monopoles"}}}});
  EXPECT_EQ(seeded["initial"]["seed"], 7);
  EXPECT_EQ(seeded["initial"]["sampling_seed"], 7);
}

TEST(ExperimentSchema, ModulusAndPortalExperimentsResolveToTheirOptionsDefaults) {
  json r = Resolve({{"method", "modulus"}, {"target", {{"analytic", "sphere"}}}});
  TargetOptions target;
  target.analytic = "sphere";
  target.origin.reset();  // the unit frame has no fractal origin
  EXPECT_EQ(r["target"], target.ToJson());
  EXPECT_EQ(r["modulus"], ModulusStageOptions().ToJson());
  EXPECT_EQ(r["modulus"]["output"]["resolution"], mesh::MeshingOptions{}.resolution);
  EXPECT_EQ(r["pictures"], PicturesOptions().ToJson());
  r = Resolve({{"method", "portal"}, {"portal", {{"koch", true}}}});
  PortalStageOptions portal;
  portal.koch = true;
  EXPECT_EQ(r["portal"], portal.ToJson());
  EXPECT_FALSE(r.contains("target"));
}

// The option column of `--help` for `flag` ("-r,--resolution INT:[8, 1024]=97"), or "".
std::string OptionLine(const std::string& help, const std::string& flag) {
  std::istringstream in(help);
  for (std::string line; std::getline(in, line);) {
    const auto b = line.find_first_not_of(' ');
    if (b == std::string::npos || line[b] != '-') continue;
    const auto e = line.find("  ", b);
    const std::string column = line.substr(b, e == std::string::npos ? std::string::npos : e - b);
    const std::string names = column.substr(0, column.find(' '));
    std::stringstream ns(names);
    for (std::string n; std::getline(ns, n, ',');)
      if (n == flag) return column;
  }
  return "";
}

// The long name of a setting's flag ("--resolution" of "-r,--resolution").
std::string LongName(const std::string& flag) {
  std::stringstream ns(flag);
  std::string last;
  for (std::string n; std::getline(ns, n, ',');) last = n;
  return last;
}

// Every option of `command` bound to a setting of O (those in `keys`, when given) shows the
// default of `o` (a default-constructed O, or the stage's start).
template <class O>
void ExpectHelpShowsDefaults(const std::vector<std::string>& command, const O& o,
                             const std::vector<std::string>& keys = {}) {
  std::vector<std::string> args = command;
  args.push_back("--help");
  const auto r = testing::RunQuijiboArgs(args);
  ASSERT_EQ(r.code, 0) << r.err;
  int checked = 0;
  for (const auto& s : O::Settings().settings()) {
    if (s.flag.empty() || s.type == SettingType::kBoolean || s.type == SettingType::kNumbers) continue;
    if (!keys.empty() && std::find(keys.begin(), keys.end(), s.key) == keys.end()) continue;
    if (!s.Applies(o)) continue;
    json expected = s.get(o);
    if (expected.is_null() && s.fallback) expected = s.fallback(o);
    if (expected.is_null()) continue;  // an optional setting without a default (--quijibo-seconds)
    const std::string column = OptionLine(r.out, LongName(s.flag));
    ASSERT_FALSE(column.empty()) << command[0] << ": " << s.flag << " is not in --help";
    const auto eq = column.rfind('=');
    ASSERT_NE(eq, std::string::npos) << command[0] << ": " << column << " shows no default";
    const std::string shown = column.substr(eq + 1);
    if (expected.is_string()) {
      EXPECT_EQ(shown, expected.get<std::string>()) << command[0] << " " << s.flag;
    } else {
      EXPECT_DOUBLE_EQ(std::stod(shown), expected.get<double>()) << command[0] << " " << s.flag << ": " << column;
    }
    ++checked;
  }
  EXPECT_GT(checked, 0) << command[0];
}

// `quijibo optimize` binds OptimizeOptions' schema entries (optim/optimizer.h), as `quijibo run` reads them.
TEST(CommandLineSchema, OptimizeHelpShowsTheOptimizerDefaults) {
  const auto r = testing::RunQuijiboArgs({"optimize", "--help"});
  ASSERT_EQ(r.code, 0) << r.err;
  const json defaults = optim::OptimizeOptions().ToJson();
  const std::vector<std::pair<std::string, std::string>> flags = {
      {"--alpha", "alpha"},           {"--memory", "memory"},
      {"--absolute-every", "absolute_every"}, {"--checkpoint-every", "checkpoint_every"},
      {"--memory-budget", "memory_budget_gb"}, {"--tolerance", "tolerance"},
      {"--evaluator", "evaluator"},   {"--precision", "precision"},
      {"--backend", "backend"},       {"--weights", "weights"},
      {"--level-weights", "level_weights"}, {"--level-start", "level_start"},
      {"--storage", "storage"}};
  for (const auto& [flag, key] : flags) {
    const std::string column = OptionLine(r.out, flag);
    ASSERT_FALSE(column.empty()) << flag;
    const std::string shown = column.substr(column.rfind('=') + 1);
    if (defaults[key].is_string()) EXPECT_EQ(shown, defaults[key].get<std::string>()) << flag;
    else EXPECT_DOUBLE_EQ(std::stod(shown), defaults[key].get<double>()) << flag;
  }
}

TEST(CommandLineSchema, HelpShowsTheOptionsDefaults) {
  ExpectHelpShowsDefaults({"monopoles"}, TargetOptions(),
                          {"resolution", "padding", "fractal_radius", "box", "origin", "frame_scale"});
  InitialGuessStageOptions kernel, monopoles;
  monopoles.kind = "monopoles";
  ExpectHelpShowsDefaults({"monopoles"}, kernel);
  ExpectHelpShowsDefaults({"monopoles"}, monopoles);
  ExpectHelpShowsDefaults({"mesh"}, MeshStageOptions());
  ExpectHelpShowsDefaults({"picture", "slice"}, PicturesOptions(), {"slice_iterations", "slice_size"});
  ExpectHelpShowsDefaults({"picture", "slice"}, MeshStageOptions(), {"escape", "iso", "precision"});
  ExpectHelpShowsDefaults({"picture", "field"}, MeshStageOptions(), {"iterations", "escape", "iso", "precision"});
  ExpectHelpShowsDefaults({"picture", "render"}, PicturesOptions(), {"render_size", "render_views"});
  ExpectHelpShowsDefaults({"modulus"}, ModulusStageOptions());
  ExpectHelpShowsDefaults({"modulus"}, VersorOptions());
  ExpectHelpShowsDefaults({"modulus"}, ProductOutputOptions());
  ExpectHelpShowsDefaults({"portal"}, PortalStageOptions());
  ExpectHelpShowsDefaults({"portal"}, ProductOutputOptions());
  ExpectHelpShowsDefaults({"compare"}, CompareOptions());
  ExpectHelpShowsDefaults({"compare"}, ModulusStageOptions(), {"alpha", "beta"});
  ExpectHelpShowsDefaults({"plot"}, PlotOptions());
}

}  // namespace
}  // namespace quijibo::pipeline
