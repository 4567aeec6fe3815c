#include "methods/modulus_target.h"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <map>

#include "mesh/sdf.h"
#include "mesh/frame_file.h"
#include "util/error.h"
#include "util/io.h"
#include "util/json_reader.h"

namespace quijibo::mesh {

using nlohmann::json;

bool IsMeshFile(const std::string& s) {
  return HasExtension(s, ".obj") || HasExtension(s, ".ply") || HasExtension(s, ".stl") || HasExtension(s, ".off");
}

// A mesh in the unit frame (bounding box centred at the origin, longest side 100/110: the authors'
// set-up) and its signed distance on the cube [-0.5, 0.5]^3 at `sdf_resolution` cells.
std::shared_ptr<ScalarGrid> UnitFrameMeshSdf(const std::string& path, int sdf_resolution, TriangleMesh* unit_mesh,
                                             double* scale, Vec3* center) {
  MeshReadReport rep;
  TriangleMesh mesh = ReadMesh(path, &rep);
  const BoundingBox bb = ComputeBoundingBox(mesh);
  double longest = 0;
  for (int a = 0; a < 3; ++a) longest = std::max(longest, bb.max[a] - bb.min[a]);
  if (!(longest > 0)) throw Error(path + ": the mesh's bounding box is a point");
  const double s = kUnitFrameLongestSide / longest;
  Vec3 c;
  for (int a = 0; a < 3; ++a) c[a] = 0.5 * (bb.min[a] + bb.max[a]);
  for (Vec3& v : mesh.vertices)
    for (int a = 0; a < 3; ++a) v[a] = s * (v[a] - c[a]);
  SdfOptions so;
  so.name = path;
  auto grid = std::make_shared<ScalarGrid>(SignedDistance(mesh, GridFrame::Cube(sdf_resolution, {0, 0, 0}, 1.0), so));
  if (unit_mesh) *unit_mesh = std::move(mesh);
  if (scale) *scale = s;
  if (center) *center = c;
  return grid;
}

LoadedTarget LoadModulusTarget(const std::string& spec, int sdf_resolution) {
  LoadedTarget t;
  if (IsMeshFile(spec)) {
    double s = 1;
    Vec3 c{0, 0, 0};
    t.grid = UnitFrameMeshSdf(spec, sdf_resolution, &t.mesh_unit, &s, &c);
    t.target = ModulusTargetFromUnitGrid(t.grid);
    t.unit_per_source = s;
    t.info = {{"kind", "mesh"},
              {"file", spec},
              {"unit_frame", {{"scale", s}, {"mesh_center", {c[0], c[1], c[2]}}}},
              {"sdf_resolution", sdf_resolution}};
  } else if (HasExtension(spec, ".qgrid")) {
    t.grid = std::make_shared<ScalarGrid>(ReadGrid(spec));
    FractalFrame f;
    const std::string frame_path = FrameJsonPathFor(spec);
    const bool have_frame = std::filesystem::exists(frame_path);
    if (have_frame) f = ReadFrameJson(frame_path);
    // The unit frame is centred on the box: a grid whose fractal origin was placed inside the shape
    // (`quijibo sdf --origin inside`, a run's target.qgrid) would be read shifted.
    if (!f.default_origin())
      throw Error(spec + ": its frame (" + frame_path + ") places the fractal origin inside the shape; the shape "
                  "modulus and portals need the box centre: make the grid with `quijibo sdf --origin center`, or give "
                  "the mesh itself");
    t.target = ModulusTargetFromGrid(t.grid, f.fractal_radius, f.padding, &t.unit_per_grid);
    t.unit_per_source = t.unit_per_grid;
    t.info = {{"kind", "qgrid"},
              {"file", spec},
              {"frame_file", have_frame ? frame_path : "(none: defaults)"},
              {"unit_per_fractal", t.unit_per_grid}};
  } else {
    t.target = AnalyticModulusTarget(spec);
    t.info = {{"kind", "analytic"}, {"spec", spec}};
  }
  t.target.name = spec;
  return t;
}

MaskGridLoader MakeMaskGridLoader(int sdf_resolution) {
  auto cache = std::make_shared<std::map<std::string, std::shared_ptr<const ScalarGrid>>>();
  return [cache, sdf_resolution](const std::string& path) -> std::shared_ptr<const ScalarGrid> {
    if (!IsMeshFile(path)) return std::make_shared<ScalarGrid>(ReadGrid(path));
    auto it = cache->find(path);
    if (it == cache->end())
      it = cache->emplace(path, UnitFrameMeshSdf(path, sdf_resolution, nullptr, nullptr, nullptr)).first;
    return it->second;
  };
}

void ReadModulusParams(const std::string& path, ShapeModulusOptions& so, int sdf_resolution) {
  const json doc = ParseJson(ReadFile(path), path);
  JsonReader r(doc, path);
  if (!doc.is_object()) r.fail("", "expected a JSON object");
  r.allow_keys("", {"alpha", "beta", "origin_offset"});
  const std::string dir = std::filesystem::path(path).parent_path().string();
  const MaskGridLoader load = MakeMaskGridLoader(sdf_resolution);
  if (r.has("/alpha")) so.alpha = ParameterFieldFromJson(r, "/alpha", dir, load);
  if (r.has("/beta")) so.beta = ParameterFieldFromJson(r, "/beta", dir, load);
  if (r.has("/origin_offset")) so.origin_offset = ReadVec3(r, "/origin_offset");
  if (auto why = so.Validate(); !why.empty()) r.fail("", why);
}

}  // namespace quijibo::mesh
