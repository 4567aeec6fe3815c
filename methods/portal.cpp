#include "methods/portal.h"

#include <cmath>

#include "util/error.h"

namespace quijibo {

using nlohmann::json;

Vec3 PortalTransform::Apply(const Vec3& x) const {
  Vec3 v{scale * (x[0] - center[0]), scale * (x[1] - center[1]), scale * (x[2] - center[2])};
  if (angle_deg != 0.0) {
    // Rodrigues: v cos t + (k x v) sin t + k (k.v)(1 - cos t), k the unit axis.
    const double n = std::sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
    const Vec3 k{axis[0] / n, axis[1] / n, axis[2] / n};
    const double t = angle_deg * M_PI / 180.0, c = std::cos(t), s = std::sin(t);
    const double kv = k[0] * v[0] + k[1] * v[1] + k[2] * v[2];
    const Vec3 kx{k[1] * v[2] - k[2] * v[1], k[2] * v[0] - k[0] * v[2], k[0] * v[1] - k[1] * v[0]};
    for (int a = 0; a < 3; ++a) v[a] = v[a] * c + kx[a] * s + k[a] * kv * (1 - c);
  }
  for (int a = 0; a < 3; ++a) v[a] += translation[a];
  if (noise_amplitude != 0.0) {
    const Vec3 n = noise(x);
    for (int a = 0; a < 3; ++a) v[a] += noise_amplitude * n[a];
  }
  return v;
}

std::string Portal::Validate() const {
  if (auto why = mask.Validate(); !why.empty()) return why;
  if (!(feather >= 0) || !std::isfinite(feather)) return "feather must be >= 0";
  if (!(strength >= 0 && strength <= 1)) return "strength must be in [0, 1]";
  if (!(transform.scale > 0) || !std::isfinite(transform.scale)) return "transform scale must be > 0";
  if (transform.angle_deg != 0.0 && std::hypot(transform.axis[0], transform.axis[1], transform.axis[2]) == 0.0)
    return "rotation axis must be non-zero";
  return {};
}

PortalMap::PortalMap(std::shared_ptr<const QuaternionMap> base, std::vector<Portal> portals,
                     std::function<double(const Quat&)> base_set)
    : base_(std::move(base)), portals_(std::move(portals)), base_set_(std::move(base_set)) {
  if (!base_) throw Error("portal map: no base map");
  for (std::size_t i = 0; i < portals_.size(); ++i) {
    if (auto why = portals_[i].Validate(); !why.empty()) throw Error("portal " + std::to_string(i) + ": " + why);
    if (portals_[i].exclude_base && !base_set_)
      throw Error("portal " + std::to_string(i) + ": exclude_base needs the base set's function");
  }
}

double PortalMap::Blend(const Quat& q, int* which) const {
  const Vec3 x{q.w, q.x, q.y};
  double best = 0.0;
  int best_i = -1;
  double s = 0.0;
  bool have_s = false;
  for (std::size_t i = 0; i < portals_.size(); ++i) {
    const Portal& p = portals_[i];
    const double d = p.mask.distance(x);
    double b;
    if (p.feather > 0) {
      if (d >= 0) continue;
      b = p.strength * SmoothStep(-d / p.feather);
    } else {
      if (!(d < 0)) continue;
      b = p.strength;
    }
    if (p.exclude_base) {
      if (!have_s) {
        s = base_set_(q);
        have_s = true;
      }
      if (!(s > 0)) continue;  // inside the base set: the base map applies
    }
    if (b > best) {
      best = b;
      best_i = int(i);
    }
  }
  if (which) *which = best_i;
  return best;
}

Quat PortalMap::Apply(const Quat& q) const {
  int i = -1;
  const double b = Blend(q, &i);
  if (i < 0 || b <= 0.0) return base_->Apply(q);
  const PortalTransform& t = portals_[i].transform;
  const Vec3 y = t.Apply({q.w, q.x, q.y});
  const Quat tq{y[0], y[1], y[2], q.z * t.scale};
  if (b >= 1.0) return tq;
  return tq * b + base_->Apply(q) * (1.0 - b);
}

Portal PortalFromJson(const JsonReader& r, const std::string& p, const std::string& base_dir,
                      const MaskGridLoader& load) {
  r.allow_keys(p, {"mask", "feather", "strength", "exclude_base", "transform"});
  Portal portal;
  portal.mask = MaskFromJson(r, p + "/mask", base_dir, load);
  portal.feather = r.number_or(p + "/feather", 0.0);
  portal.strength = r.number_or(p + "/strength", 1.0);
  portal.exclude_base = r.boolean_or(p + "/exclude_base", false);
  PortalTransform& t = portal.transform;
  t.center = portal.mask.center;
  if (r.has(p + "/transform")) {
    const std::string q = p + "/transform";
    r.allow_keys(q, {"center", "scale", "rotation", "translation", "noise"});
    if (r.has(q + "/center")) t.center = ReadVec3(r, q + "/center");
    t.scale = r.number_or(q + "/scale", 1.0);
    if (r.has(q + "/rotation")) {
      r.allow_keys(q + "/rotation", {"angle_deg", "axis"});
      t.angle_deg = r.number(q + "/rotation/angle_deg");
      if (r.has(q + "/rotation/axis")) t.axis = ReadVec3(r, q + "/rotation/axis");
    }
    if (r.has(q + "/translation")) t.translation = ReadVec3(r, q + "/translation");
    if (r.has(q + "/noise")) {
      const std::string n = q + "/noise";
      r.allow_keys(n, {"amplitude", "frequency", "octaves", "seed"});
      t.noise_amplitude = r.number(n + "/amplitude");
      t.noise.frequency = r.number_or(n + "/frequency", 1.0);
      t.noise.octaves = int(r.number_or(n + "/octaves", 1));
      t.noise.seed = std::uint64_t(r.number_or(n + "/seed", 1));
      if (t.noise.octaves < 1 || t.noise.octaves > 16) r.fail(n + "/octaves", "expected an integer in [1, 16]");
    }
  }
  if (auto why = portal.Validate(); !why.empty()) r.fail(p, why);
  return portal;
}

std::vector<Portal> PortalsFromJson(const JsonReader& r, const std::string& p, const std::string& base_dir,
                                    const MaskGridLoader& load) {
  std::vector<Portal> portals;
  const std::size_t n = r.has(p) ? r.array_size(p) : 0;
  for (std::size_t i = 0; i < n; ++i) portals.push_back(PortalFromJson(r, p + "/" + std::to_string(i), base_dir, load));
  return portals;
}

json PortalToJson(const Portal& p) {
  auto v = [](const Vec3& x) { return json::array({x[0], x[1], x[2]}); };
  const PortalTransform& t = p.transform;
  json tr = {{"center", v(t.center)}, {"scale", t.scale}, {"translation", v(t.translation)}};
  if (t.angle_deg != 0.0) tr["rotation"] = {{"angle_deg", t.angle_deg}, {"axis", v(t.axis)}};
  if (t.noise_amplitude != 0.0)
    tr["noise"] = {{"amplitude", t.noise_amplitude}, {"frequency", t.noise.frequency},
                   {"octaves", t.noise.octaves}, {"seed", t.noise.seed}};
  return {{"mask", MaskToJson(p.mask)}, {"feather", p.feather}, {"strength", p.strength},
          {"exclude_base", p.exclude_base}, {"transform", tr}};
}

std::vector<Portal> KochPortals(double side, double feather) {
  std::vector<Portal> out;
  const double dist = 2.0 * side / (3.0 * std::sqrt(3.0));  // tip centroid from the origin
  const double radius = side / (3.0 * std::sqrt(3.0));
  for (int i = 0; i < 6; ++i) {
    const double a = M_PI / 2 + i * M_PI / 3;  // the tips of HexagramPolygon
    Portal p;
    p.mask.type = Mask::Type::kSphere;
    p.mask.center = {dist * std::cos(a), dist * std::sin(a), 0.0};
    p.mask.radius = radius;
    p.feather = feather;
    p.exclude_base = true;
    p.transform.center = p.mask.center;
    p.transform.scale = 3.0;
    out.push_back(p);
  }
  return out;
}

}  // namespace quijibo
