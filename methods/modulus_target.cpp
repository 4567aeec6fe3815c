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
namespace fs = std::filesystem;

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

int ReadUnitSdfResolution(const JsonReader& r, const std::string& p, int fallback) {
  if (!r.has(p)) return fallback;
  const long long n = r.integer(p);
  if (n < kMinUnitSdfResolution || n > kMaxUnitSdfResolution)
    r.fail(p, "expected an integer in [" + std::to_string(kMinUnitSdfResolution) + ", " +
                  std::to_string(kMaxUnitSdfResolution) + "], found " + std::to_string(n));
  return int(n);
}

Versor ReadVersor(const JsonReader& r, const std::string& p, const std::string& dir, const ModulusTarget& target,
                  bool* generated) {
  Versor v;
  if (generated) *generated = false;
  auto rel = [&](const std::string& f) {
    const fs::path path(f);
    return (path.is_relative() && !dir.empty()) ? (fs::path(dir) / path).string() : f;
  };
  if (r.has(p)) r.allow_keys(p, {"polynomial", "generate", "noise"});
  if (r.has(p + "/polynomial")) {
    if (r.at(p + "/polynomial").is_object())
      v.polynomial = VersorPolynomialFromJson(r.at(p + "/polynomial"), r.source() + " at " + p + "/polynomial");
    else
      v.polynomial = ReadVersorPolynomial(rel(r.string(p + "/polynomial")));
    return v;
  }
  if (r.has(p + "/noise")) {
    r.allow_keys(p + "/noise", {"frequency", "octaves", "seed"});
    v.kind = Versor::Kind::kNoise;
    v.noise.frequency = r.number_or(p + "/noise/frequency", 4.0);
    v.noise.octaves = int(r.number_or(p + "/noise/octaves", 1));
    v.noise.seed = std::uint64_t(r.number_or(p + "/noise/seed", 1));
    return v;
  }
  const std::string g = p + "/generate";
  VersorGeneratorOptions go;
  go.box_min = target.box_min;
  go.box_max = target.box_max;
  if (r.has(g)) {
    r.allow_keys(g, {"roots", "min_power", "max_power", "integer_powers", "seed"});
    go.roots = int(r.number_or(g + "/roots", go.roots));
    go.min_power = r.number_or(g + "/min_power", go.min_power);
    go.max_power = r.number_or(g + "/max_power", go.max_power);
    go.integer_powers = r.boolean_or(g + "/integer_powers", true);
    go.seed = std::uint64_t(r.number_or(g + "/seed", 1));
  }
  if (auto why = go.Validate(); !why.empty()) r.fail(g, why);
  v.polynomial = GenerateVersorPolynomial(go);
  if (generated) *generated = true;
  return v;
}

json VersorToJson(const Versor& v) {
  if (v.kind == Versor::Kind::kNoise)
    return {{"noise", {{"frequency", v.noise.frequency}, {"octaves", v.noise.octaves}, {"seed", v.noise.seed}}}};
  return {{"polynomial", VersorPolynomialToJson(v.polynomial)}};
}

ModulusMap MakeModulusMap(LoadedTarget target, int sdf_resolution, Versor versor, const ShapeModulusOptions& shape,
                          const std::optional<AuthorsFrame>& authors) {
  ModulusMap m;
  if (authors) target.target = InAuthorsFrame(target.target, *authors);
  m.target = std::move(target);
  m.sdf_resolution = sdf_resolution;
  m.versor = std::move(versor);
  m.shape = shape;
  m.authors = authors;
  m.map = std::make_shared<ShapeModulusMap>(m.target.target, m.versor, m.shape);
  auto beta = shape.beta;
  auto offset = shape.origin_offset;
  auto phi = m.target.target.phi;
  m.base_set = [phi, beta, offset](const Quat& q) {
    const Vec3 x{q.w - offset[0], q.x - offset[1], q.y - offset[2]};
    return phi(x) + beta(x);
  };
  return m;
}

