// Pictures of a Julia set (PNG through util/image.h):
//  - a slice of the set against the target shape: agreement in grey, mismatches in two colours;
//  - a slice of the iterate's modulus and versor (the 2023 paper's Fig. 2 idea);
//  - shaded renderings of a mesh: mesh/render.h.
#pragma once

#include <cstdint>
#include <functional>
#include <string>

#include "mesh/marching_cubes.h"
#include "mesh/render.h"
#include "mesh/triangle_mesh.h"
#include "quijibo/grid.h"
#include "util/image.h"
#include "quijibo/julia.h"

namespace quijibo::mesh {

// An axis-aligned plane through a box: the picture covers the box's two other axes (in increasing
// order: x-y for axis z, x-z for axis y, y-z for axis x), the first one horizontal, the second
// one vertical pointing up.
struct SliceView {
  int axis = 2;  // the plane's normal: 0 x, 1 y, 2 z
  double at = 0.0;
  Vec3 min_corner{-2.0, -2.0, -2.0};
  Vec3 max_corner{2.0, 2.0, 2.0};
  int size = 512;  // pixels along the longer side
  std::string Validate() const;
  // The two in-plane axes.
  int u() const { return axis == 0 ? 1 : 0; }
  int v() const { return axis == 2 ? 1 : 2; }
  int width() const;
  int height() const;
  Vec3 point(int px, int py) const;  // pixel centre
};

// Colours of SliceAgainstTarget.
inline constexpr Rgb kBothInside{70, 70, 70}, kBothOutside{235, 235, 235}, kJuliaOnly{235, 120, 20},
    kTargetOnly{30, 110, 235};

struct SliceAgreement {
  std::int64_t both_inside = 0, both_outside = 0, julia_only = 0, target_only = 0;
  double agreement() const;  // fraction of pixels where the two agree
};

// The set {field < iso} against {target < 0} (target: a signed distance .qgrid in the same frame,
// sampled trilinearly, clamped at its border) on `view`.
Image SliceAgainstTarget(const BatchField& field, const ScalarGrid& target, const SliceView& view,
                         SliceAgreement* agreement = nullptr);

// Two panels side by side: the log-modulus L = log|q_m| (grey, 0.5 + 0.5 tanh((L - iso) / scale),
// scale = modulus_scale, or when it is 0 half the 90th percentile of |L - iso| over the picture;
// the iso line L = iso in red) and the versor of q_m (its i, j, k components as R, G, B, mapped
// from [-1, 1] to [0, 255]).
Image ModulusVersorSlice(const RationalMap& map, const JuliaOptions& options, const SliceView& view,
                         double modulus_scale = 0.0, double iso = 0.0);

// The slice z = 0 of a field over the box of `sdf` (its larger side, `size` pixels square):
// {field < 0} black, else light grey, the target's outline {sdf = 0} red (`quijibo compare`).
Image InsideSlice(const std::function<double(const Vec3&)>& field, const ScalarGrid& sdf, int size);

}  // namespace quijibo::mesh
