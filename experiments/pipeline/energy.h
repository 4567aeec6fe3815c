// The energy stage: psi (2015 paper Eqns 5-8) of a map on a target, its gradient and diagnostics as
// a JSON report, by the exact log-linear evaluator or the paper's cached one in any precision. What
// `quijibo energy` prints and Python's energy returns.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "util/settings.h"
#include "quijibo/energy.h"
#include "quijibo/grid.h"
#include "quijibo/loglinear_energy.h"
#include "quijibo/rational_map.h"
#include "quijibo/real.h"
#include "quijibo/target.h"

namespace quijibo::pipeline {

struct EnergyStageOptions {
  EnergyOptions energy;                 // alpha
  std::string evaluator = "loglinear";  // "loglinear" (exact, double; "dense" names it too) or "cached"
  Precision precision = Precision::kDouble;
  LogLinearOptions::Storage storage = LogLinearOptions::Storage::kAuto;
  // The level's grid and weights, as the optimizer makes them (quijibo/target.h): the optimizer's
  // weight field; resolution 0 is the target's own grid.
  WeightField weights = kDefaultWeightField;
  int resolution = 0;
  LevelWeights level_weights = LevelWeights::kSampleFinest;
  double slice = 0;  // k component S of the sample quaternions [x, y, z, S]
  EnergyMode mode = EnergyMode::kFull;
  bool gradient = true;
  int repeats = 1;  // evaluations, each timed

  static const Schema<EnergyStageOptions>& Settings();
  static EnergyStageOptions FromJson(const JsonReader& r, const std::string& pointer,
                                     const std::filesystem::path& base);
};

// Evaluates psi (and its gradient) of `map` on the level grid of `options` on `target` `repeats`
// times; returns the report: energy (number and exact decimal string), gradient (numbers, named,
// and exact strings), cell counts, seconds of each evaluation and their median, set-up seconds,
// storage used, the settings and the weights.
nlohmann::json EnergyStage(const RationalMap& map, const ScalarGrid& target, const EnergyStageOptions& options);

}  // namespace quijibo::pipeline
