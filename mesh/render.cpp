#include "mesh/render.h"

#include <embree3/rtcore.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <vector>

#include "util/error.h"

namespace quijibo::mesh {

std::string RenderOptions::Validate() const {
  if (size < 16 || size > 8192) return "render: size must be in [16, 8192]";
  if (views < 1 || views > 4) return "render: views must be 1 to 4";
  if (shading != "depth" && shading != "flat") return "render: shading must be depth or flat, found \"" + shading + "\"";
  if (samples < 1 || samples > 256) return "render: samples must be in [1, 256]";
  if (ao_rays < 0 || ao_rays > 256) return "render: ao_rays must be in [0, 256]";
  if (!(ao_distance > 0 && ao_distance <= 4)) return "render: ao_distance must be in (0, 4]";
  if (!(light_spread >= 0 && light_spread <= 45)) return "render: light_spread must be in [0, 45] degrees";
  if (framing) {
    for (double x : *framing)
      if (!std::isfinite(x)) return "render: the framing must be finite";
    if (!((*framing)[3] > 0)) return "render: the framing radius must be > 0";
  }
  return {};
}

std::array<double, 4> Framing(const TriangleMesh& mesh) {
  if (mesh.vertices.empty()) return {0, 0, 0, 1};
  Vec3 lo = mesh.vertices[0], hi = mesh.vertices[0];
  for (const Vec3& p : mesh.vertices)
    for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], p[a]), hi[a] = std::max(hi[a], p[a]);
  const Vec3 c{(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, (lo[2] + hi[2]) / 2};
  double r = 0;
  for (const Vec3& p : mesh.vertices) r = std::max(r, std::hypot(p[0] - c[0], p[1] - c[1], p[2] - c[2]));
  return {c[0], c[1], c[2], r > 0 ? r : 1.0};
}

Image SideBySide(const std::vector<Image>& images, int gap) {
  int w = 0, h = 0;
  for (const Image& im : images) w += im.width, h = std::max(h, im.height);
  w += gap * std::max(0, int(images.size()) - 1);
  Image out(std::max(w, 1), std::max(h, 1), Rgb{255, 255, 255});
  int x0 = 0;
  for (const Image& im : images) {
    for (int y = 0; y < im.height; ++y)
      for (int x = 0; x < im.width; ++x) out.at(x0 + x, y) = im.pixels[std::size_t(y) * im.width + x];
    x0 += im.width + gap;
  }
  return out;
}

