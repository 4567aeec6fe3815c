#include "mesh/normalize.h"

#include <algorithm>
#include <cmath>

#include "quijibo/error.h"

namespace quijibo {

FractalFrame NormalizationFor(const TriangleMesh& mesh, double padding, double fractal_radius) {
  FractalFrame frame;
  frame.padding = padding;
  frame.fractal_radius = fractal_radius;
  if (const std::string why = frame.validate(); !why.empty())
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

}  // namespace quijibo
