// The coordinate frames every stage shares.
//
//   user frame        the coordinates of the input mesh
//   normalized frame  p = scale * x + translation: the mesh's bounding box centred at
//                     (0.5, 0.5, 0.5), its longest side 1 - 2 * padding (default padding 0.125,
//                     as the reference code; so the mesh spans [0.125, 0.875] on that axis)
//   fractal frame     w = fractal_radius * (p - origin) (default radius 4): where roots live and the
//                     map is iterated. A point w becomes the quaternion [w_x, w_y, w_z, slice].
//                     `origin` is the normalized point that becomes 0: the cube's centre
//                     (0.5, 0.5, 0.5) by default, or a point deep inside the shape (mesh/normalize.h,
//                     PlaceOriginInside), because iterating the map traps orbits at the origin:
//                     an inside point (|R(q)| < 1) lands in the unit ball about it, so when the
//                     origin lies outside the shape the n-step set empties.
//
// Every file that holds coordinates records this transform, so results can be mapped back onto
// the user's mesh: x = (w / fractal_radius + origin - translation) / scale. The unit cube, the
// box of the target grid, of meshing and of pictures, is box_center() +- fractal_radius / 2.
#pragma once

#include "quijibo/grid.h"
#include "util/settings.h"

namespace quijibo {

struct FractalFrame {
  // The largest fractal_radius accepted or chosen: beyond it a shape is thinner than 1e-4 of its box.
  static constexpr double kMaxFractalRadius = 1e4;
  double fractal_radius = 4.0;
  double padding = 0.125;
  // Normalization of the user's mesh into the unit cube (identity when no mesh is involved).
  double scale = 1.0;
  Vec3 translation{0.0, 0.0, 0.0};
  Vec3 origin{0.5, 0.5, 0.5};  // normalized point at the fractal origin, in [0, 1]^3

  Vec3 user_to_fractal(const Vec3& x) const {
    Vec3 w;
    for (int a = 0; a < 3; ++a) w[a] = fractal_radius * (scale * x[a] + translation[a] - origin[a]);
    return w;
  }
  Vec3 fractal_to_user(const Vec3& w) const {
    Vec3 x;
    for (int a = 0; a < 3; ++a) x[a] = (w[a] / fractal_radius + origin[a] - translation[a]) / scale;
    return x;
  }
  // The centre of the normalized unit cube (and of the mesh's bounding box) in the fractal frame.
  Vec3 box_center() const {
    return {fractal_radius * (0.5 - origin[0]), fractal_radius * (0.5 - origin[1]), fractal_radius * (0.5 - origin[2])};
  }
  bool default_origin() const { return origin == Vec3{0.5, 0.5, 0.5}; }
  // Lengths scale by this factor from the user frame to the fractal frame.
  double user_to_fractal_scale() const { return fractal_radius * scale; }
  std::string Validate() const;
};

// How frame `b` differs from frame `a`: "" when they are the same (to 1e-9 relative), else the
// fields that differ, "origin (0.5, 0.5, 0.5) vs (0.43, 0.52, 0.47), fractal_radius 4 vs 13.5". A map
// and a target grid in different frames place the shape and the roots differently: psi, the
// optimization and the figures are then wrong without any other sign.
std::string FrameDifference(const FractalFrame& a, const FractalFrame& b);

// The box of the target grid (the region the energy sees and fits).
enum class TargetBox {
  // The whole normalized unit cube, box_center() +- fractal_radius / 2: the shape with a
  // margin of `padding` on every side (1/6 of its longest side with the default padding), so the
  // energy sees and penalizes set growing beside the shape; the same box `quijibo mesh` and the
  // pictures use by default. The default for mesh targets.
  kUnitCube,
  // The reference code's SDF box: the mesh's longest side plus one cell on each side,
  // radius * (1 - 2 * padding) * (n + 2) / n, sampled at cell centres without its half-cell shift
  // (n = 97, defaults: side 3.0619, cell 0.03157). Set outside it is not seen by the energy and
  // leaks (docs/benchmarks.md, shape suite). Analytic targets keep this box.
  kReference,
};
inline const EnumNames<TargetBox> kTargetBoxes("target box", {{TargetBox::kUnitCube, "unit"},
                                                             {TargetBox::kReference, "reference"}});
inline TargetBox ParseTargetBox(const std::string& name) { return kTargetBoxes.Parse(name); }
inline std::string TargetBoxName(TargetBox box) { return kTargetBoxes.Name(box); }

// Cells per axis of the target grid: the paper's 97, and the range every command, experiment and
// the Python module accept (the grid costs n^3 cells; its log-distance matrix n^3 per root).
inline constexpr int kDefaultTargetResolution = 97;
inline constexpr ValueRange kTargetResolutionRange{8, 1024};

// The target grid of resolution n in the fractal frame: a cube centred at box_center() (the
// centre of the mesh's bounding box).
GridFrame TargetGridFrame(int n, const FractalFrame& frame, TargetBox box = TargetBox::kReference);

}  // namespace quijibo
