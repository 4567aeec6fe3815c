// Multi-level optimization schedules (2015 paper §4.5): levels run coarse to fine, each a list of
// passes:
//   V  variable-coarsened: only ln C, tau, beta move
//   F  full: all R + 3 variables
//   R  reweighted: a full pass under the reference code's reweighted W (reweight.h), after which
//      the original W is restored
// Written as the paper does, "25(VFRF)50(VFRF)97(VF)", or as JSON with per-pass caps:
//   {"levels": [{"resolution": 25, "passes": "VFRF"},
//               {"resolution": 97, "passes": [{"kind": "V", "max_iterations": 100},
//                                             {"kind": "F", "max_iterations": 400, "tolerance": 1e-6}]}],
//    "defaults": {"V": {"max_iterations": 200}, "F": {...}, "R": {...}}}
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace quijibo {

class JsonReader;

enum class PassKind : char { kVariable = 'V', kFull = 'F', kReweighted = 'R' };

struct PassSpec {
  PassKind kind = PassKind::kFull;
  int max_iterations = 2000;  // the reference code's cap
  double tolerance = 1e-5;    // on the infinity norm of the projected gradient
  std::string validate() const;
};

struct LevelSpec {
  int resolution = 25;  // cells along the longest axis of the target's box
  std::vector<PassSpec> passes;
};

struct Schedule {
  std::vector<LevelSpec> levels;

  // "25(VFRF)50(VFRF)97(VF)"; passes get `defaults[kind]` (V, F, R in that order).
  static Schedule Parse(const std::string& notation, const PassSpec defaults[3] = nullptr);
  // The JSON form at `pointer` of a document read by `reader` (errors name the JSON pointer).
  static Schedule FromJson(const JsonReader& reader, const std::string& pointer);
  nlohmann::json ToJson() const;
  std::string notation() const;
  int pass_count() const;
  std::string validate() const;
};

// Defaults per pass kind, indexed V, F, R.
PassSpec DefaultPass(PassKind kind);

}  // namespace quijibo
