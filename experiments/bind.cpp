#include "experiments/bind.h"

namespace quijibo::cli {

std::string DefaultText(const nlohmann::json& v) {
  if (v.is_string()) return v.get<std::string>();
  std::string s = v.dump();
  if (v.is_number_float() && s.size() > 2 && s.ends_with(".0")) s.resize(s.size() - 2);
  return s;
}

CLI::Validator RangeValidator(pipeline::SettingType type, double lo, double hi, bool open_lo, bool open_hi,
                              const std::vector<int>&) {
  using pipeline::SettingType;
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
        return pipeline::CheckValue(v, element, lo, hi, open_lo, open_hi, {}, {});
      },
      pipeline::DescribeRange(element, lo, hi, open_lo, open_hi));
}

}  // namespace quijibo::cli
