// Targets of the shape modulus and portals (docs/modulus-portals.md) in the unit frame: a mesh
// normalized as the authors do (bounding box centred at the origin, longest side 100/110) with its
// signed distance on [-0.5, 0.5]^3, a .qgrid from `quijibo sdf` mapped in with its frame file, or an
// analytic shape; SDF masks made from meshes the same way, and --params files.
#pragma once

#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

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
inline constexpr int kMinUnitSdfResolution = 8, kMaxUnitSdfResolution = 2048;
template <class Ref>
auto UnitSdfResolutionSetting(Ref ref) {
  return [ref]<class O>(Schema<O>& s) {
    s.Integer("sdf_resolution", "--sdf-resolution", "Mesh targets and SDF masks: SDF cells on [-0.5,0.5]^3", ref,
              kMinUnitSdfResolution, kMaxUnitSdfResolution);
  };
}
// The same setting as a map object's key (the map kinds "modulus" and "portals"): `fallback` when absent.
int ReadUnitSdfResolution(const JsonReader& r, const std::string& pointer, int fallback = kDefaultUnitSdfResolution);

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

// A versor as a map object gives it: {"polynomial": a file or the polynomial's JSON inline},
// {"generate": {"roots", "min_power", "max_power", "integer_powers", "seed"}} (roots in `target`'s
// box) or {"noise": {"frequency", "octaves", "seed"}}; no versor (`pointer` absent): a polynomial
// generated with the defaults. `generated` (if given) tells whether it was generated.
Versor ReadVersor(const JsonReader& r, const std::string& pointer, const std::string& dir, const ModulusTarget& target,
                  bool* generated = nullptr);
// The versor as ReadVersor reads it back: the polynomial inline, or the noise.
nlohmann::json VersorToJson(const Versor& v);

// A shape modulus map and what it was made of: the one construction of the map kind "modulus"
// (methods/maps/modulus.cpp), the modulus stage and a portal spec's shape modulus base.
struct ModulusMap {
  LoadedTarget target;  // as iterated: its dimension (2: the complex plane), the authors' frame applied
  int sdf_resolution = kDefaultUnitSdfResolution;  // of mesh targets and SDF masks
  Versor versor;
  bool versor_generated = false;
  ShapeModulusOptions shape;
  std::optional<AuthorsFrame> authors;
  std::shared_ptr<const ShapeModulusMap> map;
  // The base set's signed function in distance units, phi + beta (= log|f| / alpha): portals'
  // exclude_base.
  std::function<double(const Quat&)> base_set;
};

// The map of `target` (its dimension as it is to be drawn) with `versor` and `shape`; with
// `authors` (its unit_scale set), the target is read as the authors' code reads it
// (InAuthorsFrame), alpha and beta being already this toolkit's (AuthorsParameters).
ModulusMap MakeModulusMap(LoadedTarget target, int sdf_resolution, Versor versor, const ShapeModulusOptions& shape,
                          const std::optional<AuthorsFrame>& authors);

// The keys of a shape modulus map object besides "kind" (ReadModulusMap); a portal spec's shape
// modulus base has the first six at its top level.
inline const std::vector<std::string> kModulusMapKeys = {"target", "alpha", "beta", "origin_offset", "versor",
                                                         "dimension", "sdf_resolution", "authors_frame"};
// The object at `pointer`: "target" (a mesh or .qgrid relative to `dir`, or an analytic shape),
// "dimension" (2 or 3; default the target's), "alpha", "beta" (numbers or parameter fields),
// "origin_offset", "versor" (ReadVersor), "sdf_resolution" (default `sdf_resolution`) and
// "authors_frame" {"sdf_resolution", "nodes"}. Errors through r.fail (JSON pointer).
ModulusMap ReadModulusMap(const JsonReader& r, const std::string& pointer, const std::string& dir,
                          int sdf_resolution = kDefaultUnitSdfResolution);
// The map object ReadModulusMap reads back to the same map ({"kind": "modulus", ...}): files as
// absolute paths (SDF masks of alpha and beta relative to `mask_dir`), the versor inline.
nlohmann::json ModulusMapToJson(const ModulusMap& m, const std::string& mask_dir);

// A --params file: {"alpha": A, "beta": B, "origin_offset": [ox, oy, oz]}, A and B numbers or
// parameter fields (methods/mask.h). Keys present override `so`. Throws quijibo::Error naming the
// file and JSON pointer.
void ReadModulusParams(const std::string& path, ShapeModulusOptions& so, int sdf_resolution);

}  // namespace quijibo::mesh
