#include "mesh/normalize.h"

#include <algorithm>
#include <cmath>

#include "mesh/sdf.h"
#include "util/error.h"

namespace quijibo::mesh {

FractalFrame NormalizationFor(const TriangleMesh& mesh, double padding, double fractal_radius) {
  FractalFrame frame;
  frame.padding = padding;
  frame.fractal_radius = fractal_radius;
  if (const std::string why = frame.Validate(); !why.empty())
    throw Error("normalization: " + why);
  if (mesh.vertices.empty()) throw Error("normalization: mesh has no vertices");
  const BoundingBox box = ComputeBoundingBox(mesh);
  double longest = 0.0;
  for (int a = 0; a < 3; ++a) longest = std::max(longest, box.max[a] - box.min[a]);
  if (!(longest > 0.0) || !std::isfinite(longest))
    throw Error("normalization: the mesh's bounding box has no extent");
  frame.scale = (1.0 - 2.0 * padding) / longest;
  for (int a = 0; a < 3; ++a)
    frame.translation[a] = 0.5 - frame.scale * 0.5 * (box.min[a] + box.max[a]);
  return frame;
}

FractalFrame PlaceOriginInside(const TriangleMesh& user_mesh, FractalFrame frame, const std::string& name,
                               int resolution) {
  SdfOptions o;
  o.name = name;
  const ScalarGrid sdf =
      SignedDistance(ToFractalFrame(user_mesh, frame), TargetGridFrame(resolution, frame, TargetBox::kUnitCube), o);
  const auto deepest = std::min_element(sdf.values.begin(), sdf.values.end());
  if (deepest == sdf.values.end() || !(*deepest < 0))
    throw Error(name + ": no point of the grid is inside the shape: cannot place the fractal origin inside it");
  const Vec3 w = sdf.frame.cell_center(std::int64_t(deepest - sdf.values.begin()));
  for (int a = 0; a < 3; ++a) frame.origin[a] = w[a] / frame.fractal_radius + frame.origin[a];
  return frame;
}

FractalFrame ScaleToTrap(const TriangleMesh& user_mesh, FractalFrame frame, const std::string& name,
                         double max_fractal_radius) {
  const double depth = UnsignedDistance(ToFractalFrame(user_mesh, frame), {Vec3{0.0, 0.0, 0.0}})[0];
  if (!(depth > 0.0) || !std::isfinite(depth))
    throw Error(name + ": the fractal origin is on the surface: cannot scale the frame to it");
  frame.fractal_radius = std::min(frame.fractal_radius / depth, max_fractal_radius);
  return frame;
}

TriangleMesh ToFractalFrame(const TriangleMesh& mesh, const FractalFrame& frame) {
  TriangleMesh out = mesh;
  for (Vec3& p : out.vertices) p = frame.user_to_fractal(p);
  return out;
}

TriangleMesh FromFractalFrame(const TriangleMesh& mesh, const FractalFrame& frame) {
  TriangleMesh out = mesh;
  for (Vec3& p : out.vertices) p = frame.fractal_to_user(p);
  return out;
}

}  // namespace quijibo::mesh
