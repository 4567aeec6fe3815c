// Map kinds: every map the Julia-set engine iterates, read from one JSON object {"kind": ..., ...}
// (docs/map-kinds.md). A kind states how its map is read, the iteration defaults it is drawn with
// (n, escape radius, which set is the inside) and its default region, in one place: its own file in
// methods/maps/. The engine (the mesher's field, 2D images, the portal scenes' base map, the
// `julia` experiment method and `quijibo julia`) takes any kind through this interface.
//
// Adding a kind is three files: methods/maps/<name>.cpp (the map and its `MapKind`), one line
// QUIJIBO_MAP_KIND(<name>) in methods/maps/kinds.inc (its schema entry), and its test.
#pragma once

#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "quijibo/quaternion_map.h"
#include "util/json_reader.h"

namespace quijibo {

struct KindMap;

struct MapKind {
  std::string name;               // the JSON "kind"
  std::string help;               // one line: the map and its keys
  std::vector<std::string> keys;  // its object's keys besides "kind"
  IterationOptions iteration;     // its defaults: n, escape radius, inside convention
  double half_extent = 1.5;       // its default region: [-h, h] on every axis (2D: x, y)
  bool defaults_from_base = false;  // n, escape, inside and region are its base map's (portals)
  std::string region;               // how its maps choose their region, when not [-h, h]
  // The map of the object at `pointer` (keys already checked against `keys`) and, when it has them,
  // its own region and iteration defaults; relative paths against `dir`. Errors through r.fail (JSON pointer).
  std::function<KindMap(const JsonReader& r, const std::string& pointer, const std::string& dir)> read;
};

// Every kind, in kinds.inc's order.
const std::vector<MapKind>& MapKinds();
// The kind of that name; throws quijibo::Error listing the kinds when there is none.
const MapKind& FindMapKind(const std::string& name);

struct KindMap {
  const MapKind* kind = nullptr;
  std::shared_ptr<const QuaternionMap> map;
  // Its iteration defaults: set by ReadKindMap to the kind's unless the reader set the map's own
  // (portals: their base map's).
  std::optional<IterationOptions> iteration;
  Vec3 center{0, 0, 0};      // the default region: center +- half_extent
  double half_extent = 0.0;  // 0: the kind's
  // A region that is not that cube (the shape modulus: its target's box, grown), as a --box:
  // x0 y0 x1 y1 when `two_d`, else x0 y0 z0 x1 y1 z1; unset: the cube.
  std::function<std::vector<double>(bool two_d)> box;
  // s(q) < 0 inside the map's one-step set (portals' exclude_base); unset: log|F(q)|.
  std::function<double(const Quat&)> base_set;
  // The default region as a --box (x0 y0 x1 y1 when `two_d`, else x0 y0 z0 x1 y1 z1).
  std::vector<double> Region(bool two_d) const;
};
// Reads the map object at `pointer` ({"kind": ..., the kind's keys}).
KindMap ReadKindMap(const JsonReader& r, const std::string& pointer, const std::string& dir);
// Where a map document holds its map object: "" (it is one) or "/map" (a stage's report recording
// the map it drew, such as the modulus stage's modulus.json).
std::string MapObjectPointer(const nlohmann::json& doc);

// Each kind's name, help, keys and defaults (`quijibo settings`, docs).
nlohmann::json DescribeMapKinds();

}  // namespace quijibo
