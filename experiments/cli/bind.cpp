#include "experiments/cli/bind.h"

#include "quijibo/frame.h"

namespace quijibo::cli {

std::string DefaultText(const nlohmann::json& v) {
  if (v.is_string()) return v.get<std::string>();
  std::string s = v.dump();
  if (v.is_number_float() && s.size() > 2 && s.ends_with(".0")) s.resize(s.size() - 2);
  return s;
}

CLI::Validator RangeValidator(SettingType type, double lo, double hi, bool open_lo, bool open_hi,
                              const std::vector<int>&) {
  const SettingType element = type == SettingType::kNumbers ? SettingType::kNumber : type;
  return CLI::Validator(
      [=](std::string& text) -> std::string {
        nlohmann::json v;
        try {
          std::size_t used = 0;
          if (element == SettingType::kInteger)
            v = std::stoll(text, &used);
          else
            v = std::stod(text, &used);
          if (used != text.size()) return "expected a number, found \"" + text + "\"";
        } catch (const std::exception&) {
          return "expected a number, found \"" + text + "\"";
        }
        return CheckValue(v, element, lo, hi, open_lo, open_hi, {}, {});
      },
      DescribeRange(element, lo, hi, open_lo, open_hi));
}

CLI::Option* AddTargetResolution(CLI::App* c, int& value, const std::string& flag, const std::string& help) {
  const ValueRange& r = kTargetResolutionRange;
  return c->add_option(flag, value, help)
      ->capture_default_str()
      ->check(RangeValidator(SettingType::kInteger, r.lo, r.hi, r.open_lo, r.open_hi, {}));
}

}  // namespace quijibo::cli