namespace {

struct V3 {
  double x = 0, y = 0, z = 0;
};
V3 operator+(V3 a, V3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
V3 operator-(V3 a, V3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
V3 operator*(double s, V3 a) { return {s * a.x, s * a.y, s * a.z}; }
double Dot(V3 a, V3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
V3 Cross(V3 a, V3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
V3 Normalized(V3 a) {
  const double n = std::sqrt(Dot(a, a));
  return n > 0 ? (1.0 / n) * a : V3{0, 0, 1};
}

// A camera looking at the framing's centre from (azimuth, elevation).
struct Camera {
  V3 back, right, up;
  double scale;  // pixels per unit
  int size;
  Camera(double azimuth, double elevation, double radius, int size_) : size(size_) {
    const double az = azimuth * M_PI / 180, el = elevation * M_PI / 180;
    back = {std::sin(az) * std::cos(el), std::sin(el), std::cos(az) * std::cos(el)};
    right = {std::cos(az), 0, -std::sin(az)};
    up = Cross(back, right);
    scale = 0.47 * size / radius;
  }
};

// splitmix64: a seeded stream per pixel, so that the image is the same on any thread count.
struct Rng {
  std::uint64_t s;
  std::uint64_t Next() {
    std::uint64_t z = (s += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  double Uniform() { return double(Next() >> 11) * 0x1.0p-53; }
};

// An orthonormal basis about n.
void Basis(V3 n, V3& t, V3& b) {
  t = Normalized(std::abs(n.x) > 0.9 ? Cross(n, V3{0, 1, 0}) : Cross(n, V3{1, 0, 0}));
  b = Cross(n, t);
}

// sRGB-ish output of a linear value.
std::uint8_t Encode(double v) { return std::uint8_t(std::lround(255 * std::pow(std::clamp(v, 0.0, 1.0), 1 / 2.2))); }
double Decode(double byte) { return std::pow(byte / 255.0, 2.2); }

// The background at image height fraction t (0 top, 1 bottom), linear.
V3 Background(double t) {
  const double top = Decode(250), bottom = Decode(222);
  const double v = top + (bottom - top) * t;
  return {v, v, v * 1.01};
}

class Scene {
 public:
  Scene(const TriangleMesh& mesh, const std::array<double, 4>& framing) : centre_{framing[0], framing[1], framing[2]} {
    device_ = rtcNewDevice(nullptr);
    if (!device_) throw Error("render: Embree could not start (" + std::to_string(int(rtcGetDeviceError(nullptr))) + ")");
    scene_ = rtcNewScene(device_);
    rtcSetSceneFlags(scene_, RTC_SCENE_FLAG_COMPACT);
    RTCGeometry geom = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* vb = static_cast<float*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                           3 * sizeof(float), mesh.vertices.size()));
    auto* ib = static_cast<unsigned*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                              3 * sizeof(unsigned), mesh.triangles.size()));
    if (!vb || !ib) {
      rtcReleaseGeometry(geom);
      Release();
      throw Error("render: Embree could not allocate the mesh's buffers (" + std::to_string(mesh.triangles.size()) +
                  " triangles)");
    }
    // Relative to the framing's centre, so that single precision keeps the detail of a small crust.
    vertices_.resize(mesh.vertices.size());
    for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
      const Vec3& p = mesh.vertices[i];
      vertices_[i] = {p[0] - centre_.x, p[1] - centre_.y, p[2] - centre_.z};
      vb[3 * i] = float(vertices_[i].x), vb[3 * i + 1] = float(vertices_[i].y), vb[3 * i + 2] = float(vertices_[i].z);
    }
    normals_.assign(mesh.vertices.size(), V3{});
    triangles_ = &mesh.triangles;
    ground_ = std::numeric_limits<double>::infinity();
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
      const auto& f = mesh.triangles[t];
      for (int k = 0; k < 3; ++k) ib[3 * t + k] = unsigned(f[k]);
      const V3 n = Cross(vertices_[f[1]] - vertices_[f[0]], vertices_[f[2]] - vertices_[f[0]]);  // area-weighted
      for (int k = 0; k < 3; ++k) normals_[f[k]] = normals_[f[k]] + n;
    }
    for (V3& n : normals_) n = Normalized(n);
    for (const V3& p : vertices_) ground_ = std::min(ground_, p.y);
    rtcCommitGeometry(geom);
    rtcAttachGeometry(scene_, geom);
    rtcReleaseGeometry(geom);
    rtcCommitScene(scene_);
    if (const RTCError e = rtcGetDeviceError(device_); e != RTC_ERROR_NONE) {
      Release();
      throw Error(std::string("render: Embree could not build the scene (") +
                  (e == RTC_ERROR_OUT_OF_MEMORY ? "out of memory" : "error " + std::to_string(int(e))) + ")");
    }
  }
  ~Scene() { Release(); }
  Scene(const Scene&) = delete;
  Scene& operator=(const Scene&) = delete;

  struct Hit {
    bool mesh = false;
    double t = 0;
    V3 geometric, shading;  // unit, facing the ray's origin
    bool front = true;      // the triangle's outside faces the ray's origin
  };
  // The nearest mesh hit along o + t d, t in (0, tfar).
  bool Intersect(V3 o, V3 d, double tfar, Hit& hit) const {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    RTCRayHit rh{};
    rh.ray.org_x = float(o.x), rh.ray.org_y = float(o.y), rh.ray.org_z = float(o.z);
    rh.ray.dir_x = float(d.x), rh.ray.dir_y = float(d.y), rh.ray.dir_z = float(d.z);
    rh.ray.tnear = 0.0f;
    rh.ray.tfar = float(tfar);
    rh.ray.mask = 0xFFFFFFFFu;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(scene_, &ctx, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return false;
    const auto& f = (*triangles_)[rh.hit.primID];
    V3 g = Normalized(Cross(vertices_[f[1]] - vertices_[f[0]], vertices_[f[2]] - vertices_[f[0]]));
    const double u = rh.hit.u, v = rh.hit.v;
    V3 s = Normalized((1 - u - v) * normals_[f[0]] + u * normals_[f[1]] + v * normals_[f[2]]);
    hit.mesh = true;
    hit.t = rh.ray.tfar;
    hit.front = Dot(g, d) < 0;
    if (!hit.front) g = -1.0 * g, s = -1.0 * s;
    if (Dot(s, d) >= 0) s = g;  // an interpolated normal turned away: the face's own
    hit.geometric = g, hit.shading = s;
    return true;
  }
  bool Occluded(V3 o, V3 d, double tfar) const {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    RTCRay r{};
    r.org_x = float(o.x), r.org_y = float(o.y), r.org_z = float(o.z);
    r.dir_x = float(d.x), r.dir_y = float(d.y), r.dir_z = float(d.z);
    r.tnear = 0.0f;
    r.tfar = float(tfar);
    r.mask = 0xFFFFFFFFu;
    rtcOccluded1(scene_, &ctx, &r);
    return r.tfar < 0;
  }
  double ground() const { return ground_; }

 private:
  void Release() {
    if (scene_) rtcReleaseScene(scene_), scene_ = nullptr;
    if (device_) rtcReleaseDevice(device_), device_ = nullptr;
  }
  RTCDevice device_ = nullptr;
  RTCScene scene_ = nullptr;
  V3 centre_;
  std::vector<V3> vertices_, normals_;
  const std::vector<std::array<int, 3>>* triangles_ = nullptr;
  double ground_ = 0;
};

struct RayCounts {
  std::int64_t camera = 0, shadow = 0, occlusion = 0;
};

// The ray-traced view (shading "depth").
Image TraceView(const Scene& scene, const Camera& cam, double radius, const RenderOptions& o, int view,
                RayCounts& counts) {
  const int n = cam.size;
  Image img(n, n);
  const V3 light = Normalized({-0.45, 1.0, 0.6});  // towards the key light, in the mesh's frame
  V3 lt, lb;
  Basis(light, lt, lb);
  const double cos_spread = std::cos(o.light_spread * M_PI / 180);
  const double eps = 1e-4 * radius, reach = o.ao_distance * radius, far = 8 * radius;
  const double ground = scene.ground();
  const V3 front_albedo{Decode(214), Decode(190), Decode(156)}, back_albedo{Decode(110), Decode(135), Decode(200)};
  std::int64_t cam_rays = 0, shadow_rays = 0, ao_rays = 0;
#pragma omp parallel for schedule(dynamic, 2) reduction(+ : cam_rays, shadow_rays, ao_rays)
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      Rng rng{o.seed * 0x9E3779B97F4A7C15ull ^ (std::uint64_t(view) << 56) ^ (std::uint64_t(y) << 28) ^ std::uint64_t(x)};
      V3 sum{};
      for (int s = 0; s < o.samples; ++s) {
        // Stratified: sample s in its cell of a side x side grid over the pixel.
        const int side = int(std::ceil(std::sqrt(double(o.samples))));
        const double jx = o.samples == 1 ? 0.5 : (s % side + rng.Uniform()) / side;
        const double jy = o.samples == 1 ? 0.5 : ((s / side) % side + rng.Uniform()) / side;
        const double u = (x + jx - n / 2.0) / cam.scale, v = (n / 2.0 - (y + jy)) / cam.scale;
        const V3 d = -1.0 * cam.back;
        const V3 origin = u * cam.right + v * cam.up + (2 * radius) * cam.back;
        ++cam_rays;
        Scene::Hit hit;
        const bool on_mesh = scene.Intersect(origin, d, far, hit);
        // The ground plane y = ground, seen from above, nearer than the mesh.
        double tg = std::numeric_limits<double>::infinity();
        if (o.ground && d.y < -1e-9) tg = (ground - origin.y) / d.y;
        const bool on_ground = o.ground && std::isfinite(tg) && tg > 0 && (!on_mesh || tg < hit.t);
        const double bg_t = std::clamp((y + jy) / n, 0.0, 1.0);
        const V3 bg = Background(bg_t);
        if (!on_mesh && !on_ground) {
          sum = sum + bg;
          continue;
        }
        V3 p, ng, ns;
        if (on_ground) {
          p = origin + tg * d;
          ng = ns = {0, 1, 0};
        } else {
          p = origin + hit.t * d;
          ng = hit.geometric, ns = hit.shading;
        }
        const V3 q = p + eps * ng;
        // Ambient occlusion: cosine-weighted rays about the face's normal (the interpolated one of a
        // coarse mesh leans across its edges).
        double open = 1;
        if (o.ao_rays > 0) {
          V3 t, b;
          Basis(ng, t, b);
          int free = 0;
          for (int k = 0; k < o.ao_rays; ++k) {
            const double r1 = rng.Uniform(), r2 = rng.Uniform();
            const double rr = std::sqrt(r1), phi = 2 * M_PI * r2;
            const V3 dir = Normalized(rr * std::cos(phi) * t + rr * std::sin(phi) * b + std::sqrt(std::max(0.0, 1 - r1)) * ng);
            ++ao_rays;
            bool blocked = scene.Occluded(q, dir, reach);
            if (!blocked && o.ground && !on_ground && dir.y < 0) blocked = (ground - q.y) / dir.y < reach;
            free += blocked ? 0 : 1;
          }
          open = double(free) / o.ao_rays;
        }
        // The soft key light: one ray into its cone.
        const double c = 1 - rng.Uniform() * (1 - cos_spread), sn = std::sqrt(std::max(0.0, 1 - c * c));
        const double phi = 2 * M_PI * rng.Uniform();
        const V3 l = Normalized(c * light + sn * std::cos(phi) * lt + sn * std::sin(phi) * lb);
        const double lambert = std::max(0.0, Dot(ns, l));
        double visible = 0;
        if (lambert > 0 && Dot(ng, l) > 0) {
          ++shadow_rays;
          visible = scene.Occluded(q, l, far) ? 0 : 1;
        }
        if (on_ground) {
          // A shadow catcher: the background darkened by the shadow and the occlusion.
          const double k = 0.3 + 0.5 * visible + 0.2 * open;
          sum = sum + k * bg;
          continue;
        }
        const V3& albedo = hit.front ? front_albedo : back_albedo;
        const double light_in = 0.5 * open + 0.72 * lambert * visible + 0.04;
        sum = sum + light_in * albedo;
      }
      const double w = 1.0 / o.samples;
      img.at(x, y) = {Encode(w * sum.x), Encode(w * sum.y), Encode(w * sum.z)};
    }
  counts.camera += cam_rays, counts.shadow += shadow_rays, counts.occlusion += ao_rays;
  return img;
}

// The earlier picture (shading "flat"): z-buffer, Lambert shading from a light at the viewer's upper left.
Image FlatView(const TriangleMesh& mesh, const Camera& cam, const std::array<double, 4>& framing) {
  const int size = cam.size;
  const V3 c{framing[0], framing[1], framing[2]};
  Image img(size, size, Rgb{255, 255, 255});
  std::vector<std::array<double, 3>> s(mesh.vertices.size());
  for (std::size_t i = 0; i < s.size(); ++i) {
    const V3 d = V3{mesh.vertices[i][0], mesh.vertices[i][1], mesh.vertices[i][2]} - c;
    s[i] = {size / 2.0 + cam.scale * Dot(d, cam.right), size / 2.0 - cam.scale * Dot(d, cam.up), Dot(d, cam.back)};
  }
  std::vector<double> depth(std::size_t(size) * size, -std::numeric_limits<double>::infinity());
  const V3 light = Normalized(-0.4 * cam.right + 0.6 * cam.up + cam.back);
  for (const auto& t : mesh.triangles) {
    const Vec3 &A = mesh.vertices[t[0]], &B = mesh.vertices[t[1]], &C = mesh.vertices[t[2]];
    const V3 n0 = Cross(V3{B[0] - A[0], B[1] - A[1], B[2] - A[2]}, V3{C[0] - A[0], C[1] - A[1], C[2] - A[2]});
    if (!(Dot(n0, n0) > 0)) continue;
    const V3 n = Normalized(n0);
    const bool front = Dot(n, cam.back) >= 0;
    const double k = 0.18 + 0.82 * std::abs(Dot(n, light));
    const Rgb colour = front ? Rgb{std::uint8_t(225 * k), std::uint8_t(205 * k), std::uint8_t(170 * k)}
                             : Rgb{std::uint8_t(120 * k), std::uint8_t(140 * k), std::uint8_t(200 * k)};
    const auto &a = s[t[0]], &b = s[t[1]], &cc = s[t[2]];
    const double area = (b[0] - a[0]) * (cc[1] - a[1]) - (b[1] - a[1]) * (cc[0] - a[0]);
    if (area == 0) continue;
    const int x0 = std::max(0, int(std::floor(std::min({a[0], b[0], cc[0]}))));
    const int x1 = std::min(size - 1, int(std::ceil(std::max({a[0], b[0], cc[0]}))));
    const int y0 = std::max(0, int(std::floor(std::min({a[1], b[1], cc[1]}))));
    const int y1 = std::min(size - 1, int(std::ceil(std::max({a[1], b[1], cc[1]}))));
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        const double px = x + 0.5, py = y + 0.5;
        const double w0 = ((b[0] - px) * (cc[1] - py) - (b[1] - py) * (cc[0] - px)) / area;
        const double w1 = ((cc[0] - px) * (a[1] - py) - (cc[1] - py) * (a[0] - px)) / area;
        const double w2 = 1 - w0 - w1;
        if (w0 < 0 || w1 < 0 || w2 < 0) continue;
        const double z = w0 * a[2] + w1 * b[2] + w2 * cc[2];
        double& dd = depth[std::size_t(y) * size + x];
        if (z <= dd) continue;
        dd = z;
        img.at(x, y) = colour;
      }
  }
  return img;
}

