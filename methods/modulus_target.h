// Targets of the shape modulus and portals (docs/modulus-portals.md) in the unit frame: a mesh
// normalized as the authors do (bounding box centred at the origin, longest side 100/110) with its
// signed distance on [-0.5, 0.5]^3, a .qgrid from `quijibo sdf` mapped in with its frame file, or an
// analytic shape; SDF masks made from meshes the same way, and --params files.
#pragma once

#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "mesh/triangle_mesh.h"
#include "util/settings.h"
#include "quijibo/grid.h"
#include "methods/mask.h"
#include "methods/modulus.h"

namespace quijibo::mesh {

// .obj, .ply, .stl or .off (any case).
bool IsMeshFile(const std::string& path);

// The cells of a mesh's SDF in the unit frame (UnitFrameMeshSdf), a setting of the shape modulus'
// and the portals' stages, defined once: Schema<O>().With(UnitSdfResolutionSetting(ref)).
inline constexpr int kDefaultUnitSdfResolution = 100;  // the 2023 code's sdfGen resolution
template <class Ref>
auto UnitSdfResolutionSetting(Ref ref) {
  return [ref]<class O>(Schema<O>& s) {
    s.Integer("sdf_resolution", "--sdf-resolution", "Mesh targets and SDF masks: SDF cells on [-0.5,0.5]^3", ref, 8,
              2048);
  };
}

// A mesh in the unit frame and its signed distance on the cube [-0.5, 0.5]^3 at `sdf_resolution`
// cells; the unit-frame mesh, the scale and the bounding box's centre go to the pointers given.
std::shared_ptr<ScalarGrid> UnitFrameMeshSdf(const std::string& path, int sdf_resolution, TriangleMesh* unit_mesh,
                                             double* scale, Vec3* center);

// What a loaded target is and how it maps to the unit frame.
struct LoadedTarget {
  ModulusTarget target;
  std::shared_ptr<ScalarGrid> grid;  // the SDF, when there is one
  double unit_per_grid = 1.0;        // unit-frame length per grid-frame length
  // Unit-frame length per length unit of the target's file: a mesh's normalization scale, a
  // .qgrid's unit_per_grid, 1 for analytic targets (the units the authors' SDF would hold).
  double unit_per_source = 1.0;
  TriangleMesh mesh_unit;            // the target mesh in the unit frame (mesh targets only)
  nlohmann::json info = nlohmann::json::object();
};

// A mesh (its SDF at `sdf_resolution`), a .qgrid (fractal frame, mapped into the unit frame with
// its frame file) or an analytic target ("sphere", "disc", "hexagram[:size=S]").
LoadedTarget LoadModulusTarget(const std::string& spec, int sdf_resolution);

// The grid of an "sdf" mask: a .qgrid as is; a mesh (.obj/.ply/.stl/.off) normalized like a mesh
// target with its signed distance on [-0.5, 0.5]^3 at `sdf_resolution` cells, so a mask made from
// the target's own mesh lines up with it. Meshes are read once per loader (cached by path).
MaskGridLoader MakeMaskGridLoader(int sdf_resolution);

// A --params file: {"alpha": A, "beta": B, "origin_offset": [ox, oy, oz]}, A and B numbers or
// parameter fields (methods/mask.h). Keys present override `so`. Throws quijibo::Error naming the
// file and JSON pointer.
void ReadModulusParams(const std::string& path, ShapeModulusOptions& so, int sdf_resolution);

}  // namespace quijibo::mesh
