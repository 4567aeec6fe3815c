// Normalization of a user's mesh into the unit cube and the fractal frame (see quijibo/frame.h).
#pragma once

#include "mesh/triangle_mesh.h"
#include "quijibo/frame.h"
#include "util/settings.h"

#include <string>

namespace quijibo::mesh {

// The reference code's rule (TRIANGLE_MESH::normalize): the bounding box centre goes to
// (0.5, 0.5, 0.5) and the longest side becomes 1 - 2 * padding, uniformly scaled; so with the
// default padding the mesh spans [0.125, 0.875] on its longest axis.
//   mesh            the user's mesh (at least one vertex, not all at one point)
//   padding         in [0, 0.5)
//   fractal_radius  > 0, the fractal frame is w = fractal_radius * (p - 0.5)
// Throws quijibo::Error when the bounding box is a point or the options are invalid.
FractalFrame NormalizationFor(const TriangleMesh& mesh, double padding = FractalFrame{}.padding,
                              double fractal_radius = FractalFrame{}.fractal_radius);

// How the fractal origin is placed (quijibo/frame.h).
enum class OriginPlacement {
  kCenter,  // the centre of the unit cube (the mesh's bounding box): the reference code
  kInside,  // the point deepest inside the shape, where the iteration's trap belongs
};
inline const EnumNames<OriginPlacement> kOriginPlacements("origin placement", {{OriginPlacement::kCenter, "center"},
                                                                             {OriginPlacement::kInside, "inside"}});
inline OriginPlacement ParseOriginPlacement(const std::string& name) { return kOriginPlacements.Parse(name); }
inline std::string OriginPlacementName(OriginPlacement p) { return kOriginPlacements.Name(p); }

// `frame` with its origin moved to the point deepest inside `user_mesh`: the cell centre with the
// most negative signed distance (the first in x-fastest order on ties) on a `resolution`^3 grid
// over the unit cube. `name` names the mesh in errors. Throws quijibo::Error when no cell is inside.
FractalFrame PlaceOriginInside(const TriangleMesh& user_mesh, FractalFrame frame, const std::string& name,
                               int resolution = 48);

// How the fractal frame's scale is chosen (docs/fidelity.md §3).
enum class FrameScale {
  kFixed,  // w = fractal_radius (p - origin), fractal_radius as given (4: the reference code)
  kTrap,   // the ball of radius 1 about the origin just fits inside the shape (ScaleToTrap)
};
inline const EnumNames<FrameScale> kFrameScales("frame scale", {{FrameScale::kTrap, "trap"}, {FrameScale::kFixed, "fixed"}});
inline FrameScale ParseFrameScale(const std::string& name) { return kFrameScales.Parse(name); }
inline std::string FrameScaleName(FrameScale s) { return kFrameScales.Name(s); }

// `frame` with fractal_radius chosen so that the ball of radius 1 about the fractal origin touches
// the surface of `user_mesh`: fractal_radius / depth, where depth is the distance from the origin to
// the surface in `frame`'s fractal units, capped at `max_fractal_radius`. Why: a point of the one-step
// set {|R(q)| < 1} lands in that ball; where the ball sticks out of the shape, its orbit leaves the
// shape and the n-step set loses the point, and where the ball lies deeper than the surface, orbits
// from just outside are caught. The one-step set does not depend on the scale (ln C absorbs it).
// The origin must be inside (PlaceOriginInside). `name` names the mesh in errors. Throws
// quijibo::Error when the origin is on or outside the surface.
FractalFrame ScaleToTrap(const TriangleMesh& user_mesh, FractalFrame frame, const std::string& name,
                         double max_fractal_radius = FractalFrame::kMaxFractalRadius);

// Maps every vertex user -> fractal frame (ToFractalFrame) or back (FromFractalFrame).
// Orientation is kept (the maps are a positive scale and a translation).
TriangleMesh ToFractalFrame(const TriangleMesh& mesh, const FractalFrame& frame);
TriangleMesh FromFractalFrame(const TriangleMesh& mesh, const FractalFrame& frame);

}  // namespace quijibo::mesh
