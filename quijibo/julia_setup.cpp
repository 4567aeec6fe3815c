#include "quijibo/julia_setup.h"

#include <cmath>

#include "util/error.h"

namespace quijibo {

std::string JuliaSetupOptions::Validate() const {
  if (!box.empty() && box.size() != 6) return "box: expected xmin,ymin,zmin,xmax,ymax,zmax";
  for (std::size_t a = 0; a < 3 && box.size() == 6; ++a)
    if (!(box[3 + a] > box[a])) return "box: max must exceed min on every axis";
  if (!rotation.empty() && rotation.size() != 4) return "rotation: expected ax,ay,az,degrees";
  if (translate && translate->size() != 3 && translate->size() != 4) return "translate: expected x,y,z[,k]";
  if (translate_potential && translate && translate->size() == 4 && (*translate)[3] != 0.0)
    return "translate: with translate_potential it gives a direction in space (x, y, z), found a k component";
  if (!(detail >= 0 && std::isfinite(detail))) return "detail: expected a non-negative number";
  return julia.Validate();
}

Vec4 ResolveRootTranslation(const RationalMap& iterated, const JuliaSetupOptions& o) {
  if (o.translate_potential) {
    const Vec3 direction = o.translate ? Vec3{(*o.translate)[0], (*o.translate)[1], (*o.translate)[2]}
                                       : Vec3{0.0, 0.0, 1.0};
    return TranslationForPotential(iterated, direction, *o.translate_potential);
  }
  Vec4 t = o.julia.root_translation;
  if (o.translate)
    for (std::size_t a = 0; a < o.translate->size(); ++a) t[a] = (*o.translate)[a];
  return t;
}

JuliaSetup MakeJuliaSetup(const RationalMap& input, const JuliaSetupOptions& o) {
  if (auto why = o.Validate(); !why.empty()) throw Error(why);
  JuliaSetup s;
  s.map = IterationMap(input, o.frame, o.detail, &s.lambda);
  const double half = s.map.frame.fractal_radius / 2;
  const Vec3 c = s.map.frame.box_center();
  for (int a = 0; a < 3; ++a) {
    s.box_min[a] = o.box.size() == 6 ? o.box[a] : c[a] - half;
    s.box_max[a] = o.box.size() == 6 ? o.box[3 + a] : c[a] + half;
  }
  s.julia = o.julia;
  s.julia.root_translation = ResolveRootTranslation(s.map, o);
  if (o.rotation.size() == 4) {
    const Vec3 center{(s.box_min[0] + s.box_max[0]) / 2, (s.box_min[1] + s.box_max[1]) / 2,
                      (s.box_min[2] + s.box_max[2]) / 2};
    s.julia.placement = SampleTransform::AxisAngle({o.rotation[0], o.rotation[1], o.rotation[2]}, o.rotation[3], center);
  }
  if (auto why = s.julia.Validate(); !why.empty()) throw Error(why);
  return s;
}

IteratedQuaternionMap MakeIteratedQuaternionMap(const RationalMap& input, const JuliaSetupOptions& o,
                                                IterationOptions iteration) {
  const JuliaSetup s = MakeJuliaSetup(input, o);
  IteratedQuaternionMap m;
  m.map = std::make_shared<const RationalQuaternionMap>(s.map, s.julia);
  const Vec4& t = s.julia.root_translation;
  iteration.offset = Quat(t[0], t[1], t[2], t[3]);
  iteration.capture_radius = s.julia.capture_radius;
  m.iteration = iteration;
  m.center = s.map.frame.box_center();
  m.half_extent = s.map.frame.fractal_radius / 2;
  return m;
}

}  // namespace quijibo
