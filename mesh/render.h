// Pictures of a mesh with depth: a small ray tracer over Embree (Intel's ray-tracing kernels,
// Debian's libembree-dev) that makes a fractal crust legible.
//
// Shading "depth" (the default): each pixel averages `samples` jittered camera rays; where a ray
// meets the mesh, the colour is the albedo times
//   sky   = ambient occlusion: the fraction of `ao_rays` cosine-distributed rays over the normal
//           that leave within `ao_distance` of the mesh's radius (pores, folds and overhangs darken),
//   key   = a soft key light (a cone of `light_spread` degrees about one direction, fixed in the
//           mesh's frame, above and to the front left) times its visibility by one shadow ray,
// plus a faint fill; normals are the area-weighted vertex normals, interpolated. A ground plane
// under the mesh (its lowest point along y, the frame's up) catches the shadow and the occlusion,
// so the shape stands somewhere. Faces seen from behind (the inside through a cut at the box) are
// blue. Sampling is seeded per pixel: the image does not depend on the thread count.
// Shading "flat": the earlier z-buffer with Lambert shading from one light, no shadows, for
// comparison (docs/meshing.md "Pictures").
//
// Views: front (looking along -z), side (along -x), top (along -y), three-quarter; orthographic,
// framed on the mesh's bounding sphere or on `framing` (the same for several meshes: a triptych,
// the frames of a film).
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>

#include "mesh/triangle_mesh.h"
#include "util/image.h"

namespace quijibo::mesh {

struct RenderOptions {
  int size = 400;                    // pixels per view, in [16, 8192]
  int views = 4;                     // in [1, 4]: front, side, top, three-quarter (the first `views`)
  std::string shading = "depth";     // "depth" (occlusion, soft shadows, ground) or "flat" (Lambert)
  int samples = 4;                   // camera rays per pixel (depth), in [1, 256]
  int ao_rays = 8;                   // occlusion rays per camera ray (depth), in [0, 256]
  double ao_distance = 0.15;         // occlusion reach, fraction of the framing radius, in (0, 4]
  double light_spread = 4.0;         // key light's cone half angle, degrees, in [0, 45]
  bool ground = true;                // the ground plane (depth)
  std::uint64_t seed = 1;            // the sampling's seed
  // Centre x, y, z and radius of the framed sphere (the mesh's frame); none: the mesh's own.
  std::optional<std::array<double, 4>> framing;
  std::string Validate() const;
};

// The camera directions of the views, (azimuth, elevation) in degrees.
inline constexpr double kViewAngles[4][2] = {{0, 0}, {90, 0}, {0, 89.9}, {35, 25}};

// The framing of `mesh`: its bounding box's centre and the largest distance of a vertex from it.
std::array<double, 4> Framing(const TriangleMesh& mesh);

struct RenderSummary {
  double seconds = 0, bvh_seconds = 0;
  std::int64_t triangles = 0, camera_rays = 0, shadow_rays = 0, occlusion_rays = 0;
};

// `options.views` views of `mesh`, side by side, each `options.size` pixels square. Throws
// quijibo::Error for options out of range, a mesh without triangles, or an Embree failure.
Image RenderMesh(const TriangleMesh& mesh, const RenderOptions& options = {}, RenderSummary* summary = nullptr);
inline Image RenderMesh(const TriangleMesh& mesh, int size, int views) {
  RenderOptions o;
  o.size = size;
  o.views = views;
  return RenderMesh(mesh, o);
}

// One view of `mesh` from (azimuth, elevation) degrees, `options.size` pixels square.
Image RenderView(const TriangleMesh& mesh, double azimuth, double elevation, const RenderOptions& options = {},
                 RenderSummary* summary = nullptr);

// Images side by side on white, `gap` pixels apart, tops aligned.
Image SideBySide(const std::vector<Image>& images, int gap = 8);

}  // namespace quijibo::mesh