ModulusMap ReadModulusMap(const JsonReader& r, const std::string& p, const std::string& dir, int sdf_resolution) {
  auto rel = [&](const std::string& f) {
    const fs::path path(f);
    return (path.is_relative() && !dir.empty()) ? (fs::path(dir) / path).string() : f;
  };
  sdf_resolution = ReadUnitSdfResolution(r, p + "/sdf_resolution", sdf_resolution);
  const MaskGridLoader load_mask = MakeMaskGridLoader(sdf_resolution);
  const std::string t = r.string(p + "/target");
  LoadedTarget lt = LoadModulusTarget(IsMeshFile(t) || HasExtension(t, ".qgrid") ? rel(t) : t, sdf_resolution);
  if (r.has(p + "/dimension")) {
    const long long d = r.integer(p + "/dimension");
    if (d != 2 && d != 3) r.fail(p + "/dimension", "expected 2 (the complex plane) or 3, found " + std::to_string(d));
    lt.target.dimension = int(d);
  }
  ShapeModulusOptions so;
  if (r.has(p + "/alpha")) so.alpha = ParameterFieldFromJson(r, p + "/alpha", dir, load_mask);
  if (r.has(p + "/beta")) so.beta = ParameterFieldFromJson(r, p + "/beta", dir, load_mask);
  if (r.has(p + "/origin_offset")) so.origin_offset = ReadVec3(r, p + "/origin_offset");
  if (auto why = so.Validate(); !why.empty()) r.fail(p, why);
  bool generated = false;
  Versor v = ReadVersor(r, p + "/versor", dir, lt.target, &generated);  // roots in the target's own box
  std::optional<AuthorsFrame> authors;
  const std::string a = p + "/authors_frame";
  if (r.has(a)) {
    r.allow_keys(a, {"sdf_resolution", "nodes"});
    if (lt.target.dimension != 3) r.fail(a, "expected a 3D target (the authors' frame is 3D)");
    AuthorsFrame af;
    af.sdf_resolution = int(r.integer(a + "/sdf_resolution"));
    if (r.has(a + "/nodes")) af.nodes = int(r.integer(a + "/nodes"));
    af.unit_scale = lt.unit_per_source;
    if (auto why = af.Validate(); !why.empty()) r.fail(a, why);
    authors = af;
  }
  ModulusMap m = MakeModulusMap(std::move(lt), sdf_resolution, std::move(v), so, authors);
  m.versor_generated = generated;
  return m;
}

namespace {
// A parameter field's JSON with its SDF masks' files absolute (relative ones against `dir`).
json AbsoluteMaskFiles(json j, const std::string& dir) {
  if (j.is_object() && j.value("type", "") == "sdf" && j.contains("file") && j["file"].is_string()) {
    fs::path f = j["file"].get<std::string>();
    if (f.is_relative() && !dir.empty()) f = fs::path(dir) / f;
    j["file"] = fs::absolute(f).lexically_normal().string();
  }
  if (j.is_structured())
    for (auto& x : j) x = AbsoluteMaskFiles(x, dir);
  return j;
}
}  // namespace

json ModulusMapToJson(const ModulusMap& m, const std::string& mask_dir) {
  const json& info = m.target.info;
  const std::string kind = info.value("kind", "analytic");
  const std::string target = kind == "analytic" ? info.value("spec", m.target.target.name)
                                                : fs::absolute(info.value("file", m.target.target.name)).lexically_normal().string();
  const Vec3& o = m.shape.origin_offset;
  json j = {{"kind", "modulus"},  // methods/maps/modulus.cpp
            {"target", target},
            {"dimension", m.target.target.dimension},
            {"sdf_resolution", m.sdf_resolution},
            {"alpha", AbsoluteMaskFiles(ParameterFieldToJson(m.shape.alpha), mask_dir)},
            {"beta", AbsoluteMaskFiles(ParameterFieldToJson(m.shape.beta), mask_dir)},
            {"origin_offset", {o[0], o[1], o[2]}},
            {"versor", VersorToJson(m.versor)}};
  if (m.authors) j["authors_frame"] = {{"sdf_resolution", m.authors->sdf_resolution}, {"nodes", m.authors->node_count()}};
  return j;
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
