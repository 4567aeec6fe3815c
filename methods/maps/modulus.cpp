// Map kind "modulus": the shape modulus map (Schor and Kim 2023; methods/modulus.h), the map the
// modulus stage draws, read from what the stage writes or given inline:
//   {"kind": "modulus", "file": "modulus.json"}   the map a modulus stage drew (its report's "map")
//   {"kind": "modulus", "target": mesh, .qgrid or analytic shape, "alpha", "beta" (numbers or
//    parameter fields), "origin_offset", "versor" ({"polynomial": file or inline}, {"generate": ...}
//    or {"noise": ...}), "dimension" (2: the complex plane), "sdf_resolution", "authors_frame"}
// (mesh::ReadModulusMap, the one reader of a portal spec's shape modulus base too). Drawn with the
// stage's defaults: 3 iterations, escape radius 20, inside |q_n| < 1, over the target's box grown
// by 15 % of its longest side.
#include <filesystem>

#include "methods/map_kind.h"
#include "methods/modulus_target.h"
#include "util/io.h"

namespace quijibo {

MapKind MapKind_modulus() {
  MapKind k;
  k.name = "modulus";
  k.help = "the shape modulus (2023): \"file\" a modulus stage's report (modulus.json), or \"target\", \"alpha\", "
           "\"beta\", \"origin_offset\", \"versor\", \"dimension\", \"sdf_resolution\", \"authors_frame\"";
  k.keys = mesh::kModulusMapKeys;
  k.keys.push_back("file");
  k.iteration = IterationOptions{};  // the modulus stage's: 3 iterations, escape radius 20
  k.region = "the target's box grown by 15 % of its longest side";
  k.read = [](const JsonReader& r, const std::string& p, const std::string& dir) {
    if (r.has(p + "/file")) {
      for (const std::string& key : mesh::kModulusMapKeys)
        if (r.has(p + "/" + key)) r.fail(p + "/" + key, "expected no other key with \"file\"");
      std::filesystem::path file = r.string(p + "/file");
      if (file.is_relative() && !dir.empty()) file = std::filesystem::path(dir) / file;
      const nlohmann::json doc = ParseJson(ReadFile(file.string()), file.string());
      const JsonReader fr(doc, file.string());
      const std::string inner = MapObjectPointer(doc);
      if (fr.string_or(inner + "/kind", "") != "modulus")
        fr.fail(inner, "expected a shape modulus map {\"kind\": \"modulus\", ...} or a modulus stage's report "
                       "holding one (\"map\")");
      // One level of indirection: a file naming a file could name itself.
      if (fr.has(inner + "/file")) fr.fail(inner + "/file", "expected the map itself here, not another file");
      return ReadKindMap(fr, inner, file.parent_path().string());
    }
    const mesh::ModulusMap mm = mesh::ReadModulusMap(r, p, dir);
    KindMap m;
    m.map = mm.map;
    m.base_set = mm.base_set;
    const ModulusTarget target = mm.target.target;
    m.box = [target](bool two_d) { return ModulusRegion(target, two_d); };
    // The cube about the target's box (a portal scene's region for this base).
    double longest = 0;
    for (int a = 0; a < 3; ++a) {
      m.center[a] = 0.5 * (target.box_min[a] + target.box_max[a]);
      longest = std::max(longest, target.box_max[a] - target.box_min[a]);
    }
    m.half_extent = 0.5 * longest;
    return m;
  };
  return k;
}

}  // namespace quijibo
