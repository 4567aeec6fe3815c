// The renders with depth (mesh/render.h): ambient occlusion darkens what is enclosed, the key light
// casts a shadow on the ground, the image is the same on any thread count, bad options are refused.
#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <vector>

#include "mesh/render.h"
#include "util/error.h"

namespace quijibo::mesh {
namespace {

// An axis-aligned box [lo, hi], each face an 8 x 8 grid of quads (so that the vertex normals are the
// faces' but along the edges), outward (counter-clockwise seen from outside); `open_top` leaves out
// the face y = hi, so the box is a cup (its inside seen from within: back faces).
void AddBox(TriangleMesh& m, Vec3 lo, Vec3 hi, bool open_top = false) {
  constexpr int n = 8;
  // Each face: a corner, two edge directions (u x v outward) and whether it is the top.
  struct Face {
    Vec3 origin, u, v;
  };
  const Vec3 d{hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]};
  const std::vector<Face> faces = {
      {{lo[0], lo[1], lo[2]}, {0, 0, d[2]}, {0, d[1], 0}},      // x = lo, outward -x
      {{hi[0], lo[1], lo[2]}, {0, d[1], 0}, {0, 0, d[2]}},      // x = hi, +x
      {{lo[0], lo[1], lo[2]}, {d[0], 0, 0}, {0, 0, d[2]}},      // y = lo, -y
      {{lo[0], hi[1], lo[2]}, {0, 0, d[2]}, {d[0], 0, 0}},      // y = hi, +y
      {{lo[0], lo[1], lo[2]}, {0, d[1], 0}, {d[0], 0, 0}},      // z = lo, -z
      {{lo[0], lo[1], hi[2]}, {d[0], 0, 0}, {0, d[1], 0}}};     // z = hi, +z
  for (std::size_t f = 0; f < faces.size(); ++f) {
    if (open_top && f == 3) continue;
    const Face& F = faces[f];
    const int b = int(m.vertices.size());
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i) {
        Vec3 p;
        for (int a = 0; a < 3; ++a) p[a] = F.origin[a] + F.u[a] * i / n + F.v[a] * j / n;
        m.vertices.push_back(p);
      }
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const int v00 = b + j * (n + 1) + i, v10 = v00 + 1, v01 = v00 + n + 1, v11 = v01 + 1;
        m.triangles.push_back({v00, v10, v11});
        m.triangles.push_back({v00, v11, v01});
      }
  }
}

double Brightness(const Image& im, int x, int y) {
  const Rgb c = im.pixels[std::size_t(y) * im.width + x];
  return (c.r + c.g + c.b) / 3.0;
}

TEST(Render, AmbientOcclusionDarkensTheCupsFloorNearItsWalls) {
  TriangleMesh cup;
  AddBox(cup, {-1, 0, -1}, {1, 0.6, 1}, true);
  RenderOptions o;
  o.size = 96;
  o.samples = 4;
  o.ao_rays = 32;
  o.ao_distance = 0.5;  // reach 0.72: the walls beside the point, not the ones 1 from the middle
  o.ground = false;
  // Seen from above (the top view), the floor's centre and a point beside the wall x = 1, away from
  // the key light (which comes from -x): only the occlusion darkens it.
  const Image with = RenderView(cup, 0, 89.9, o);
  o.ao_rays = 0;
  const Image without = RenderView(cup, 0, 89.9, o);
  // The framing's scale: 0.47 size / radius pixels per unit, the centre at the image's centre.
  const double radius = Framing(cup)[3], scale = 0.47 * o.size / radius;
  const int c = o.size / 2, near = int(std::lround(o.size / 2.0 + 0.9 * scale));
  // What the occlusion takes away: much more beside the wall than in the open middle.
  const double loss_near = Brightness(without, near, c) - Brightness(with, near, c);
  const double loss_centre = Brightness(without, c, c) - Brightness(with, c, c);
  EXPECT_GT(loss_near, loss_centre + 10) << loss_near << " " << loss_centre;
  EXPECT_GT(Brightness(with, c, c), 60);  // the open floor is lit
}

TEST(Render, TheKeyLightCastsAShadowOnTheGround) {
  TriangleMesh box;
  AddBox(box, {-0.3, 0, -0.3}, {0.3, 1.2, 0.3});
  RenderOptions o;
  o.size = 96;
  o.samples = 2;
  o.ao_rays = 4;
  // The ground under the box is darker than the background somewhere (the shadow), and the ground
  // takes the background's grey: count grey pixels clearly darker than the background's darkest.
  auto shadow_pixels = [&](const Image& im) {
    int n = 0;
    for (const Rgb& p : im.pixels)
      if (std::abs(p.r - p.g) < 4 && std::abs(p.g - p.b) < 6 && p.r < 205) ++n;
    return n;
  };
  const Image depth = RenderView(box, 35, 25, o);
  EXPECT_GT(shadow_pixels(depth), 50);
  o.shading = "flat";
  EXPECT_EQ(shadow_pixels(RenderView(box, 35, 25, o)), 0);  // the Lambert picture has no ground
}

TEST(Render, TheImageDoesNotDependOnTheThreadCount) {
  TriangleMesh m;
  AddBox(m, {-1, 0, -1}, {1, 0.6, 1}, true);
  AddBox(m, {-0.2, 0.1, -0.2}, {0.2, 0.9, 0.2});
  RenderOptions o;
  o.size = 64;
  o.views = 4;
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  const Image one = RenderMesh(m, o);
  omp_set_num_threads(std::max(2, threads));
  const Image many = RenderMesh(m, o);
  omp_set_num_threads(threads);
  ASSERT_EQ(one.width, 4 * 64);
  ASSERT_EQ(one.pixels.size(), many.pixels.size());
  for (std::size_t i = 0; i < one.pixels.size(); ++i)
    ASSERT_TRUE(one.pixels[i].r == many.pixels[i].r && one.pixels[i].g == many.pixels[i].g &&
                one.pixels[i].b == many.pixels[i].b)
        << i;
  RenderSummary s;
  o.views = 1;
  RenderMesh(m, o, &s);
  EXPECT_EQ(s.camera_rays, std::int64_t(64) * 64 * o.samples);
  EXPECT_GT(s.occlusion_rays, 0);
}

TEST(Render, BadOptionsAndEmptyMeshesAreRefused) {
  TriangleMesh m;
  AddBox(m, {0, 0, 0}, {1, 1, 1});
  RenderOptions o;
  o.shading = "glossy";
  EXPECT_THROW(RenderMesh(m, o), Error);
  o = {};
  o.samples = 0;
  EXPECT_THROW(RenderMesh(m, o), Error);
  o = {};
  o.framing = std::array<double, 4>{0, 0, 0, -1};
  EXPECT_THROW(RenderMesh(m, o), Error);
  EXPECT_THROW(RenderMesh(TriangleMesh{}, RenderOptions{}), Error);
}

}  // namespace
}  // namespace quijibo::mesh
