// The command line agrees with the schemas (util/settings.h): every option bound to a setting
// shows the setting's default and accepts exactly its range and choices, and every command's target
// grid resolution is the experiment's. The options are checked on the app `quijibo` parses, with
// a required option never given, so a value is judged by CLI11's validation alone and no command runs.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "experiments/cli/bind.h"
#include "experiments/cli/cli.h"
#include "experiments/pipeline/experiment.h"

namespace quijibo::cli {
namespace {

using nlohmann::json;

// A required option on every command, never given: CLI11 checks requirements after it has run the
// options' validators and callbacks and before the command's own callback, so a parse is judged
// and no command runs. (Removing the callbacks instead would free the state they own while the
// options' callbacks still write into it.)
void StopBeforeRunning(CLI::App* app) {
  app->add_flag("--test-stop-before-running")->required();
  for (CLI::App* sub : app->get_subcommands([](CLI::App*) { return true; })) StopBeforeRunning(sub);
}

// True when `quijibo <command> <args>` is refused for an option's value (a range or a choice),
// not for a missing required option.
bool Refused(const std::string& command, const std::string& args) {
  CLI::App app;
  AddCommands(app);
  StopBeforeRunning(&app);
  try {
    app.parse(command + " " + args, false);
  } catch (const CLI::ValidationError&) {
    return true;
  } catch (const CLI::ParseError&) {
    return false;
  }
  return false;
}

// The option's long name in a schema flag ("-r,--resolution" -> "--resolution").
std::string LongName(const std::string& flag) {
  for (const std::string& n : CLI::detail::split_names(flag))
    if (CLI::detail::trim_copy(n).rfind("--", 0) == 0) return CLI::detail::trim_copy(n);
  return "";
}

std::string Text(double x, bool integer) { return integer ? std::to_string((long long)x) : json(x).dump(); }

// The values at and just beyond each finite end of a setting's range: accepted, refused.
void ExpectRange(const std::string& command, const std::string& name, const json& s) {
  const bool integer = s["type"] == "integer";
  if (s["type"] != "integer" && s["type"] != "number") return;
  auto step = [&](double x) { return integer ? 1.0 : std::max(1e-3, std::abs(x) * 1e-3); };
  if (s.contains("lo") && std::abs(s["lo"].get<double>()) < 1e15) {
    const double lo = s["lo"], inside = s["open_lo"].get<bool>() ? lo + step(lo) : lo;
    const double outside = s["open_lo"].get<bool>() ? lo : lo - step(lo);
    EXPECT_FALSE(Refused(command, name + "=" + Text(inside, integer))) << command << " " << name << " " << s["range"];
    EXPECT_TRUE(Refused(command, name + "=" + Text(outside, integer))) << command << " " << name << " " << s["range"];
  }
  if (s.contains("hi") && std::abs(s["hi"].get<double>()) < 1e15) {
    const double hi = s["hi"], inside = s["open_hi"].get<bool>() ? hi - step(hi) : hi;
    const double outside = s["open_hi"].get<bool>() ? hi : hi + step(hi);
    EXPECT_FALSE(Refused(command, name + "=" + Text(inside, integer))) << command << " " << name << " " << s["range"];
    EXPECT_TRUE(Refused(command, name + "=" + Text(outside, integer))) << command << " " << name << " " << s["range"];
  }
}

// Checks every setting of `section` whose flag `command` has (of `keys` only, when given, as the
// command binds them); returns how many it found. With `all`, every setting with a flag must be there.
int ExpectBound(const std::string& command, const std::string& section, bool all,
                const std::vector<std::string>& keys = {}) {
  CLI::App app;
  AddCommands(app);
  CLI::App* c = &app;
  for (const std::string& name : CLI::detail::split(command, ' ')) c = c->get_subcommand(name);
  const json settings = pipeline::DescribeSettings().at(section);
  std::vector<std::string> seen;
  int found = 0;
  for (const json& s : settings) {
    if (!keys.empty() && std::find(keys.begin(), keys.end(), s["key"]) == keys.end()) continue;
    const std::string name = LongName(s["flag"]);
    // The first setting with a flag is the one bound (kinds may share a flag).
    if (name.empty() || std::find(seen.begin(), seen.end(), name) != seen.end()) continue;
    seen.push_back(name);
    const CLI::Option* opt = c->get_option_no_throw(name);
    if (!opt) {
      EXPECT_FALSE(all) << command << " has no " << name << " (" << section << "/" << s["key"] << ")";
      continue;
    }
    ++found;
    SCOPED_TRACE(command + " " + name);
    if (!s["default"].is_null() && s["type"] != "boolean" && s["type"] != "numbers") {
      EXPECT_EQ(opt->get_default_str(), DefaultText(s["default"]));
    }
    ExpectRange(command, name, s);
    if (s.contains("choices")) {
      for (const json& choice : s["choices"]) EXPECT_FALSE(Refused(command, name + "=" + choice.get<std::string>()));
      EXPECT_TRUE(Refused(command, name + "=no-such-choice"));
    }
  }
  return found;
}

TEST(CliSettingsTest, EveryOptimizerSettingIsAnOptionOfOptimizeWithTheSameDefaultAndRange) {
  EXPECT_GE(ExpectBound("optimize", "optimizer", true), 15);
}

TEST(CliSettingsTest, EveryEnergySettingIsAnOptionOfEnergyWithTheSameDefaultAndRange) {
  EXPECT_GE(ExpectBound("energy", "energy", true), 10);
}

TEST(CliSettingsTest, TheStageCommandsShowTheExperimentsDefaultsAndRanges) {
  EXPECT_GE(ExpectBound("mesh", "mesh", false), 8);
  EXPECT_GE(ExpectBound("monopoles", "target", false), 5);
  EXPECT_GE(ExpectBound("monopoles", "initial", false), 10);
  EXPECT_GE(ExpectBound("picture slice", "pictures", false, {"slice_iterations", "slice_size"}), 2);
  EXPECT_GE(ExpectBound("picture render", "pictures", false, {"render_size", "render_views"}), 2);
  EXPECT_GE(ExpectBound("modulus", "modulus", false), 2);
  EXPECT_GE(ExpectBound("modulus", "modulus/versor", false), 1);
}

// The target grid of every command: the experiment's default (but where a command says why not)
// and the experiment's range.
TEST(CliSettingsTest, EveryTargetResolutionTakesTheExperimentsDefaultAndRange) {
  json resolution;
  const json target = pipeline::DescribeSettings().at("target");
  for (const json& s : target)
    if (s["key"] == "resolution") resolution = s;
  ASSERT_EQ(resolution["range"], "[8, 1024]");
  const std::vector<std::pair<std::string, std::string>> options = {
      {"optimize", "--target-resolution"}, {"energy", "--target-resolution"}, {"map random", "--target-resolution"},
      {"target", "--resolution"},          {"sdf", "--resolution"},           {"monopoles", "--resolution"},
      {"bench stages", "--resolution"},    {"bench shapes", "--resolution"}};
  for (const auto& [command, name] : options) {
    SCOPED_TRACE(command + " " + name);
    CLI::App app;
    AddCommands(app);
    CLI::App* c = &app;
    for (const std::string& part : CLI::detail::split(command, ' ')) c = c->get_subcommand(part);
    const CLI::Option* opt = c->get_option(name);
    // `map random --center-on` centres ln C on a coarse grid: the median of L needs no more.
    if (command != "map random") {
      EXPECT_EQ(opt->get_default_str(), DefaultText(resolution["default"]));
    }
    ExpectRange(command, name, resolution);
  }
}

}  // namespace
}  // namespace quijibo::cli
