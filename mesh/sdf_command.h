// `quijibo sdf`: mesh file -> normalized fractal frame -> signed distance on the target grid.
#pragma once

#include <string>

#include "mesh/normalize.h"
#include "mesh/sdf.h"
#include "quijibo/frame.h"

namespace quijibo::mesh {

struct SdfCommandOptions {
  std::string input;          // mesh file (.obj, .ply, .stl, .off)
  std::string output;         // the .qgrid to write
  std::string vdb_output;     // optional .vdb of the same field ("" = none)
  int resolution = kDefaultTargetResolution;  // n: the grid has n^3 cells (TargetGridFrame)
  double padding = FractalFrame{}.padding;  // normalization padding, in [0, 0.5)
  double fractal_radius = FractalFrame{}.fractal_radius;
  TargetBox box = TargetBox::kUnitCube;  // the grid's box (quijibo/frame.h)
  OriginPlacement origin = OriginPlacement::kCenter;  // the fractal origin (mesh/normalize.h)
  FrameScale frame_scale = FrameScale::kTrap;  // with the origin inside (mesh/normalize.h)
  bool quiet = false;         // no summary on standard output
  SdfOptions sdf;             // sign policy (sdf.name is set to the input path)

  // Empty when valid, else what is wrong.
  std::string Validate() const;
};

// Reads and validates the mesh, normalizes it (NormalizationFor), builds the grid with
// TargetGridFrame(resolution, frame, box), computes SignedDistance, and writes
//   options.output                  the field (.qgrid, fractal frame)
//   FrameJsonPathFor(options.output)  the FractalFrame, so later stages can map back
//   options.vdb_output              if set, the field as an OpenVDB level set
// Everything is computed before anything is written, each file is written atomically, and if a
// later write fails the files this run already wrote are removed. Throws quijibo::Error.
void RunSdfCommand(const SdfCommandOptions& options);

// "<dir>/bunny.qgrid" -> "<dir>/bunny.frame.json" (the extension, if any, is replaced).
std::string FrameJsonPathFor(const std::string& qgrid_path);

// The frame file: {"format":"quijibo-frame","version":1,"fractal_radius":..,"padding":..,
// "scale":..,"translation":[..],"source_mesh":..,"resolution":..}.
void WriteFrameJson(const std::string& path, const FractalFrame& frame,
                    const std::string& source_mesh, int resolution);
FractalFrame ReadFrameJson(const std::string& path);

// The one check of every command that takes a map and a target grid: throws quijibo::Error,
// naming both files and the fields that differ, when the grid's frame (its .frame.json; a grid
// without one, such as an analytic target's, is in the default frame) is not the map's.
void CheckSameFrame(const FractalFrame& map_frame, const std::string& map_path, const std::string& target_path);
// The same with the target's frame at hand (`target_frame_source` names where it comes from).
void CheckSameFrame(const FractalFrame& map_frame, const std::string& map_path, const FractalFrame& target_frame,
                    const std::string& target, const std::string& target_frame_source);

}  // namespace quijibo::mesh
