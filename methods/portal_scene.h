// Portal scenes (Schor and Kim 2024; docs/modulus-portals.md): a spec document ("quijibo-portals"
// version 1) read into a base map (a shape modulus, a QUIJIBO map file, or a map object of any kind,
// methods/map_kind.h, whose iteration defaults and region it takes) with its portals, and the
// Koch snowflake preset.
#pragma once

#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "methods/modulus.h"
#include "quijibo/quaternion_map.h"

namespace quijibo::mesh {

struct PortalScene {
  std::shared_ptr<const QuaternionMap> map;
  ModulusTarget target;  // for the default region (and phi)
  bool two_d = false;
  nlohmann::json spec;    // the spec, as read or as built by the preset
  VersorPolynomial poly;  // when generated (to write with --write-poly)
  // The spec's output defaults: iterations, escape radius, box (4 or 6 numbers; empty: none).
  int iterations = 20;
  double escape = 20.0;
  // The base map kind's inside convention, starting offset and capture (its n and escape radius are
  // `iterations` and `escape` above, which the spec may set).
  IterationOptions iteration;
  std::vector<double> box;
};

// Builds the base map and portals from a spec document; relative paths in it resolve against
// `source`'s folder; mesh targets and SDF masks are sampled at `sdf_resolution`. Throws
// quijibo::Error naming `source` and the JSON pointer.
PortalScene SceneFromSpec(const nlohmann::json& doc, const std::string& source, int sdf_resolution);

// The Koch snowflake preset (2024 Figs. 4, 7, 8): a hexagram of side 1 plus six portals; with
// `turbulent`, a noise versor (Fig. 8).
nlohmann::json KochSpec(double alpha, double beta, bool turbulent, double feather);

}  // namespace quijibo::mesh
