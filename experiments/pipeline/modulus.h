// The shape modulus stage (Schor and Kim 2023; docs/modulus-portals.md): the Julia set of a
// target's shape modulus map, in the complex plane (PNG) or meshed in 3D (PLY).
#pragma once

#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "experiments/pipeline/product.h"
#include "experiments/pipeline/settings.h"
#include "methods/modulus.h"
#include "methods/modulus_target.h"

namespace quijibo::pipeline {

struct VersorOptions {
  VersorOptions() { generate.seed = kDefaultSeed; }
  std::optional<std::string> poly;  // a versor polynomial file; unset: one is generated
  VersorGeneratorOptions generate;  // roots, powers, seed (the box: the target's)
  double noise_frequency = 0;       // > 0: a noise versor of this frequency instead
  int noise_octaves = 1;

  static const Schema<VersorOptions>& Settings();
  // The versor for `target` (a generated polynomial's roots lie in the target's box).
  Versor Make(const ModulusTarget& target) const;
};

struct ModulusStageOptions {
  ModulusStageOptions() { output.format = "ply"; }
  ShapeModulusOptions shape;                  // alpha and beta as numbers (fields: `params`)
  std::optional<std::vector<double>> offset;  // origin translation ox oy oz (2023 Fig. 5)
  std::optional<std::string> params;          // alpha/beta fields and origin_offset (override the above)
  int sdf_resolution = mesh::kDefaultUnitSdfResolution;  // UnitSdfResolutionSetting
  VersorOptions versor;
  ProductOutputOptions output;
  bool two_d = false;              // the complex plane (slice z = 0 of a 3D target)
  // Read the target as the authors' code does, RES[, NODES] (NODES defaults to RES), and take
  // alpha and beta as their a and b (AuthorsParameters). Command line only: no experiment key.
  std::vector<int> authors_frame;

  std::string Validate() const;
  static const Schema<ModulusStageOptions>& Settings();
  static ModulusStageOptions FromJson(const JsonReader& r, const std::string& pointer,
                                      const std::filesystem::path& base, const ModulusStageOptions& start);
  static ModulusStageOptions FromJson(const JsonReader& r, const std::string& pointer,
                                      const std::filesystem::path& base) {
    return FromJson(r, pointer, base, ModulusStageOptions());
  }
  nlohmann::json ToJson() const;
};

struct ModulusStageResult {
  Product product;
  Versor versor;
  std::shared_ptr<const QuaternionMap> map;  // as drawn
  // The stage's report (modulus.json; `quijibo modulus` prints it); its "map" is the map object
  // {"kind": "modulus", ...} that draws the same set (`quijibo julia modulus.json`).
  nlohmann::json report;
};

// The shape modulus of `target` (a mesh, a .qgrid or an analytic shape: methods/modulus_target.h),
// rendered or meshed; `out` (.png or .ply) decides 2D or 3D with the options. Writes nothing.
ModulusStageResult Modulus(const std::string& target, const ModulusStageOptions& options, const std::string& out);

// Writes the product to `out` and, when not empty, the generated versor polynomial to `poly_out`;
// all or nothing.
void WriteModulus(const ModulusStageResult& result, const std::string& out, const std::string& poly_out);

}  // namespace quijibo::pipeline
