// The valid range of a numeric setting, written once next to the setting and read by the
// options' Validate, their FromJson and the command line's checks, so the three cannot disagree.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

namespace quijibo::optim {

struct SettingRange {
  const char* key;       // the setting's JSON key
  double lo, hi;
  bool integer = false;  // an integer setting (messages say so)
  bool open_lo = false;  // (lo, hi] instead of [lo, hi]

  bool contains(double v) const { return (open_lo ? v > lo : v >= lo) && v <= hi; }
  // "[1, 100]" for integers; numbers as JSON writes them: "(0.0, 1000000.0]".
  std::string interval() const {
    std::string s = open_lo ? "(" : "[";
    s += integer ? std::to_string((long long)lo) : nlohmann::json(lo).dump();
    s += ", ";
    s += integer ? std::to_string((long long)hi) : nlohmann::json(hi).dump();
    return s + "]";
  }
  std::string Format(double v) const {
    return integer ? std::to_string((long long)v) : nlohmann::json(v).dump();
  }
  // What a JSON reader says about a value outside the range: "expected an integer in [1, 100], found 0".
  std::string Expected(double v) const {
    return std::string("expected ") + (integer ? "an integer" : "a number") + " in " + interval() + ", found " +
           Format(v);
  }
  // What Validate says: "" or "memory must be in [1, 100], found 0".
  std::string Check(double v) const {
    return contains(v) ? std::string() : std::string(key) + " must be in " + interval() + ", found " + Format(v);
  }
};

}  // namespace quijibo::optim
