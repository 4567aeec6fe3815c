// Portals (Schor and Kim, SIGGRAPH 2024, §3): directable self-similarity inside the map.
//
//   F_F(x) = F(x)                             x outside every mask
//          = B(x) T(x) + (1 - B(x)) F(x)      x in a portal's mask M        (Eqn 7)
//
// F is the base map (a shape modulus map or a QUIJIBO rational map), T the portal's transform,
// B its blend factor. B = 1 gives Eqn 6 (a pure portal), B = 0 the base map.
//
// Blend factor with feathered edges: for a portal with mask distance d(x) (negative inside) and
// feather w > 0,
//   B(x) = b * SmoothStep(-d(x) / w)   [and B = 0 where s(x) <= 0 when exclude_base]
// so B rises from 0 on the mask's boundary to b (the portal's strength, default 1) at depth w:
// F_F is continuous across the boundary (B = 0 there). With w = 0 the mask is a hard indicator
// (B = b inside). exclude_base makes the mask "the portal region minus the base set" (the 2024
// paper's turbulent snowflake; the authors' code does this with the base Julia set): s(x) is the
// base set's signed function, phi(x) + beta(x) for the shape modulus (a distance) and log|R(q)|
// for a rational map. That cut is NOT feathered: a feathered cut leaves a visible gap between the
// base set and the copies (measured on the snowflake). When several portals
// overlap, the one with the largest B applies (the first on ties).
//
// Transform (affine, optionally blended with noise):
//   T(x) = R (s (x - c)) + t + a N(x)
// c the portal's centre (the mask's centre by default), s the scale, R a rotation (angle about
// an axis; 2D: about z), t the translation (where the copy is taken from), N a seeded vector noise
// field with amplitude a. T acts on the three components phi reads (w, i, j); k is multiplied by
// s. The authors' code uses spheres only, T(x) = R s (x - c) onto the origin, no blend and no
// feather.
//
// In 2D everything lives in the plane z = 0 and rotations are about z.
#pragma once

#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "quijibo/quaternion_map.h"
#include "methods/mask.h"
#include "methods/modulus.h"

namespace quijibo {

struct PortalTransform {
  Vec3 center{0, 0, 0};
  double scale = 1.0;
  double angle_deg = 0.0;
  Vec3 axis{0, 0, 1};
  Vec3 translation{0, 0, 0};
  NoiseField noise;
  double noise_amplitude = 0.0;
  Vec3 Apply(const Vec3& x) const;
};

struct Portal {
  Mask mask;
  double feather = 0.0;
  double strength = 1.0;  // b: B's value deep inside the mask
  bool exclude_base = false;
  PortalTransform transform;
  std::string Validate() const;
};

class PortalMap : public QuaternionMap {
 public:
  // base_set: s(q) < 0 inside the base set (used by exclude_base portals; may be empty if none).
  PortalMap(std::shared_ptr<const QuaternionMap> base, std::vector<Portal> portals,
            std::function<double(const Quat&)> base_set);
  Quat Apply(const Quat& q) const override;
  // B at q and which portal gives it (-1: none).
  double Blend(const Quat& q, int* which = nullptr) const;
  const std::vector<Portal>& portals() const { return portals_; }

 private:
  std::shared_ptr<const QuaternionMap> base_;
  std::vector<Portal> portals_;
  std::function<double(const Quat&)> base_set_;
};

// Portal JSON: {"mask": {...mask...}, "feather": w, "strength": b, "exclude_base": bool,
//   "transform": {"center": [..], "scale": s, "rotation": {"angle_deg": a, "axis": [..]},
//                 "translation": [..], "noise": {"amplitude": a, "frequency": f, "octaves": n, "seed": k}}}
Portal PortalFromJson(const JsonReader& r, const std::string& pointer, const std::string& base_dir,
                      const MaskGridLoader& load = {});
nlohmann::json PortalToJson(const Portal& p);
// The array of portals at `pointer` (absent: none), each as PortalFromJson reads it.
std::vector<Portal> PortalsFromJson(const JsonReader& r, const std::string& pointer, const std::string& base_dir,
                                    const MaskGridLoader& load = {});

// The Koch snowflake of the 2024 paper (Figs. 4, 7, 8), worked out here: the hexagram H of
// triangle side `side` (centroids at the origin) and one disc portal per star tip i, centred on
// the tip triangle's centroid c_i (at distance side/(2 sqrt3) + side/(6 sqrt3) = 2 side/(3 sqrt3)
// from the origin), radius side / (3 sqrt3) (the circumradius of the tip's own snowflake,
// so neighbouring discs touch at the hexagram's inner corners), T_i(x) = 3 (x - c_i), and
// exclude_base. Then S(x) = H(x) or (x in disc_i and S(T_i(x))), which is the snowflake: it is H
// plus, on each tip, a copy of itself scaled by 1/3 (the snowflake is 6-fold symmetric).
std::vector<Portal> KochPortals(double side, double feather);

}  // namespace quijibo
