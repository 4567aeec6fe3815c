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
  // The map of the object at `pointer` (keys already checked against `keys`) and, when it has one,
  // its own region; relative paths against `dir`. Errors through r.fail (JSON pointer).
  std::function<KindMap(const JsonReader& r, const std::string& pointer, const std::string& dir)> read;
};

// Every kind, in kinds.inc's order.
const std::vector<MapKind>& MapKinds();
// The kind of that name; throws quijibo::Error listing the kinds when there is none.
const MapKind& FindMapKind(const std::string& name);

struct KindMap {
  const MapKind* kind = nullptr;
  std::shared_ptr<const QuaternionMap> map;
  Vec3 center{0, 0, 0};      // the default region: center +- half_extent
  double half_extent = 0.0;  // 0: the kind's
  // s(q) < 0 inside the map's one-step set (portals' exclude_base); unset: log|F(q)|.
  std::function<double(const Quat&)> base_set;
};
// Reads the map object at `pointer` ({"kind": ..., the kind's keys}).
KindMap ReadKindMap(const JsonReader& r, const std::string& pointer, const std::string& dir);

// Each kind's name, help, keys and defaults (`quijibo settings`, docs).
nlohmann::json DescribeMapKinds();

}  // namespace quijibo
