// The Julia-set stage: the Julia set of a map of any kind (methods/map_kind.h: a QUIJIBO map,
// q^d + c, ...) drawn in the complex plane (PNG) or meshed in 3D (PLY through the shared mesher),
// with the kind's iteration defaults and region unless the output says otherwise. The experiment
// method "julia" and `quijibo julia` (docs/map-kinds.md).
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "experiments/pipeline/product.h"
#include "experiments/pipeline/settings.h"

namespace quijibo::pipeline {

struct JuliaSetStageOptions {
  JuliaSetStageOptions() { output.format = "png"; }
  // The map: a file holding a map object ({"kind": ...}) or the object inline (paths resolved).
  std::string map_file;
  nlohmann::json map_inline;  // null unless inline
  ProductOutputOptions output;  // iterations, escape and box default to the kind's

  std::string Validate() const;
  static JuliaSetStageOptions FromJson(const JsonReader& r, const std::string& pointer,
                                       const std::filesystem::path& base);
  nlohmann::json ToJson() const;
  // The map document and the name messages and relative paths use.
  nlohmann::json MapDocument(std::string* source) const;
};

struct JuliaSetStageResult {
  Product product;
  nlohmann::json map;     // the map object, as used
  nlohmann::json report;  // julia.json (`quijibo julia` prints it)
};

// The set drawn (output.format png) or meshed (ply). Writes nothing; throws quijibo::Error.
JuliaSetStageResult JuliaSet(const JuliaSetStageOptions& options);

}  // namespace quijibo::pipeline
