// Map kind "portals": a map of any kind with portals (Schor and Kim 2024 Eqn 7; methods/portal.h):
//   {"kind": "portals", "base": {a map object}, "portals": [portal, ...] (PortalFromJson; none: the
//    base map), "sdf_resolution": cells of SDF masks made from meshes (default 100)}
// exclude_base cuts the base kind's set (KindMap::base_set: phi + beta for the shape modulus,
// log|R| for a QUIJIBO map). Drawn with the base map's iteration defaults, inside and region.
#include "methods/map_kind.h"
#include "methods/modulus_target.h"
#include "methods/portal.h"

namespace quijibo {

MapKind MapKind_portals() {
  MapKind k;
  k.name = "portals";
  k.help = "portals (2024) in a map: \"base\" a map object, \"portals\" [portal, ...], \"sdf_resolution\" of SDF "
           "masks (default 100); n, escape, inside and region: the base's";
  k.keys = {"base", "portals", "sdf_resolution"};
  k.defaults_from_base = true;
  k.read = [](const JsonReader& r, const std::string& p, const std::string& dir) {
    const KindMap base = ReadKindMap(r, p + "/base", dir);
    const int sdf_resolution = mesh::ReadUnitSdfResolution(r, p + "/sdf_resolution");
    std::vector<Portal> portals = PortalsFromJson(r, p + "/portals", dir, mesh::MakeMaskGridLoader(sdf_resolution));
    KindMap m;
    m.map = std::make_shared<PortalMap>(base.map, std::move(portals), base.base_set);
    m.iteration = base.iteration;
    m.center = base.center;
    m.half_extent = base.half_extent;
    m.box = base.box;
    return m;
  };
  return k;
}

}  // namespace quijibo
