// Map kind "rational": a QUIJIBO map (map.json, 2015 Eqns 4 and 8) iterated in log-polar form
// (quijibo/julia.h), with the mesh stage's detail, iteration frame and root translation
// (MakeIteratedQuaternionMap, quijibo/julia_setup.h):
//   {"kind": "rational", "file": "map.json", "detail": percent (default 0.25, the mesh stage's),
//    "iteration_frame": "map" or "reference", "translate": [x, y, z(, k)],
//    "translate_potential": L at -t (with "translate" as its direction, default z), "capture": radius}
// The region is the map's normalized cube in its iteration frame. A translated map moves its roots
// and its samples by t (IterationOptions::offset), as `quijibo mesh --translate` does.
#include <filesystem>

#include "methods/map_kind.h"
#include "quijibo/julia.h"
#include "quijibo/julia_setup.h"
#include "quijibo/rational_map.h"
#include "util/error.h"

namespace quijibo {

MapKind MapKind_rational() {
  MapKind k;
  k.name = "rational";
  k.help = "a QUIJIBO map: \"file\" map.json, \"detail\" percent (default 0.25), \"iteration_frame\" map or "
           "reference, \"translate\" [x, y, z(, k)], \"translate_potential\" L at -t, \"capture\" radius";
  k.keys = {"file", "detail", "iteration_frame", "translate", "translate_potential", "capture"};
  const JuliaOptions defaults;  // the mesh stage's n and escape radius
  k.iteration.iterations = defaults.iterations;
  k.iteration.escape_radius = defaults.escape_radius;
  k.read = [iteration = k.iteration](const JsonReader& r, const std::string& p, const std::string& dir) {
    std::filesystem::path file = r.string(p + "/file");
    if (file.is_relative() && !dir.empty()) file = std::filesystem::path(dir) / file;
    JuliaSetupOptions setup;
    setup.detail = r.number_or(p + "/detail", kSmoothDetail);
    if (!(setup.detail >= 0 && setup.detail <= 100)) r.fail(p + "/detail", "expected a number in [0, 100]");
    const std::string frame = r.string_or(p + "/iteration_frame", "map");
    if (frame != "map" && frame != "reference") r.fail(p + "/iteration_frame", "expected \"map\" or \"reference\"");
    setup.frame = ParseIterationFrame(frame);
    if (r.has(p + "/translate")) {
      const std::size_t n = r.array_size(p + "/translate");
      if (n != 3 && n != 4) r.fail(p + "/translate", "expected [x, y, z] or [x, y, z, k]");
      std::vector<double> t;
      for (std::size_t a = 0; a < n; ++a) t.push_back(r.number(p + "/translate/" + std::to_string(a)));
      setup.translate = t;
    }
    if (r.has(p + "/translate_potential")) {
      const double L = r.number(p + "/translate_potential");
      if (!(L >= kTranslatePotentialRange.lo && L < kTranslatePotentialRange.hi))
        r.fail(p + "/translate_potential", "expected a number in [-1000, 0)");
      setup.translate_potential = L;
    }
    setup.julia.capture_radius = r.number_or(p + "/capture", 0.0);
    if (!(setup.julia.capture_radius >= 0 && setup.julia.capture_radius < 1))
      r.fail(p + "/capture", "expected a number in [0, 1)");
    IteratedQuaternionMap it;
    try {
      it = MakeIteratedQuaternionMap(ReadMap(file.string()), setup, iteration);
    } catch (const Error& e) {
      r.fail(p, e.what());
    }
    KindMap m;
    m.map = it.map;
    m.iteration = it.iteration;
    // The one-step set in sampling coordinates: L at the translated start (the untranslated set).
    m.base_set = [rm = it.map, offset = it.iteration.offset](const Quat& q) { return rm->LogModulus(q + offset); };
    m.center = it.center;
    m.half_extent = it.half_extent;
    return m;
  };
  return k;
}

}  // namespace quijibo
