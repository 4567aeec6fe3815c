#include "methods/portal_scene.h"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <functional>

#include "methods/map_kind.h"
#include "methods/modulus_target.h"
#include "util/error.h"
#include "util/io.h"
#include "util/json_reader.h"
#include "methods/portal.h"
#include "quijibo/rational_map.h"

namespace quijibo::mesh {

using nlohmann::json;

PortalScene SceneFromSpec(const json& doc, const std::string& source, int sdf_resolution) {
  JsonReader r(doc, source);
  if (!doc.is_object()) r.fail("", "expected a JSON object (a portal spec)");
  r.allow_keys("", {"format", "version", "description", "target", "map", "alpha", "beta", "origin_offset", "versor",
                    "iterations", "escape_radius", "box", "portals", "dimension"});
  if (r.string("/format") != "quijibo-portals") r.fail("/format", "expected \"quijibo-portals\"");
  if (r.integer("/version") != 1) r.fail("/version", "expected 1 (the only version so far)");
  const std::string dir = std::filesystem::path(source).parent_path().string();
  auto rel = [&](const std::string& p) {
    std::filesystem::path f(p);
    return (f.is_relative() && !dir.empty()) ? (std::filesystem::path(dir) / f).string() : p;
  };
  PortalScene s;
  s.spec = doc;
  const MaskGridLoader load_mask = MakeMaskGridLoader(sdf_resolution);
  std::shared_ptr<const QuaternionMap> base;
  std::function<double(const Quat&)> base_set;
  int default_iterations = 20;
  double default_escape = 20.0;
  if (r.has("/map") && r.at("/map").is_object()) {
    if (r.has("/target")) r.fail("/map", "give either \"map\" or \"target\", not both");
    const KindMap km = ReadKindMap(r, "/map", dir);
    base = km.map;
    base_set = km.base_set;
    for (int a = 0; a < 3; ++a)
      s.target.box_min[a] = km.center[a] - km.half_extent, s.target.box_max[a] = km.center[a] + km.half_extent;
    s.target.dimension = int(r.number_or("/dimension", 3));
    default_iterations = km.kind->iteration.iterations;
    default_escape = km.kind->iteration.escape_radius;
    s.bounded = km.kind->iteration.bounded;
  } else if (r.has("/map")) {
    if (r.has("/target")) r.fail("/map", "give either \"map\" (a QUIJIBO map) or \"target\", not both");
    auto rm = std::make_shared<RationalQuaternionMap>(ReadMap(rel(r.string("/map"))));
    base = rm;
    base_set = [rm](const Quat& q) { return rm->LogModulus(q); };
    s.target.box_min = {-1.5, -1.5, -1.5};
    s.target.box_max = {1.5, 1.5, 1.5};
    s.target.dimension = int(r.number_or("/dimension", 3));
  } else {
    const std::string t = r.string("/target");
    LoadedTarget lt = LoadModulusTarget(IsMeshFile(t) || HasExtension(t, ".qgrid") ? rel(t) : t, sdf_resolution);
    s.target = lt.target;
    if (r.has("/dimension")) s.target.dimension = int(r.integer("/dimension"));
    ShapeModulusOptions so;
    if (r.has("/alpha")) so.alpha = ParameterFieldFromJson(r, "/alpha", dir, load_mask);
    if (r.has("/beta")) so.beta = ParameterFieldFromJson(r, "/beta", dir, load_mask);
    if (r.has("/origin_offset")) so.origin_offset = ReadVec3(r, "/origin_offset");
    if (auto why = so.Validate(); !why.empty()) r.fail("", why);
    Versor v;
    if (r.has("/versor")) {
      r.allow_keys("/versor", {"polynomial", "generate", "noise"});
      if (r.has("/versor/polynomial")) {
        v.polynomial = ReadVersorPolynomial(rel(r.string("/versor/polynomial")));
      } else if (r.has("/versor/noise")) {
        r.allow_keys("/versor/noise", {"frequency", "octaves", "seed"});
        v.kind = Versor::Kind::kNoise;
        v.noise.frequency = r.number_or("/versor/noise/frequency", 4.0);
        v.noise.octaves = int(r.number_or("/versor/noise/octaves", 1));
        v.noise.seed = std::uint64_t(r.number_or("/versor/noise/seed", 1));
      } else {
        const std::string g = "/versor/generate";
        VersorGeneratorOptions go;
        go.box_min = s.target.box_min;
        go.box_max = s.target.box_max;
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
        s.poly = v.polynomial;
      }
    } else {
      VersorGeneratorOptions go;
      go.box_min = s.target.box_min;
      go.box_max = s.target.box_max;
      v.polynomial = GenerateVersorPolynomial(go);
      s.poly = v.polynomial;
    }
    auto sm = std::make_shared<ShapeModulusMap>(s.target, v, so);
    base = sm;
    // The base set's signed function, in distance units: phi + beta (= log|f| / alpha).
    auto beta = so.beta;
    auto offset = so.origin_offset;
    auto phi = s.target.phi;
    base_set = [phi, beta, offset](const Quat& q) {
      const Vec3 x{q.w - offset[0], q.x - offset[1], q.y - offset[2]};
      return phi(x) + beta(x);
    };
  }
  s.two_d = s.target.dimension == 2;
  std::vector<Portal> portals;
  const std::size_t n = r.has("/portals") ? r.array_size("/portals") : 0;
  for (std::size_t i = 0; i < n; ++i)
    portals.push_back(PortalFromJson(r, "/portals/" + std::to_string(i), dir, load_mask));
  s.map = std::make_shared<PortalMap>(base, std::move(portals), base_set);
  s.iterations = int(r.number_or("/iterations", default_iterations));
  s.escape = r.number_or("/escape_radius", default_escape);
  if (r.has("/box")) {
    const std::size_t k = r.array_size("/box");
    if (k != 4 && k != 6) r.fail("/box", "expected 4 (2D) or 6 (3D) numbers");
    for (std::size_t i = 0; i < k; ++i) s.box.push_back(r.number("/box/" + std::to_string(i)));
  }
  return s;
}

json KochSpec(double alpha, double beta, bool turbulent, double feather) {
  json portals = json::array();
  for (const Portal& p : KochPortals(1.0, feather)) portals.push_back(PortalToJson(p));
  json spec = {
      {"format", "quijibo-portals"},
      {"version", 1},
      {"description", std::string("Koch snowflake (2024 paper Figs. 4, 7") + (turbulent ? ", 8: turbulent)" : ")")},
      {"target", "hexagram:size=1"},
      {"alpha", alpha},
      {"beta", beta},
      {"iterations", 30},
      {"escape_radius", 20.0},
      {"box", {-0.62, -0.62, 0.62, 0.62}},
      {"portals", portals}};
  if (turbulent)
    spec["versor"] = {{"noise", {{"frequency", 6.0}, {"octaves", 2}, {"seed", 1}}}};
  else
    spec["versor"] = {{"generate", {{"roots", 10}, {"min_power", 2}, {"max_power", 12}, {"seed", 1}}}};
  return spec;
}

}  // namespace quijibo::mesh
