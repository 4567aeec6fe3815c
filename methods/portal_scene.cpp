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
    s.iteration = *km.iteration;
    default_iterations = km.iteration->iterations;
    default_escape = km.iteration->escape_radius;
  } else if (r.has("/map")) {
    if (r.has("/target")) r.fail("/map", "give either \"map\" (a QUIJIBO map) or \"target\", not both");
    auto rm = std::make_shared<RationalQuaternionMap>(ReadMap(rel(r.string("/map"))));
    base = rm;
    base_set = [rm](const Quat& q) { return rm->LogModulus(q); };
    s.target.box_min = {-1.5, -1.5, -1.5};
    s.target.box_max = {1.5, 1.5, 1.5};
    s.target.dimension = int(r.number_or("/dimension", 3));
  } else {
    const ModulusMap mm = ReadModulusMap(r, "", dir, sdf_resolution);
    s.target = mm.target.target;
    if (mm.versor_generated) s.poly = mm.versor.polynomial;
    base = mm.map;
    base_set = mm.base_set;
  }
  s.two_d = s.target.dimension == 2;
  s.map = std::make_shared<PortalMap>(base, PortalsFromJson(r, "/portals", dir, load_mask), base_set);
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
