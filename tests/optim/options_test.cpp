// OptimizeOptions: the one definition of every optimizer setting (defaults, ranges, JSON).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "optim/optimizer.h"
#include "optim/schedule.h"
#include "util/error.h"
#include "util/json_reader.h"

namespace quijibo::optim {
namespace {

using nlohmann::json;

OptimizeOptions Read(const json& j, const std::filesystem::path& base = ".") {
  return OptimizeOptions::FromJson(JsonReader(j, "exp.json"), "", base);
}

std::string ErrorOf(const json& j) {
  try {
    Read(j);
  } catch (const Error& e) {
    return e.what();
  }
  return "no error";
}

// The per-kind caps are written once: a V pass without a cap gets 200 iterations whether the
// schedule comes from the notation, the JSON form, the default schedule or OptimizeOptions.
TEST(OptimizeOptionsTest, AVPassWithoutACapGetsTheSameDefaultEverywhere) {
  EXPECT_EQ(DefaultPass(PassKind::kVariable).max_iterations, 200);
  EXPECT_EQ(DefaultPass(PassKind::kFull).max_iterations, 2000);
  EXPECT_EQ(DefaultPass(PassKind::kReweighted).max_iterations, 2000);
  EXPECT_EQ(Schedule::Parse("10(VFR)").levels[0].passes[0].max_iterations, 200);
  const json form = json::parse(R"({"levels": [{"resolution": 10, "passes": [{"kind": "V"}, {"kind": "F"}]}]})");
  EXPECT_EQ(Schedule::FromJson(JsonReader(form, "s.json"), "").levels[0].passes[0].max_iterations, 200);
  const OptimizeOptions defaults;
  EXPECT_EQ(defaults.max_iterations.V, 200);
  EXPECT_EQ(defaults.schedule.notation(), OptimizeOptions::kDefaultSchedule);
  EXPECT_EQ(defaults.schedule.levels[0].passes[0].max_iterations, 200);
  EXPECT_EQ(defaults.schedule.levels[0].passes[1].max_iterations, 2000);
  // The experiment's optimizer object without any key: the same settings.
  EXPECT_EQ(Read(json::object()).ToJson(), defaults.ToJson());
  EXPECT_EQ(Read(json::object()).schedule.levels[2].passes[0].max_iterations, 200);
  EXPECT_EQ(defaults.Validate(), "");
}

TEST(OptimizeOptionsTest, ToJsonHoldsEverySettingAndReadsBackUnchanged) {
  const json j = json::parse(R"j({"schedule": "10(VFRF)20(VF)", "backend": "ceres", "evaluator": "dense",
      "weights": "layer", "level_weights": "recompute", "level_start": "best", "alpha": 12.5, "memory": 7,
      "tolerance": 1e-6, "max_iterations": {"V": 11, "F": 22, "R": 33}, "checkpoint_every": 4,
      "absolute_every": 3, "storage": "float", "memory_budget_gb": 0.3})j");
  const OptimizeOptions o = Read(j);
  EXPECT_EQ(o.backend, "ceres");
  EXPECT_EQ(o.level_weights, LevelWeights::kRecompute);
  EXPECT_EQ(o.level_start, OptimizeOptions::LevelStart::kBest);
  EXPECT_EQ(o.storage, LogLinearOptions::Storage::kFloat);
  EXPECT_EQ(o.memory_budget_gb, 0.3);  // kept in GB: it reads back exactly
  EXPECT_EQ(o.schedule.levels[0].passes[0].max_iterations, 11);
  EXPECT_EQ(o.schedule.levels[0].passes[2].max_iterations, 33);
  EXPECT_EQ(o.schedule.levels[1].passes[1].tolerance, 1e-6);
  const json out = o.ToJson();
  for (const auto& [key, value] : j.items())
    if (key != "schedule") {
      EXPECT_EQ(out.at(key), value) << key;
    }
  EXPECT_EQ(out.at("precision"), "double");
  EXPECT_EQ(out.at("schedule").at("notation"), "10(VFRF)20(VF)");
  // out_dir, resume and callbacks are not settings.
  for (const char* k : {"out_dir", "resume", "callbacks"}) EXPECT_FALSE(out.contains(k)) << k;
  EXPECT_EQ(Read(out).ToJson(), out);
  // The schedule's notation beside its levels must agree with them.
  json wrong = out;
  wrong["schedule"]["notation"] = "10(VF)";
  EXPECT_EQ(ErrorOf(wrong), "exp.json: /schedule/notation: \"10(VF)\" does not match the levels (10(VFRF)20(VF)); give "
                            "either \"notation\" or \"levels\"");
}

TEST(OptimizeOptionsTest, ASchedulesFileResolvesAgainstTheBase) {
  const auto dir = std::filesystem::temp_directory_path() / "quijibo_options_base";
  std::filesystem::create_directories(dir / "schedules");
  std::ofstream(dir / "schedules" / "s.json") << R"({"levels": [{"resolution": 12, "passes": "VF"}]})";
  EXPECT_EQ(Read(json{{"schedule", "schedules/s.json"}}, dir).schedule.notation(), "12(VF)");
  EXPECT_NE(ErrorOf(json{{"schedule", "schedules/none.json"}}).find("/schedule: no such schedule file"),
            std::string::npos);
  // Every error inside a schedule file names the file and the pointer, notation errors included.
  auto error_in_file = [&](const std::string& text) {
    std::ofstream(dir / "schedules" / "bad.json") << text;
    try {
      Read(json{{"schedule", "schedules/bad.json"}}, dir);
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const std::string file = (dir / "schedules" / "bad.json").string();
  EXPECT_EQ(error_in_file(R"({"levels": [{"resolution": 12, "passes": "VX"}]})")
                .rfind(file + ": /levels/0/passes: schedule \"12(VX)\": at character 5: unknown pass 'X'", 0),
            0u);
  EXPECT_EQ(error_in_file(R"({"notation": "12(VF"})").rfind(file + ": /notation: schedule", 0), 0u);
  EXPECT_EQ(error_in_file("\"12(VX)\"").rfind(file + ": /: schedule \"12(VX)\"", 0), 0u);
  EXPECT_EQ(error_in_file(R"({"levels": [{"resolution": 12, "passes": [{"kind": "V", "max_iters": 5}]}]})"),
            file + ": /levels/0/passes/0/max_iters: unknown key (did you mean \"max_iterations\"?)");
  EXPECT_EQ(error_in_file("{\n \"levels\": [\n oops").rfind(file + ":3:2: invalid JSON: syntax error", 0), 0u);
  std::filesystem::remove_all(dir);
}

// Unknown keys get the known key they were probably meant as: a typo, another spelling, a clipped word.
TEST(OptimizeOptionsTest, UnknownKeysGetSuggestions) {
  EXPECT_EQ(ErrorOf({{"max_iters", 5}}), "exp.json: /max_iters: unknown key (did you mean \"max_iterations\"?)");
  EXPECT_EQ(ErrorOf({{"maxIterations", 5}}), "exp.json: /maxIterations: unknown key (did you mean \"max_iterations\"?)");
  EXPECT_EQ(ErrorOf({{"checkpoint", 5}}), "exp.json: /checkpoint: unknown key (did you mean \"checkpoint_every\"?)");
  EXPECT_EQ(SuggestKey("colour", {"alpha", "memory"}), "");
  EXPECT_EQ(SuggestKey("mem", {"alpha", "memory"}), "");
}

TEST(OptimizeOptionsTest, BadValuesNameThePointerAndTheRange) {
  EXPECT_EQ(ErrorOf({{"memory", 0}}), "exp.json: /memory: expected an integer in [1, 100], found 0");
  EXPECT_EQ(ErrorOf({{"alpha", 0}}), "exp.json: /alpha: expected a number in (0.0, 1000000.0], found 0.0");
  EXPECT_EQ(ErrorOf({{"max_iterations", {{"F", 0}}}}),
            "exp.json: /max_iterations/F: expected an integer in [1, 10000000], found 0");
  EXPECT_EQ(ErrorOf({{"backend", "bfgs"}}), "exp.json: /backend: expected one of \"lbfgspp\", \"ceres\", found \"bfgs\"");
  EXPECT_EQ(ErrorOf({{"memroy", 5}}), "exp.json: /memroy: unknown key (did you mean \"memory\"?)");
  EXPECT_EQ(ErrorOf({{"precision", "float"}, {"evaluator", "dense"}}),
            "exp.json: /precision: the loglinear evaluator runs in double only; use \"evaluator\": \"cached\" for "
            "\"float\"");
  EXPECT_EQ(ErrorOf({{"schedule", "10(VX)"}}).rfind("exp.json: /schedule: schedule \"10(VX)\"", 0), 0u);
  EXPECT_EQ(ErrorOf(json::array()), "exp.json: /: expected an object, found array []");
  // An integral float counts as an integer; extra keys are allowed only when named.
  EXPECT_EQ(Read({{"memory", 6.0}}).memory, 6);
  EXPECT_EQ(ErrorOf({{"name", "a"}}), "exp.json: /name: unknown key");
  EXPECT_NO_THROW(OptimizeOptions::FromJson(JsonReader(json{{"name", "a"}}, "exp.json"), "", ".", {"name"}));
}

TEST(OptimizeOptionsTest, ValidateNamesTheSettingAndItsRange) {
  OptimizeOptions o;
  o.memory = 0;
  EXPECT_EQ(o.Validate(), "memory: expected an integer in [1, 100], found 0");
  o = OptimizeOptions{};
  o.energy.alpha = -1;
  EXPECT_EQ(o.Validate(), "alpha: expected a number in (0.0, 1000000.0], found -1.0");
  o = OptimizeOptions{};
  o.max_iterations.R = 0;
  EXPECT_EQ(o.Validate(), "max_iterations.R: expected an integer in [1, 10000000], found 0");
  o = OptimizeOptions{};
  o.checkpoint_every = 0;
  EXPECT_EQ(o.Validate(), "checkpoint_every: expected an integer in [1, 1000000], found 0");
  o = OptimizeOptions{};
  o.backend = "bfgs";
  EXPECT_NE(o.Validate().find("bfgs"), std::string::npos);
}

}  // namespace
}  // namespace quijibo::optim
