// A mesh as a target: the user's mesh normalized into the fractal frame, its fractal origin
// placed, and its signed distance on the target grid. The one way a mesh becomes a target grid
// (`quijibo sdf` and the pipeline's target stage both call MeshTarget).
#pragma once

#include <string>

#include "mesh/normalize.h"
#include "mesh/sdf.h"
#include "mesh/triangle_mesh.h"
#include "quijibo/frame.h"
#include "quijibo/grid.h"

namespace quijibo::mesh {

struct MeshTargetOptions {
  int resolution = kDefaultTargetResolution;  // n: the grid has n^3 cells (TargetGridFrame)
  double padding = FractalFrame{}.padding;    // normalization padding, in [0, 0.5)
  double fractal_radius = FractalFrame{}.fractal_radius;  // > 0; with kTrap, chosen instead
  TargetBox box = TargetBox::kUnitCube;        // the grid's box (quijibo/frame.h)
  // Where the fractal origin goes. QUIJIBO's default is inside (orbits are trapped at the origin);
  // the shape modulus and portals have no fractal origin and need kCenter (the unit frame).
  OriginPlacement origin = OriginPlacement::kInside;
  FrameScale frame_scale = FrameScale::kTrap;  // used with the origin inside
  SdfOptions sdf;                              // sign policy (sdf.name is set to the mesh's name)

  // Empty when valid, else what is wrong.
  std::string Validate() const;
};

struct MeshTargetResult {
  FractalFrame frame;    // user -> fractal frame
  TriangleMesh mesh;     // the mesh in the fractal frame
  ScalarGrid grid;       // its signed distance on TargetGridFrame(resolution, frame, box)
  SdfSummary summary;    // SignedDistance's summary
};

// `user_mesh` (the user's coordinates, as read by ReadMesh) as a target:
//   frame  NormalizationFor(padding, fractal_radius); with origin kInside, PlaceOriginInside and,
//          with frame_scale kTrap, ScaleToTrap
//   mesh   ToFractalFrame(user_mesh, frame)
//   grid   SignedDistance(mesh, TargetGridFrame(resolution, frame, box), sdf)
// `name` names the mesh in errors. Throws quijibo::Error on invalid options or a mesh that bounds
// nothing (SignedDistance's refusals).
MeshTargetResult MeshTarget(const TriangleMesh& user_mesh, const std::string& name, const MeshTargetOptions& options);

}  // namespace quijibo::mesh
