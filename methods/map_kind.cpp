#include "methods/map_kind.h"

#include <cmath>

#include "util/error.h"

namespace quijibo {

#define QUIJIBO_MAP_KIND(name) MapKind MapKind_##name();
#include "methods/maps/kinds.inc"
#undef QUIJIBO_MAP_KIND

const std::vector<MapKind>& MapKinds() {
  static const std::vector<MapKind> kinds = {
#define QUIJIBO_MAP_KIND(name) MapKind_##name(),
#include "methods/maps/kinds.inc"
#undef QUIJIBO_MAP_KIND
  };
  return kinds;
}

namespace {
std::string KindList() {
  std::string list;
  for (const MapKind& k : MapKinds()) list += (list.empty() ? "" : ", ") + k.name;
  return list;
}
}  // namespace

const MapKind& FindMapKind(const std::string& name) {
  for (const MapKind& k : MapKinds())
    if (k.name == name) return k;
  throw Error("unknown map kind \"" + name + "\" (expected one of: " + KindList() + ")");
}

KindMap ReadKindMap(const JsonReader& r, const std::string& p, const std::string& dir) {
  if (!r.has(p) || !r.at(p).is_object())
    r.fail(p, "expected a map object {\"kind\": ..., ...} (kinds: " + KindList() + ")");
  const std::string name = r.string(p + "/kind");
  const MapKind* kind = nullptr;
  for (const MapKind& k : MapKinds())
    if (k.name == name) kind = &k;
  if (!kind) r.fail(p + "/kind", "expected one of " + KindList() + ", found \"" + name + "\"");
  std::vector<std::string> keys = kind->keys;
  keys.push_back("kind");
  r.allow_keys(p, keys);
  KindMap m = kind->read(r, p, dir);
  m.kind = kind;
  if (m.half_extent <= 0) m.half_extent = kind->half_extent;
  if (!m.iteration) m.iteration = kind->iteration;
  if (!m.base_set) {
    auto map = m.map;
    m.base_set = [map](const Quat& q) { return std::log(map->Apply(q).norm()); };
  }
  return m;
}

std::vector<double> KindMap::Region(bool two_d) const {
  if (box) return box(two_d);
  const Vec3& c = center;
  const double h = half_extent;
  return two_d ? std::vector<double>{c[0] - h, c[1] - h, c[0] + h, c[1] + h}
               : std::vector<double>{c[0] - h, c[1] - h, c[2] - h, c[0] + h, c[1] + h, c[2] + h};
}

std::string MapObjectPointer(const nlohmann::json& doc) {
  if (doc.is_object() && !doc.contains("kind") && doc.contains("map") && doc["map"].is_object()) return "/map";
  return "";
}

nlohmann::json DescribeMapKinds() {
  nlohmann::json out = nlohmann::json::array();
  for (const MapKind& k : MapKinds()) {
    nlohmann::json d = {{"kind", k.name}, {"help", k.help}, {"keys", k.keys}};
    if (k.defaults_from_base) {
      d["defaults"] = "the base map's";
    } else {
      d["iterations"] = k.iteration.iterations;
      d["escape"] = k.iteration.escape_radius;
      d["inside"] = k.iteration.bounded ? "bounded orbit" : "|q_n| < 1";
      if (k.region.empty())
        d["half_extent"] = k.half_extent;
      else
        d["region"] = k.region;
    }
    out.push_back(d);
  }
  return out;
}

}  // namespace quijibo
