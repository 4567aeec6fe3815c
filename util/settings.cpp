#include "util/settings.h"

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>

namespace quijibo {

using nlohmann::json;
namespace fs = std::filesystem;

namespace {

std::string Bound(SettingType type, double x) {
  if (type == SettingType::kInteger) return std::to_string(static_cast<long long>(x));
  return json(x).dump();
}

std::string Sizes(const std::vector<int>& sizes) {
  std::string s;
  for (std::size_t i = 0; i < sizes.size(); ++i)
    s += (i == 0 ? "" : i + 1 == sizes.size() ? " or " : ", ") + std::to_string(sizes[i]);
  return s;
}

std::string Choices(const std::vector<std::string>& choices) {
  std::string list;
  for (const auto& c : choices) list += (list.empty() ? "" : ", ") + ("\"" + c + "\"");
  return list;
}

bool InRange(double v, double lo, double hi, bool open_lo, bool open_hi) {
  return (open_lo ? v > lo : v >= lo) && (open_hi ? v < hi : v <= hi);
}

}  // namespace

std::string DescribeRange(SettingType type, double lo, double hi, bool open_lo, bool open_hi) {
  const bool has_lo = std::isfinite(lo), has_hi = std::isfinite(hi);
  if (has_lo && has_hi)
    return std::string(open_lo ? "(" : "[") + Bound(type, lo) + ", " + Bound(type, hi) + (open_hi ? ")" : "]");
  if (has_lo) return std::string(open_lo ? "> " : ">= ") + Bound(type, lo);
  if (has_hi) return std::string(open_hi ? "< " : "<= ") + Bound(type, hi);
  return "";
}

std::string CheckValue(const json& v, SettingType type, double lo, double hi, bool open_lo, bool open_hi,
                       const std::vector<std::string>& choices, const std::vector<int>& sizes) {
  const std::string range = DescribeRange(type, lo, hi, open_lo, open_hi);
  const std::string in = range.empty() ? "" : (range[0] == '[' || range[0] == '(' ? " in " : " ") + range;
  switch (type) {
    case SettingType::kInteger: {
      const long long x = v.get<long long>();
      if (!InRange(double(x), lo, hi, open_lo, open_hi))
        return "expected an integer" + in + ", found " + std::to_string(x);
      return {};
    }
    case SettingType::kNumber: {
      const double x = v.get<double>();
      if (!std::isfinite(x) || !InRange(x, lo, hi, open_lo, open_hi))
        return "expected a number" + in + ", found " + json(x).dump();
      return {};
    }
    case SettingType::kNumbers: {
      if (!sizes.empty() && std::find(sizes.begin(), sizes.end(), int(v.size())) == sizes.end())
        return "expected " + Sizes(sizes) + " numbers, found " + std::to_string(v.size());
      for (const json& x : v)
        if (!std::isfinite(x.get<double>()) || !InRange(x.get<double>(), lo, hi, open_lo, open_hi))
          return "expected numbers" + in + ", found " + x.dump();
      return {};
    }
    case SettingType::kChoice: {
      const std::string s = v.get<std::string>();
      if (std::find(choices.begin(), choices.end(), s) == choices.end())
        return "expected one of " + Choices(choices) + ", found \"" + s + "\"";
      return {};
    }
    case SettingType::kPath:
      if (v.get<std::string>().empty()) return "expected a file path, found an empty string";
      return {};
    default:
      return {};
  }
}

std::string SettingTypeName(SettingType type) {
  switch (type) {
    case SettingType::kInteger: return "integer";
    case SettingType::kNumber: return "number";
    case SettingType::kBoolean: return "boolean";
    case SettingType::kString: return "string";
    case SettingType::kChoice: return "choice";
    case SettingType::kPath: return "path";
    case SettingType::kNumbers: return "numbers";
  }
  return "";
}

json DescribeSetting(const std::string& key, const std::string& flag, const std::string& help, SettingType type,
                     const json& default_value, double lo, double hi, bool open_lo, bool open_hi,
                     const std::vector<std::string>& choices, const std::vector<int>& sizes) {
  json d = {{"key", key}, {"flag", flag}, {"help", help}, {"type", SettingTypeName(type)}, {"default", default_value}};
  const SettingType element = type == SettingType::kNumbers ? SettingType::kNumber : type;
  const bool numeric = element == SettingType::kInteger || element == SettingType::kNumber;
  if (const std::string range = numeric ? DescribeRange(element, lo, hi, open_lo, open_hi) : ""; !range.empty()) {
    d["range"] = range;
    if (std::isfinite(lo)) d["lo"] = lo, d["open_lo"] = open_lo;
    if (std::isfinite(hi)) d["hi"] = hi, d["open_hi"] = open_hi;
  }
  if (!choices.empty()) d["choices"] = choices;
  if (!sizes.empty()) d["sizes"] = sizes;
  return d;
}

std::string CheckRange(const std::string& name, SettingType type, double value, const ValueRange& r) {
  const json v = type == SettingType::kInteger ? json(static_cast<long long>(value)) : json(value);
  const std::string why = CheckValue(v, type, r.lo, r.hi, r.open_lo, r.open_hi, {}, {});
  return why.empty() ? why : name + ": " + why;
}

std::string ResolvePath(const fs::path& base, const std::string& p) {
  fs::path f(p);
  return (f.is_relative() ? (base / f).lexically_normal() : f).string();
}

json ReadValue(const JsonReader& r, const std::string& p, SettingType type, double lo, double hi, bool open_lo,
               bool open_hi, const std::vector<std::string>& choices, const std::vector<int>& sizes,
               const fs::path& base, bool must_exist) {
  json v;
  switch (type) {
    case SettingType::kInteger: {
      const json& j = r.at(p);
      // 97.0 is the integer 97 (JSON writers often cannot tell them apart).
      if (j.is_number_float() && std::isfinite(j.get<double>()) && j.get<double>() == std::floor(j.get<double>()) &&
          std::abs(j.get<double>()) < 9e15)
        v = static_cast<long long>(j.get<double>());
      else
        v = r.integer(p);
      break;
    }
    case SettingType::kNumber:
      v = r.number(p);
      break;
    case SettingType::kNumbers: {
      const std::size_t n = r.array_size(p);
      v = json::array();
      if (!sizes.empty() && std::find(sizes.begin(), sizes.end(), int(n)) == sizes.end())
        r.fail(p, "expected " + Sizes(sizes) + " numbers, found " + std::to_string(n));
      for (std::size_t i = 0; i < n; ++i) {
        const std::string pi = p + "/" + std::to_string(i);
        const double x = r.number(pi);
        if (std::string why = CheckValue(json(x), SettingType::kNumber, lo, hi, open_lo, open_hi, {}, {}); !why.empty())
          r.fail(pi, why);
        v.push_back(x);
      }
      return v;
    }
    case SettingType::kBoolean:
      v = r.boolean_or(p, false);
      break;
    case SettingType::kString:
    case SettingType::kChoice:
      v = r.string(p);
      break;
    case SettingType::kPath: {
      const std::string raw = r.string(p);
      if (raw.empty()) r.fail(p, "expected a file path, found an empty string");
      const std::string path = ResolvePath(base, raw);
      if (must_exist) {
        std::error_code ec;
        if (!fs::is_regular_file(path, ec)) r.fail(p, "no such file: " + path);
        if (::access(path.c_str(), R_OK) != 0) r.fail(p, "cannot read " + path + ": " + std::strerror(errno));
      }
      return path;
    }
  }
  if (std::string why = CheckValue(v, type, lo, hi, open_lo, open_hi, choices, sizes); !why.empty()) r.fail(p, why);
  return v;
}

}  // namespace quijibo
