// `quijibo sdf`: mesh file -> normalized fractal frame -> signed distance on the target grid.
#pragma once

#include <string>

#include "mesh/frame_file.h"
#include "mesh/mesh_target.h"

namespace quijibo::mesh {

struct SdfCommandOptions {
  std::string input;          // mesh file (.obj, .ply, .stl, .off)
  std::string output;         // the .qgrid to write
  std::string vdb_output;     // optional .vdb of the same field ("" = none)
  bool quiet = false;         // no summary on standard output
  // How the mesh becomes a target (MeshTarget). The origin defaults to the box centre here, not
  // inside as in a run's target stage: a .qgrid also feeds the shape modulus and portals, whose unit
  // frame has no fractal origin; `--origin inside` gives the run's target.
  MeshTargetOptions target = [] {
    MeshTargetOptions t;
    t.origin = OriginPlacement::kCenter;
    return t;
  }();

  // Empty when valid, else what is wrong.
  std::string Validate() const;
};

// Reads and validates the mesh, makes it a target (MeshTarget), and writes
//   options.output                  the field (.qgrid, fractal frame)
//   FrameJsonPathFor(options.output)  the FractalFrame, so later stages can map back
//   options.vdb_output              if set, the field as an OpenVDB level set
// Everything is computed before anything is written, each file is written atomically, and if a
// later write fails the files this run already wrote are removed. Throws quijibo::Error.
void RunSdfCommand(const SdfCommandOptions& options);

}  // namespace quijibo::mesh
