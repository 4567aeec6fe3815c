// The initial-guess stage: the map the optimization starts from. For mesh targets the log-kernel
// fit (monopole/kernel_fit.h, the default) or the paper's monopoles (monopole/fit_pipeline.h,
// 2015 §4.4); for any target a random map or a given map.json.
#pragma once

#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "experiments/pipeline/settings.h"
#include "experiments/pipeline/target.h"
#include "monopole/fit_pipeline.h"
#include "monopole/initial_guess.h"
#include "monopole/kernel_fit.h"
#include "util/image.h"
#include "quijibo/rational_map.h"

namespace quijibo::pipeline {

struct InitialGuessStageOptions {
  InitialGuessStageOptions() { SetSeeds(kDefaultSeed); }
  // "log-kernel", "monopoles", "random" or "map". The experiment's default: "log-kernel" for mesh
  // targets, else "random" (Experiment::FromJson).
  std::string kind = "log-kernel";
  monopole::KernelFitOptions kernel;    // log-kernel (kernel.seed: the blue-noise sampling)
  monopole::MonopoleOptions monopole;   // monopoles (monopole.target: fit P or 1 - P)
  monopole::InitialGuessOptions guess;  // monopoles: amplitude, zero roots, ln C scan
  // monopoles: settings left to the library's default unless given.
  std::optional<int> batch, bem_elements;
  std::optional<double> offset;
  RandomMapOptions random;  // random
  std::string map;          // map: the map.json to start from
  int png_size = 800;       // pixels of start.png (log-kernel) or potential.png (monopoles)

  std::string Validate() const;
  static const Schema<InitialGuessStageOptions>& Settings();
  // Missing settings keep `start`'s values (the kind's default and the seeds come from the
  // experiment).
  static InitialGuessStageOptions FromJson(const JsonReader& r, const std::string& pointer,
                                           const std::filesystem::path& base, const InitialGuessStageOptions& start);
  static InitialGuessStageOptions FromJson(const JsonReader& r, const std::string& pointer,
                                           const std::filesystem::path& base) {
    return FromJson(r, pointer, base, InitialGuessStageOptions());
  }
  nlohmann::json ToJson() const;
  // The monopole options with the optional settings applied.
  monopole::MonopoleOptions Monopoles() const;
  // Every seed of the guess (sampling, candidate order, random map) set to `seed`.
  void SetSeeds(std::uint64_t seed);
};

struct InitialGuessResult {
  RationalMap map;
  nlohmann::json summary;  // monopoles.json (log-kernel and monopoles; null for random and map)
  // The picture of the start: start.png (log-kernel: the one-step set against the target) or
  // potential.png (monopoles: the potential and the roots); empty for random and map.
  std::string picture_name;
  std::shared_ptr<Image> picture;
};

// What the paper's monopole start is worth: `refusal` (non-empty) when the start is inverted, which
// the optimizer cannot recover from (it stalls and ends with an empty set, issue 29); `warning`
// when the greedy fit stopped above epsilon. Both say what to do instead.
struct MonopoleStartVerdict {
  std::string refusal, warning;
};
MonopoleStartVerdict JudgeMonopoleStart(const monopole::GreedyFitSummary& fit, double epsilon, int candidates,
                                        const monopole::StartCheck& start);

// The initial map for `target` (Target()): log-kernel and monopoles need a mesh target. Prints a
// warning on stderr when the start is inverted (L not lower inside than outside); for monopoles an
// inverted start is refused (quijibo::Error, JudgeMonopoleStart), and a fit above epsilon warned of.
InitialGuessResult InitialGuess(const TargetResult& target, const InitialGuessStageOptions& options);

// map.json, and for the fits roots.ply, the picture and monopoles.json, into `dir`.
void WriteInitialGuess(const InitialGuessResult& result, const std::string& dir);

}  // namespace quijibo::pipeline
