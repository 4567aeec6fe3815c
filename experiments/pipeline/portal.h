// The portal stage (Schor and Kim 2024; docs/modulus-portals.md): a portal scene (a spec, or the
// Koch snowflake preset) rendered in the complex plane (PNG) or meshed in 3D (PLY).
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "experiments/pipeline/product.h"
#include "experiments/pipeline/settings.h"
#include "methods/modulus_target.h"
#include "methods/portal_scene.h"

namespace quijibo::pipeline {

struct PortalStageOptions {
  PortalStageOptions() { output.format = "png"; }
  // The scene: a spec file, an inline spec (paths in it already resolved), or the Koch preset.
  std::string spec_file;
  nlohmann::json spec_inline;  // null unless inline
  bool koch = false;
  bool turbulent = false;       // with koch: alpha 30 and a noise versor (2024 Fig. 8)
  std::optional<double> alpha;  // overrides the spec's
  double feather = 0.005;       // with koch: feather of the portal edges
  int sdf_resolution = mesh::kDefaultUnitSdfResolution;  // UnitSdfResolutionSetting
  ProductOutputOptions output;  // iterations, escape and box default to the spec's

  std::string Validate() const;
  static const Schema<PortalStageOptions>& Settings();
  static PortalStageOptions FromJson(const JsonReader& r, const std::string& pointer, const std::filesystem::path& base,
                                     const PortalStageOptions& start);
  static PortalStageOptions FromJson(const JsonReader& r, const std::string& pointer,
                                     const std::filesystem::path& base) {
    return FromJson(r, pointer, base, PortalStageOptions());
  }
  nlohmann::json ToJson() const;
  // The spec document (the preset's, the file's or the inline one) with the alpha override, and
  // the name messages and relative paths use.
  nlohmann::json SpecDocument(std::string* source) const;
};

struct PortalStageResult {
  Product product;
  nlohmann::json spec;    // as used
  VersorPolynomial poly;  // the generated versor polynomial (no roots otherwise)
  nlohmann::json report;  // portal.json (`quijibo portal` prints it)
};

// The scene rendered or meshed to `out` (.png for 2D scenes, .ply for 3D). Writes nothing.
PortalStageResult Portal(const PortalStageOptions& options, const std::string& out);

// Writes the product to `out` and, when not empty, the spec used to `spec_out` and the generated
// versor polynomial to `poly_out`; all or nothing.
void WritePortal(const PortalStageResult& result, const std::string& out, const std::string& spec_out,
                 const std::string& poly_out);

}  // namespace quijibo::pipeline
