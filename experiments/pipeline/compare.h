// The compare stage: a QUIJIBO map against the shape modulus of the same target (fit time, psi of
// one application and of n iterates, IoU, Chamfer, meshes and slice pictures). `Compare` computes
// and returns them; `WriteCompare` (the command line) writes them.
#pragma once

#include <cmath>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "experiments/pipeline/modulus.h"
#include "experiments/pipeline/settings.h"
#include "mesh/triangle_mesh.h"
#include "quijibo/energy.h"
#include "util/image.h"
#include "quijibo/julia.h"
#include "quijibo/quaternion_map.h"

namespace quijibo::pipeline {

struct CompareOptions {
  std::string target;                  // .qgrid from `quijibo sdf` (fractal frame; its .frame.json is used)
  std::string map;                     // QUIJIBO map.json (fractal frame)
  ModulusStageOptions modulus;         // alpha, beta, params, versor poly (else generated in the target's box)
  IterationOptions modulus_iteration;  // the shape modulus's n and escape radius
  // QUIJIBO's: the same n as the shape modulus by default, the mesh stage's escape radius.
  IterationOptions quijibo_iteration{IterationOptions{}.iterations, JuliaOptions{}.escape_radius};
  std::optional<double> quijibo_seconds;        // QUIJIBO's fit time (else summary.json next to the map)
  double energy_alpha = EnergyOptions{}.alpha;  // tanh sharpness of psi
  std::string weights = "layer";                // weight field of psi: the reference's layer weights, or inverse
  int resolution = 128;                         // marching cubes cells along the grid box
  int samples = 100000;                         // surface samples per mesh for Chamfer
  int png_size = 512;                           // pixels of each slice picture

  std::string Validate() const;
  static const Schema<CompareOptions>& Settings();
};

// What one method gave: the slice picture and the mesh (fractal frame) that compare.json names.
struct CompareProducts {
  Image picture{1, 1};
  mesh::TriangleMesh mesh;
};

struct CompareResult {
  nlohmann::json report;  // compare.json: the settings and, per method, the figures
  std::string markdown;   // compare.md (`quijibo compare` prints it)
  CompareProducts quijibo, modulus;
};

// Computes the comparison. Writes nothing; throws quijibo::Error on invalid options or inputs.
CompareResult Compare(const CompareOptions& options);

// Writes compare.json, compare.md, quijibo.png, modulus.png, quijibo.ply and modulus.ply into
// `out_dir` (created; all or nothing).
void WriteCompare(const CompareResult& result, const std::string& out_dir);

}  // namespace quijibo::pipeline
