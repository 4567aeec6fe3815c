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
  if (!m.base_set) {
    auto map = m.map;
    m.base_set = [map](const Quat& q) { return std::log(map->Apply(q).norm()); };
  }
  return m;
}

nlohmann::json DescribeMapKinds() {
  nlohmann::json out = nlohmann::json::array();
  for (const MapKind& k : MapKinds())
    out.push_back({{"kind", k.name},
                   {"help", k.help},
                   {"keys", k.keys},
                   {"iterations", k.iteration.iterations},
                   {"escape", k.iteration.escape_radius},
                   {"inside", k.iteration.bounded ? "bounded orbit" : "|q_n| < 1"},
                   {"half_extent", k.half_extent}});
  return out;
}

}  // namespace quijibo
