// Command-line bindings of a stage's settings (util/settings.h): each setting
// with a flag becomes a CLI11 option on the same Options field, its default shown from the struct
// (the same value `quijibo run` fills in) and its range checked with the same message.
#pragma once

#include <CLI/CLI.hpp>
#include <algorithm>
#include <string>
#include <vector>

#include "util/settings.h"

namespace quijibo::cli {

// A default as --help shows it: integers as integers, numbers without a trailing ".0".
std::string DefaultText(const nlohmann::json& value);

// A CLI11 validator of a setting's range ("[8, 1024]" in --help).
CLI::Validator RangeValidator(SettingType type, double lo, double hi, bool open_lo, bool open_hi,
                              const std::vector<int>& sizes);

// A target grid resolution option (kTargetResolutionRange, quijibo/frame.h) on `value`, whose
// initializer is the default shown: every command's target grid takes the experiment's range.
CLI::Option* AddTargetResolution(CLI::App* c, int& value, const std::string& flag, const std::string& help);

// Binds the settings of `o` that have a flag (only those in `keys`, when given) to options of `c`.
// The first setting with a flag wins when several (of different kinds) share it.
template <class O>
void BindSettings(CLI::App* c, O& o, const std::vector<std::string>& keys = {}) {
  for (const Setting<O>& s : O::Settings().settings()) {
    if (s.flag.empty()) continue;
    if (!keys.empty() && std::find(keys.begin(), keys.end(), s.key) == keys.end()) continue;
    bool taken = false;
    for (const auto& name : CLI::detail::split_names(s.flag)) {
      const std::string n = CLI::detail::trim_copy(name);
      taken |= c->get_option_no_throw(n) != nullptr;
    }
    if (taken) continue;
    const auto set = s.set;
    O* target = &o;
    if (s.type == SettingType::kBoolean) {
      const bool value = s.flag.rfind("--no-", 0) != 0;
      c->add_flag(
          s.flag, [target, set, value](std::int64_t) { set(*target, nlohmann::json(value)); }, s.help);
      continue;
    }
    CLI::Option* opt = nullptr;
    switch (s.type) {
      case SettingType::kInteger:
        opt = c->add_option_function<long long>(
            s.flag, [target, set](const long long& v) { set(*target, nlohmann::json(v)); }, s.help);
        break;
      case SettingType::kNumber:
        opt = c->add_option_function<double>(
            s.flag, [target, set](const double& v) { set(*target, nlohmann::json(v)); }, s.help);
        break;
      case SettingType::kNumbers:
        opt = c->add_option_function<std::vector<double>>(
            s.flag, [target, set](const std::vector<double>& v) { set(*target, nlohmann::json(v)); }, s.help);
        if (s.sizes.size() == 1) opt->expected(s.sizes[0]);
        if (s.sizes.size() > 1) opt->expected(s.sizes.front(), s.sizes.back());
        opt->delimiter(',');  // "x,y,z" as well as "x y z"
        break;
      default:
        opt = c->add_option_function<std::string>(
            s.flag, [target, set](const std::string& v) { set(*target, nlohmann::json(v)); }, s.help);
        if (s.type == SettingType::kChoice) opt->check(CLI::IsMember(s.choices));
        break;
    }
    if (s.type == SettingType::kInteger || s.type == SettingType::kNumber || s.type == SettingType::kNumbers)
      if (!DescribeRange(s.type, s.lo, s.hi, s.open_lo, s.open_hi).empty() || !s.sizes.empty())
        opt->check(RangeValidator(s.type, s.lo, s.hi, s.open_lo, s.open_hi, s.sizes));
    nlohmann::json def = s.get(o);
    if (def.is_null() && s.fallback) def = s.fallback(o);
    if (!def.is_null() && s.type != SettingType::kNumbers) opt->default_str(DefaultText(def));
  }
}

}  // namespace quijibo::cli
