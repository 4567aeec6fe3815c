// An experiment file (docs/experiments.md): one JSON document naming a method and the settings of
// each of its stages, read and validated completely (JSON-pointer errors) before anything runs.
#pragma once

#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "experiments/pipeline/energy.h"
#include "experiments/pipeline/initial.h"
#include "experiments/pipeline/julia_set.h"
#include "experiments/pipeline/mesh.h"
#include "experiments/pipeline/modulus.h"
#include "experiments/pipeline/optimize.h"
#include "experiments/pipeline/pictures.h"
#include "experiments/pipeline/portal.h"
#include "experiments/pipeline/target.h"

namespace quijibo::pipeline {

struct OutputsOptions {
  std::optional<std::string> folder;  // the results folder; unset: results/<name> (--out overrides)
  bool plot = true;                   // the convergence plot (needs gnuplot)
  bool report = true;                 // report.md
  bool report_html = true;            // report.html beside it (report_html.h); needs report
  static const Schema<OutputsOptions>& Settings();
};

struct Experiment {
  std::string path;  // the experiment file, absolute ("" when built in memory)
  std::string name;  // default: the file's name without .json
  std::string description;
  std::string method = "quijibo";  // "quijibo", "modulus", "portal" or "julia"
  // The default of every seed (monopole order and sampling, random map, generated versor).
  std::uint64_t seed = kDefaultSeed;
  std::optional<TargetOptions> target;  // required but for portal and julia
  // quijibo
  InitialGuessStageOptions initial;
  std::vector<OptimizeStageOptions> optimizers;  // at least one, unique names
  MeshStageOptions mesh;
  // The intricate surface of the same map (the triptych's (c), experiments/pipeline/triptych.h):
  // the mesh stage's settings with IntricateDefaults.
  MeshStageOptions intricate;
  // modulus, portal
  ModulusStageOptions modulus;
  PortalStageOptions portal;
  JuliaSetStageOptions julia;  // julia: a map of any kind (methods/map_kind.h)
  PicturesOptions pictures;
  OutputsOptions outputs;

  // Reads, validates and resolves an experiment file; throws quijibo::Error
  // "<file>: <JSON pointer>: <what>" on the first problem.
  static Experiment FromFile(const std::string& path);
  // The same from a document; paths resolve against `base`, messages name `source`.
  static Experiment FromJson(const nlohmann::json& doc, const std::string& source, const std::filesystem::path& base);
  // The resolved experiment: every default filled in, every path absolute (`quijibo run --check`,
  // experiment.resolved.json).
  nlohmann::json ToJson() const;
  // The optimizer run whose map the mesh and pictures use.
  const OptimizeStageOptions& chosen_optimizer() const;
};

// Every setting of an experiment, by section ("" the top level, "target", "optimizer",
// "optimizer/schedule" a pass of the JSON schedule form, "modulus/output", ...; "energy" the settings
// of `quijibo energy`, not a section of the file), as Schema::Describe
// gives them: what `quijibo settings` prints, docs/experiments.md's tables are generated from and the
// tests compare the command line's and Python's defaults and ranges with.
nlohmann::json DescribeSettings();

}  // namespace quijibo::pipeline
