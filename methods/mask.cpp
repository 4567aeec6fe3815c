#include "methods/mask.h"

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "util/error.h"

namespace quijibo {

using nlohmann::json;

double Mask::distance(const Vec3& p) const {
  switch (type) {
    case Type::kSphere: {
      const double dx = p[0] - center[0], dy = p[1] - center[1], dz = p[2] - center[2];
      return std::sqrt(dx * dx + dy * dy + dz * dz) - radius;
    }
    case Type::kBox: {
      double out2 = 0.0, in = -1e300;
      for (int a = 0; a < 3; ++a) {
        const double q = std::abs(p[a] - center[a]) - half_extent[a];
        if (q > 0) out2 += q * q;
        in = std::max(in, q);
      }
      return out2 > 0 ? std::sqrt(out2) : in;
    }
    case Type::kHalfspace:
      return normal[0] * p[0] + normal[1] * p[1] + normal[2] * p[2] - offset;
    case Type::kSdf: {
      const Vec3 u{(p[0] - center[0]) / sdf_scale, (p[1] - center[1]) / sdf_scale, (p[2] - center[2]) / sdf_scale};
      return sdf_scale * ExtendedSample(*sdf, u);
    }
  }
  return 1e300;
}

std::string Mask::Validate() const {
  switch (type) {
    case Type::kSphere:
      if (!(radius > 0) || !std::isfinite(radius)) return "sphere radius must be > 0";
      break;
    case Type::kBox:
      for (double h : half_extent)
        if (!(h >= 0) || !std::isfinite(h)) return "box half_extent must be >= 0";
      break;
    case Type::kHalfspace: {
      const double n = std::hypot(normal[0], normal[1], normal[2]);
      if (!(n > 0) || !std::isfinite(n)) return "half-space normal must be non-zero";
      break;
    }
    case Type::kSdf:
      if (!sdf) return "sdf mask has no grid";
      if (!(sdf_scale > 0) || !std::isfinite(sdf_scale)) return "sdf scale must be > 0";
      for (double c : center)
        if (!std::isfinite(c)) return "sdf center must be finite";
      break;
  }
  return {};
}

Vec3 ReadVec3(const JsonReader& r, const std::string& pointer) {
  const std::size_t n = r.array_size(pointer);
  if (n != 2 && n != 3) r.fail(pointer, "expected an array of 2 or 3 numbers, found " + std::to_string(n));
  Vec3 v{0, 0, 0};
  for (std::size_t a = 0; a < n; ++a) v[a] = r.number(pointer + "/" + std::to_string(a));
  return v;
}

Mask MaskFromJson(const JsonReader& r, const std::string& p, const std::string& base_dir, const MaskGridLoader& load) {
  Mask m;
  const std::string type = r.string(p + "/type");
  if (type == "sphere") {
    r.allow_keys(p, {"type", "center", "radius"});
    m.type = Mask::Type::kSphere;
    m.center = ReadVec3(r, p + "/center");
    m.radius = r.number(p + "/radius");
  } else if (type == "box") {
    r.allow_keys(p, {"type", "center", "half_extent"});
    m.type = Mask::Type::kBox;
    m.center = ReadVec3(r, p + "/center");
    m.half_extent = ReadVec3(r, p + "/half_extent");
  } else if (type == "halfspace") {
    r.allow_keys(p, {"type", "normal", "offset"});
    m.type = Mask::Type::kHalfspace;
    m.normal = ReadVec3(r, p + "/normal");
    m.offset = r.number(p + "/offset");
    const double n = std::hypot(m.normal[0], m.normal[1], m.normal[2]);
    if (!(n > 0)) r.fail(p + "/normal", "expected a non-zero vector");
    for (double& c : m.normal) c /= n;
    m.offset /= n;
  } else if (type == "sdf") {
    r.allow_keys(p, {"type", "file", "scale", "center"});
    m.type = Mask::Type::kSdf;
    m.sdf_path = r.string(p + "/file");
    std::filesystem::path path(m.sdf_path);
    if (path.is_relative() && !base_dir.empty()) path = std::filesystem::path(base_dir) / path;
    try {
      m.sdf = load ? load(path.string()) : std::make_shared<ScalarGrid>(ReadGrid(path.string()));
    } catch (const Error& e) {
      r.fail(p + "/file", e.what());
    }
    m.sdf_scale = r.number_or(p + "/scale", 1.0);
    if (r.has(p + "/center")) m.center = ReadVec3(r, p + "/center");
  } else {
    r.fail(p + "/type", "expected \"sphere\", \"box\", \"halfspace\" or \"sdf\", found \"" + type + "\"");
  }
  if (auto why = m.Validate(); !why.empty()) r.fail(p, why);
  return m;
}

json MaskToJson(const Mask& m) {
  auto v = [](const Vec3& x) { return json::array({x[0], x[1], x[2]}); };
  switch (m.type) {
    case Mask::Type::kSphere:
      return {{"type", "sphere"}, {"center", v(m.center)}, {"radius", m.radius}};
    case Mask::Type::kBox:
      return {{"type", "box"}, {"center", v(m.center)}, {"half_extent", v(m.half_extent)}};
    case Mask::Type::kHalfspace:
      return {{"type", "halfspace"}, {"normal", v(m.normal)}, {"offset", m.offset}};
    case Mask::Type::kSdf:
      return {{"type", "sdf"}, {"file", m.sdf_path}, {"scale", m.sdf_scale}, {"center", v(m.center)}};
  }
  return {};
}

// ---- noise ----

namespace {

inline std::uint64_t SplitMix(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

inline double Fade(double t) { return t * t * t * (t * (t * 6 - 15) + 10); }

// Gradient at a lattice point: one of Perlin's 12 cube-edge directions.
inline double Grad(std::uint64_t seed, long long i, long long j, long long k, double x, double y, double z) {
  const std::uint64_t h = SplitMix(seed ^ SplitMix(std::uint64_t(i) * 0x8da6b343ULL ^
                                                   SplitMix(std::uint64_t(j) * 0xd8163841ULL ^
                                                            std::uint64_t(k) * 0xcb1ab31fULL)));
  switch (h % 12) {
    case 0: return x + y;
    case 1: return -x + y;
    case 2: return x - y;
    case 3: return -x - y;
    case 4: return x + z;
    case 5: return -x + z;
    case 6: return x - z;
    case 7: return -x - z;
    case 8: return y + z;
    case 9: return -y + z;
    case 10: return y - z;
    default: return -y - z;
  }
}

}  // namespace

double GradientNoise::operator()(const Vec3& p) const {
  const double fx = std::floor(p[0]), fy = std::floor(p[1]), fz = std::floor(p[2]);
  const long long i = (long long)fx, j = (long long)fy, k = (long long)fz;
  const double x = p[0] - fx, y = p[1] - fy, z = p[2] - fz;
  const double u = Fade(x), v = Fade(y), w = Fade(z);
  auto g = [&](int a, int b, int c) { return Grad(seed_, i + a, j + b, k + c, x - a, y - b, z - c); };
  const double x00 = g(0, 0, 0) + u * (g(1, 0, 0) - g(0, 0, 0));
  const double x10 = g(0, 1, 0) + u * (g(1, 1, 0) - g(0, 1, 0));
  const double x01 = g(0, 0, 1) + u * (g(1, 0, 1) - g(0, 0, 1));
  const double x11 = g(0, 1, 1) + u * (g(1, 1, 1) - g(0, 1, 1));
  const double y0 = x00 + v * (x10 - x00), y1 = x01 + v * (x11 - x01);
  return y0 + w * (y1 - y0);
}

double GradientNoise::fbm(const Vec3& p, int octaves) const {
  double sum = 0.0, amp = 1.0, f = 1.0;
  for (int o = 0; o < octaves; ++o) {
    sum += amp * (*this)({p[0] * f, p[1] * f, p[2] * f});
    amp *= 0.5;
    f *= 2.0;
  }
  return sum;
}

Vec3 NoiseField::operator()(const Vec3& p) const {
  const Vec3 q{p[0] * frequency, p[1] * frequency, p[2] * frequency};
  return {GradientNoise(seed).fbm(q, octaves), GradientNoise(seed + 1).fbm(q, octaves),
          GradientNoise(seed + 2).fbm(q, octaves)};
}

// ---- parameter fields ----

double ParameterField::EvaluateRegions(const Vec3& p) const {
  double v = value;
  for (const Region& r : regions) {
    const double w = SmoothStep(-r.mask.distance(p) / r.feather + 0.5);
    v = (1.0 - w) * v + w * r.value;
  }
  return v;
}

std::string ParameterField::Validate(const std::string& name) const {
  if (!std::isfinite(value)) return name + " must be finite";
  for (const Region& r : regions) {
    if (!std::isfinite(r.value)) return name + ": region values must be finite";
    if (!(r.feather > 0)) return name + ": region feather must be > 0";
    if (auto why = r.mask.Validate(); !why.empty()) return name + ": " + why;
  }
  return {};
}

ParameterField ParameterFieldFromJson(const JsonReader& r, const std::string& p, const std::string& base_dir,
                                      const MaskGridLoader& load) {
  if (r.at(p).is_number()) return ParameterField(r.number(p));
  r.allow_keys(p, {"value", "regions"});
  ParameterField f(r.number(p + "/value"));
  if (r.has(p + "/regions")) {
    const std::size_t n = r.array_size(p + "/regions");
    for (std::size_t i = 0; i < n; ++i) {
      const std::string q = p + "/regions/" + std::to_string(i);
      r.allow_keys(q, {"mask", "value", "feather"});
      ParameterField::Region reg;
      reg.mask = MaskFromJson(r, q + "/mask", base_dir, load);
      reg.value = r.number(q + "/value");
      reg.feather = r.number(q + "/feather");
      if (!(reg.feather > 0)) r.fail(q + "/feather", "expected a number > 0");
      f.regions.push_back(std::move(reg));
    }
  }
  return f;
}

json ParameterFieldToJson(const ParameterField& f) {
  if (f.regions.empty()) return f.value;
  json regions = json::array();
  for (const auto& r : f.regions)
    regions.push_back({{"mask", MaskToJson(r.mask)}, {"value", r.value}, {"feather", r.feather}});
  return {{"value", f.value}, {"regions", regions}};
}

}  // namespace quijibo
