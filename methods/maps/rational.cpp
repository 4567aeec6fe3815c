// Map kind "rational": a QUIJIBO map (map.json, 2015 Eqns 4 and 8) iterated in log-polar form
// (quijibo/julia.h), with the mesh stage's detail and iteration frame (MakeJuliaSetup).
//   {"kind": "rational", "file": "map.json", "detail": percent (default 0.25, the mesh stage's),
//    "iteration_frame": "map" or "reference"}
// The region is the map's normalized cube in its iteration frame. The root translation and the
// other transforms of the sampling are the mesh stage's (`quijibo mesh`).
#include <filesystem>

#include "methods/map_kind.h"
#include "quijibo/julia.h"
#include "quijibo/julia_setup.h"
#include "quijibo/rational_map.h"

namespace quijibo {

MapKind MapKind_rational() {
  MapKind k;
  k.name = "rational";
  k.help = "a QUIJIBO map: \"file\" map.json, \"detail\" percent (default 0.25), \"iteration_frame\" map or reference";
  k.keys = {"file", "detail", "iteration_frame"};
  const JuliaOptions defaults;  // the mesh stage's n and escape radius
  k.iteration.iterations = defaults.iterations;
  k.iteration.escape_radius = defaults.escape_radius;
  k.read = [](const JsonReader& r, const std::string& p, const std::string& dir) {
    std::filesystem::path file = r.string(p + "/file");
    if (file.is_relative() && !dir.empty()) file = std::filesystem::path(dir) / file;
    const double detail = r.number_or(p + "/detail", kSmoothDetail);
    if (!(detail >= 0 && detail <= 100)) r.fail(p + "/detail", "expected a number in [0, 100]");
    const std::string frame = r.string_or(p + "/iteration_frame", "map");
    if (frame != "map" && frame != "reference") r.fail(p + "/iteration_frame", "expected \"map\" or \"reference\"");
    JuliaSetupOptions setup;
    setup.frame = ParseIterationFrame(frame);
    setup.detail = detail;
    const RationalMap map = MakeJuliaSetup(ReadMap(file.string()), setup).map;
    auto rm = std::make_shared<RationalQuaternionMap>(map);
    KindMap m;
    m.map = rm;
    m.base_set = [rm](const Quat& q) { return rm->LogModulus(q); };
    m.center = map.frame.box_center();
    m.half_extent = map.frame.fractal_radius / 2;
    return m;
  };
  return k;
}

}  // namespace quijibo
