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

#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "util/json_reader.h"
#include "util/settings.h"

namespace quijibo::optim {

enum class PassKind : char { kVariable = 'V', kFull = 'F', kReweighted = 'R' };
inline constexpr PassKind kPassKinds[3] = {PassKind::kVariable, PassKind::kFull, PassKind::kReweighted};
int PassKindIndex(PassKind kind);  // V 0, F 1, R 2

// What a pass gets when the schedule does not say (the one definition: the notation, the JSON
// form, OptimizeOptions and `quijibo optimize` all start from these). F and R: the reference
// code's cap; V moves three variables and converges in far fewer iterations.
inline constexpr int kDefaultMaxIterations[3] = {200, 2000, 2000};  // V, F, R
inline constexpr double kDefaultTolerance = 1e-5;
inline constexpr ValueRange kMaxIterationsRange{1, 10000000};
// Unbounded above: a tolerance no gradient meets makes a pass stop at once (tests of stalled passes).
inline constexpr ValueRange kToleranceRange{0, std::numeric_limits<double>::infinity()};

struct PassSpec {
  PassKind kind = PassKind::kFull;
  int max_iterations = kDefaultMaxIterations[1];
  double tolerance = kDefaultTolerance;  // on the infinity norm of the projected gradient
  std::string Validate() const;
  // max_iterations and tolerance, as a pass or a kind's "defaults" of the JSON form has them.
  static const Schema<PassSpec>& Settings();
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
  std::string Validate() const;
};

// The default pass of a kind (kDefaultMaxIterations, kDefaultTolerance).
PassSpec DefaultPass(PassKind kind);

}  // namespace quijibo::optim
