// The output of the shape modulus and portal stages: the Julia set of a quaternion map in the
// complex plane (PNG) or meshed in 3D (PLY through the shared mesher), over a box in the unit frame.
#pragma once

#include <chrono>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "experiments/pipeline/settings.h"
#include "mesh/marching_cubes.h"
#include "mesh/triangle_mesh.h"
#include "util/image.h"
#include "methods/modulus.h"
#include "quijibo/quaternion_map.h"

namespace quijibo::pipeline {

struct ProductOutputOptions {
  std::string format = "ply";    // "ply" (3D mesh) or "png" (2D); a stage's default may differ
  mesh::MeshingOptions meshing;  // 3D: resolution and the mesher's settings (the box is set here)
  View2D view;                   // 2D: width (= height) in pixels (the region is set here)
  // Unset: the method's (the shape modulus: IterationOptions' defaults; portals: the spec's).
  std::optional<int> iterations;
  std::optional<double> escape;
  // The region, unit frame: x0 y0 x1 y1 (2D) or x0 y0 z0 x1 y1 z1 (3D); unset: the target's box
  // grown by 15 % of its longest side on every side (or the spec's).
  std::optional<std::vector<double>> box;

  std::string Validate() const;
  static const Schema<ProductOutputOptions>& Settings();
  static ProductOutputOptions FromJson(const JsonReader& r, const std::string& pointer,
                                       const std::filesystem::path& base, const ProductOutputOptions& start);
  static ProductOutputOptions FromJson(const JsonReader& r, const std::string& pointer,
                                       const std::filesystem::path& base) {
    return FromJson(r, pointer, base, ProductOutputOptions());
  }
  nlohmann::json ToJson() const;
};

struct Product {
  std::string kind;  // "png" or "ply"
  Image image{1, 1};
  mesh::TriangleMesh mesh;
  nlohmann::json report;  // sizes, region, evaluations, seconds
};

// Renders (2D) or meshes (3D) the field log|q_n| of `map` with `iteration` over the output's box
// (default: around `target`'s box). Writes nothing; throws quijibo::Error on invalid options.
Product Produce(std::shared_ptr<const QuaternionMap> map, const ProductOutputOptions& output,
                const IterationOptions& iteration, const ModulusTarget& target, bool two_d);

// Writes the product to `path` (.png for 2D, .ply for 3D; else an error).
void WriteProduct(const Product& product, const std::string& path);

// Files written by a stage, removed again if a later step fails (no partial output).
class Outputs {
 public:
  void Add(const std::string& path) { written_.push_back(path); }
  void Rollback();
  void Commit() { written_.clear(); }
  ~Outputs() { Rollback(); }

 private:
  std::vector<std::string> written_;
};

// Wall and CPU (user + system, this process) clocks, in seconds.
double WallSeconds();
double CpuSeconds();
// Wall seconds since t0 (steady clock).
double Since(std::chrono::steady_clock::time_point t0);

}  // namespace quijibo::pipeline