std::vector<Image> Render(const TriangleMesh& mesh, const std::vector<std::array<double, 2>>& angles,
                          const RenderOptions& o, RenderSummary* summary) {
  if (auto why = o.Validate(); !why.empty()) throw Error(why);
  if (mesh.triangles.empty()) throw Error("render: the mesh has no triangles");
  const auto t0 = std::chrono::steady_clock::now();
  const std::array<double, 4> framing = o.framing ? *o.framing : Framing(mesh);
  std::vector<Image> images;
  RayCounts counts;
  double bvh = 0;
  if (o.shading == "flat") {
    for (const auto& a : angles) images.push_back(FlatView(mesh, Camera(a[0], a[1], framing[3], o.size), framing));
  } else {
    const Scene scene(mesh, framing);
    bvh = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    for (std::size_t v = 0; v < angles.size(); ++v)
      images.push_back(
          TraceView(scene, Camera(angles[v][0], angles[v][1], framing[3], o.size), framing[3], o, int(v), counts));
  }
  if (summary) {
    summary->seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    summary->bvh_seconds = bvh;
    summary->triangles = std::int64_t(mesh.triangles.size());
    summary->camera_rays = counts.camera, summary->shadow_rays = counts.shadow,
    summary->occlusion_rays = counts.occlusion;
  }
  return images;
}

}  // namespace

Image RenderMesh(const TriangleMesh& mesh, const RenderOptions& o, RenderSummary* summary) {
  if (auto why = o.Validate(); !why.empty()) throw Error(why);
  std::vector<std::array<double, 2>> angles;
  for (int v = 0; v < o.views; ++v) angles.push_back({kViewAngles[v][0], kViewAngles[v][1]});
  return SideBySide(Render(mesh, angles, o, summary), 0);
}

Image RenderView(const TriangleMesh& mesh, double azimuth, double elevation, const RenderOptions& o,
                 RenderSummary* summary) {
  if (!std::isfinite(azimuth) || !std::isfinite(elevation)) throw Error("render: the view's angles must be finite");
  return Render(mesh, {{azimuth, elevation}}, o, summary)[0];
}

}  // namespace quijibo::mesh
