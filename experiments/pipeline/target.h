// The target stage: a mesh (normalized into the fractal frame, its signed distance on the target
// grid), a .qgrid from `quijibo sdf`, or an analytic shape, as the grid the energy fits.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "experiments/pipeline/settings.h"
#include "mesh/mesh_target.h"
#include "mesh/normalize.h"
#include "mesh/triangle_mesh.h"
#include "quijibo/frame.h"
#include "quijibo/grid.h"

namespace quijibo::pipeline {

struct TargetOptions {
  // Exactly one of the three.
  std::string mesh;      // .obj, .ply, .stl or .off
  std::string qgrid;     // a signed distance grid (fractal frame); its .frame.json is read when present
  std::string analytic;  // "sphere[:radius=R]", "torus[:major=R,minor=r]" (and, for the shape modulus,
                         // "disc", "hexagram")
  // Mesh targets: how the mesh becomes a target, with MeshTarget's defaults (mesh/mesh_target.h).
  int resolution = mesh::MeshTargetOptions{}.resolution;  // cells per axis of the target grid (also analytic)
  double padding = mesh::MeshTargetOptions{}.padding;
  double fractal_radius = mesh::MeshTargetOptions{}.fractal_radius;
  TargetBox box = mesh::MeshTargetOptions{}.box;
  // Mesh targets of the QUIJIBO method: where the fractal origin goes; unset for the other
  // methods (their unit frame has no fractal origin).
  std::optional<mesh::OriginPlacement> origin = mesh::MeshTargetOptions{}.origin;
  // With the origin inside: trap chooses fractal_radius (ScaleToTrap), fixed keeps the one given.
  mesh::FrameScale frame_scale = mesh::MeshTargetOptions{}.frame_scale;

  std::string kind() const;      // "mesh", "qgrid" or "analytic" ("" when none is set)
  std::string Validate() const;  // empty when valid
  static const Schema<TargetOptions>& Settings();
  // Missing settings keep `start`'s values (an unset `origin` stays unset and is not accepted).
  static TargetOptions FromJson(const JsonReader& r, const std::string& pointer, const std::filesystem::path& base,
                                const TargetOptions& start);
  static TargetOptions FromJson(const JsonReader& r, const std::string& pointer, const std::filesystem::path& base) {
    return FromJson(r, pointer, base, TargetOptions());
  }
  nlohmann::json ToJson() const;  // with "kind"
};

struct TargetResult {
  ScalarGrid grid;          // the signed distance on the target grid, fractal frame
  FractalFrame frame;       // user -> fractal frame (identity frame for analytic targets)
  std::string source;       // the mesh or .qgrid path, or "analytic:<spec>"
  mesh::TriangleMesh mesh;  // mesh targets: the mesh in the fractal frame
  mesh::MeshReadReport read_report;
  double sdf_seconds = 0;
};

// Builds the target grid. Mesh targets: NormalizationFor(padding, fractal_radius), the origin
// placed (PlaceOriginInside), SignedDistance on TargetGridFrame(resolution, frame, box). Throws
// quijibo::Error on an unreadable or invalid input.
TargetResult Target(const TargetOptions& options);

// target.qgrid and target.frame.json (FrameJsonPathFor) in `dir`, atomically.
void WriteTarget(const TargetResult& target, const TargetOptions& options, const std::string& dir);

}  // namespace quijibo::pipeline
