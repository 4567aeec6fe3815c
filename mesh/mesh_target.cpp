#include "mesh/mesh_target.h"

#include <cmath>

#include "util/error.h"
#include "util/settings.h"

namespace quijibo::mesh {

std::string MeshTargetOptions::Validate() const {
  if (auto why = CheckRange("resolution", SettingType::kInteger, resolution, kTargetResolutionRange); !why.empty())
    return why;
  if (!(padding >= 0.0 && padding < 0.5)) return "padding must be in [0, 0.5)";
  if (!(fractal_radius > 0.0) || !std::isfinite(fractal_radius))
    return "fractal radius must be a positive finite number";
  return sdf.Validate();
}

MeshTargetResult MeshTarget(const TriangleMesh& user_mesh, const std::string& name, const MeshTargetOptions& o) {
  if (const std::string why = o.Validate(); !why.empty()) throw Error(name + ": " + why);
  MeshTargetResult t;
  t.frame = NormalizationFor(user_mesh, o.padding, o.fractal_radius);
  if (o.origin == OriginPlacement::kInside) {
    t.frame = PlaceOriginInside(user_mesh, t.frame, name);
    if (o.frame_scale == FrameScale::kTrap) t.frame = ScaleToTrap(user_mesh, t.frame, name);
  }
  t.mesh = ToFractalFrame(user_mesh, t.frame);
  SdfOptions sdf = o.sdf;
  sdf.name = name;
  t.grid = SignedDistance(t.mesh, TargetGridFrame(o.resolution, t.frame, o.box), sdf, &t.summary);
  return t;
}

}  // namespace quijibo::mesh
