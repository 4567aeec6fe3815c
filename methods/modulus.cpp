#include "methods/modulus.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <random>

#include "util/error.h"
#include "util/io.h"
#include "util/json_reader.h"

namespace quijibo {

using nlohmann::json;

// ---- targets ----

namespace {

ModulusTarget FromGrid(std::shared_ptr<const ScalarGrid> grid, double k) {
  ModulusTarget t;
  t.dimension = 3;
  // Box of the inside cells (phi < 0), in the unit frame.
  Vec3 lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
  const GridFrame& f = grid->frame;
  for (int kk = 0; kk < f.dims[2]; ++kk)
    for (int j = 0; j < f.dims[1]; ++j)
      for (int i = 0; i < f.dims[0]; ++i)
        if (grid->at(i, j, kk) < 0) {
          const Vec3 c = f.cell_center(i, j, kk);
          for (int a = 0; a < 3; ++a) {
            lo[a] = std::min(lo[a], c[a]);
            hi[a] = std::max(hi[a], c[a]);
          }
        }
  if (lo[0] > hi[0]) throw Error("target SDF has no inside cell (phi < 0)");
  for (int a = 0; a < 3; ++a) {
    t.box_min[a] = k * (lo[a] - 0.5 * f.spacing);
    t.box_max[a] = k * (hi[a] + 0.5 * f.spacing);
  }
  t.phi = [grid, k](const Vec3& u) { return k * ExtendedSample(*grid, {u[0] / k, u[1] / k, u[2] / k}); };
  t.name = "grid";
  return t;
}

std::map<std::string, double> ParseParams(const std::string& spec, std::string& name) {
  std::map<std::string, double> out;
  const auto colon = spec.find(':');
  name = spec.substr(0, colon);
  if (colon == std::string::npos) return out;
  std::string rest = spec.substr(colon + 1);
  std::size_t pos = 0;
  while (pos < rest.size()) {
    std::size_t comma = rest.find(',', pos);
    if (comma == std::string::npos) comma = rest.size();
    const std::string kv = rest.substr(pos, comma - pos);
    const auto eq = kv.find('=');
    if (eq == std::string::npos) throw Error("target \"" + spec + "\": expected key=value, found \"" + kv + "\"");
    try {
      out[kv.substr(0, eq)] = std::stod(kv.substr(eq + 1));
    } catch (const std::exception&) {
      throw Error("target \"" + spec + "\": \"" + kv.substr(eq + 1) + "\" is not a number");
    }
    pos = comma + 1;
  }
  return out;
}

}  // namespace

ModulusTarget ModulusTargetFromGrid(std::shared_ptr<const ScalarGrid> grid, double fractal_radius, double padding,
                                    double* scale) {
  if (!(fractal_radius > 0) || !(padding >= 0 && padding < 0.5)) throw Error("invalid fractal frame of the target");
  const double k = kUnitFrameLongestSide / (fractal_radius * (1.0 - 2.0 * padding));
  if (scale) *scale = k;
  return FromGrid(std::move(grid), k);
}

ModulusTarget ModulusTargetFromUnitGrid(std::shared_ptr<const ScalarGrid> grid) { return FromGrid(std::move(grid), 1.0); }

std::string AuthorsFrame::Validate() const {
  if (sdf_resolution < 1) return "authors' frame: the SDF resolution must be >= 1";
  if (nodes != 0 && nodes < 2) return "authors' frame: the node count must be >= 2 (or 0: the SDF resolution)";
  if (node_count() < 2) return "authors' frame: the node count (the SDF resolution) must be >= 2";
  if (!(unit_scale > 0) || !std::isfinite(unit_scale)) return "authors' frame: the unit scale must be a positive number";
  return {};
}

ModulusTarget InAuthorsFrame(const ModulusTarget& target, const AuthorsFrame& frame) {
  if (auto why = frame.Validate(); !why.empty()) throw Error(why);
  if (target.dimension != 3) throw Error("authors' frame: only for 3D targets");
  const double stretch = double(frame.node_count() - 1) / double(frame.sdf_resolution);
  auto g = [stretch](double t) { return -0.5 + (std::clamp(t, -0.5, 0.5) + 0.5) * stretch; };
  auto g_inverse = [stretch](double u) { return -0.5 + (u + 0.5) / stretch; };
  ModulusTarget out = target;
  out.phi = [phi = target.phi, g](const Vec3& p) { return phi({g(p[2]), g(p[1]), g(p[0])}); };
  for (int a = 0; a < 3; ++a) {
    out.box_min[a] = std::clamp(g_inverse(target.box_min[2 - a]), -0.5, 0.5);
    out.box_max[a] = std::clamp(g_inverse(target.box_max[2 - a]), -0.5, 0.5);
  }
  out.name = target.name + " (authors' frame)";
  return out;
}

ShapeModulusOptions AuthorsParameters(const ShapeModulusOptions& theirs, const AuthorsFrame& frame) {
  if (auto why = frame.Validate(); !why.empty()) throw Error(why);
  const double s = frame.unit_scale;
  auto scaled = [](ParameterField f, double k) {
    f.value = f.value * k + 0.0;  // + 0.0: a zero stays +0 (no "-0" in reports)
    for (ParameterField::Region& r : f.regions) r.value = r.value * k + 0.0;
    return f;
  };
  ShapeModulusOptions out = theirs;
  out.alpha = scaled(theirs.alpha, 1.0 / s);
  out.beta = scaled(theirs.beta, -s);
  return out;
}

double PolygonSdf(const std::vector<std::array<double, 2>>& poly, double x, double y) {
  double d2 = 1e300;
  bool inside = false;
  const std::size_t n = poly.size();
  for (std::size_t i = 0, j = n - 1; i < n; j = i++) {
    const double ax = poly[j][0], ay = poly[j][1], bx = poly[i][0], by = poly[i][1];
    const double ex = bx - ax, ey = by - ay, wx = x - ax, wy = y - ay;
    const double len2 = ex * ex + ey * ey;
    const double t = len2 > 0 ? std::clamp((wx * ex + wy * ey) / len2, 0.0, 1.0) : 0.0;
    const double dx = wx - t * ex, dy = wy - t * ey;
    d2 = std::min(d2, dx * dx + dy * dy);
    if ((ay > y) != (by > y) && x < ax + (y - ay) * ex / ey) inside = !inside;
  }
  const double d = std::sqrt(d2);
  return inside ? -d : d;
}

std::vector<std::array<double, 2>> HexagramPolygon(double s) {
  // Outer tips at the triangles' vertices (circumradius s/sqrt3), inner corners at the hexagon's
  // vertices (radius s/3), alternating, starting with the tip pointing up.
  std::vector<std::array<double, 2>> p;
  const double R = s / std::sqrt(3.0), r = s / 3.0;
  for (int i = 0; i < 12; ++i) {
    const double a = M_PI / 2 + i * M_PI / 6;
    const double rad = (i % 2 == 0) ? R : r;
    p.push_back({rad * std::cos(a), rad * std::sin(a)});
  }
  return p;
}

std::vector<double> ModulusRegion(const ModulusTarget& target, bool two_d) {
  double longest = 0;
  for (int a = 0; a < (two_d ? 2 : 3); ++a) longest = std::max(longest, target.box_max[a] - target.box_min[a]);
  if (two_d) {
    const double half = 0.5 * longest * 1.3;
    const double cx = 0.5 * (target.box_min[0] + target.box_max[0]), cy = 0.5 * (target.box_min[1] + target.box_max[1]);
    return {cx - half, cy - half, cx + half, cy + half};
  }
  std::vector<double> box(6);
  for (int a = 0; a < 3; ++a) {
    box[a] = target.box_min[a] - 0.15 * longest;
    box[3 + a] = target.box_max[a] + 0.15 * longest;
  }
  return box;
}

ModulusTarget AnalyticModulusTarget(const std::string& spec) {
  std::string name;
  auto params = ParseParams(spec, name);
  auto take = [&](const std::string& key, double fallback) {
    auto it = params.find(key);
    if (it == params.end()) return fallback;
    const double v = it->second;
    params.erase(it);
    if (!(v > 0)) throw Error("target \"" + spec + "\": " + key + " must be > 0");
    return v;
  };
  ModulusTarget t;
  t.name = spec;
  if (name == "sphere") {
    const double r = take("radius", kUnitFrameLongestSide / 2);
    t.phi = [r](const Vec3& p) { return std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]) - r; };
    t.box_min = {-r, -r, -r};
    t.box_max = {r, r, r};
  } else if (name == "disc") {
    const double r = take("radius", kUnitFrameLongestSide / 2);
    t.dimension = 2;
    t.phi = [r](const Vec3& p) { return std::hypot(p[0], p[1]) - r; };
    t.box_min = {-r, -r, 0};
    t.box_max = {r, r, 0};
  } else if (name == "hexagram") {
    const double s = take("size", 1.0);
    t.dimension = 2;
    auto poly = HexagramPolygon(s);
    t.phi = [poly](const Vec3& p) { return PolygonSdf(poly, p[0], p[1]); };
    const double R = s / std::sqrt(3.0);
    t.box_min = {-R, -R, 0};
    t.box_max = {R, R, 0};
  } else {
    throw Error("unknown analytic target \"" + name + "\" (expected sphere, disc or hexagram)");
  }
  if (!params.empty()) throw Error("target \"" + spec + "\": unknown parameter \"" + params.begin()->first + "\"");
  return t;
}

// ---- versor polynomial ----

std::string VersorPolynomial::Validate() const {
  if (roots.empty()) return "the versor polynomial has no root";
  if (roots.size() != powers.size())
    return "roots and powers differ in number (" + std::to_string(roots.size()) + " vs " +
           std::to_string(powers.size()) + ")";
  for (const Vec4& r : roots)
    for (double c : r)
      if (!std::isfinite(c)) return "root coordinates must be finite";
  for (double p : powers)
    if (!std::isfinite(p)) return "powers must be finite";
  if (!std::isfinite(power_scalar)) return "power_scalar must be finite";
  return {};
}

std::string VersorGeneratorOptions::Validate() const {
  if (roots < 1 || roots > 10000) return "root count must be in [1, 10000]";
  if (!(min_power <= max_power) || !std::isfinite(min_power) || !std::isfinite(max_power))
    return "need min_power <= max_power";
  if (integer_powers && (min_power != std::floor(min_power) || max_power != std::floor(max_power)))
    return "integer powers need integer min_power and max_power";
  for (int a = 0; a < 3; ++a)
    if (!(box_min[a] <= box_max[a])) return "box_min must be <= box_max";
  return {};
}

VersorPolynomial GenerateVersorPolynomial(const VersorGeneratorOptions& o) {
  if (auto why = o.Validate(); !why.empty()) throw Error("versor polynomial: " + why);
  std::mt19937_64 rng(o.seed);
  auto uniform = [&] { return double(rng() >> 11) * 0x1.0p-53; };  // [0, 1)
  VersorPolynomial p;
  for (int i = 0; i < o.roots; ++i) {
    Vec4 r{0, 0, 0, 0};
    for (int a = 0; a < 3; ++a) r[a] = o.box_min[a] + (o.box_max[a] - o.box_min[a]) * uniform();
    p.roots.push_back(r);
    const double u = uniform();
    if (o.integer_powers) {
      const double span = o.max_power - o.min_power + 1.0;
      p.powers.push_back(std::min(o.max_power, o.min_power + std::floor(u * span)));
    } else {
      p.powers.push_back(o.min_power + (o.max_power - o.min_power) * u);
    }
  }
  p.description = "random versor polynomial (quijibo GenerateVersorPolynomial)";
  p.generator = {{"roots", o.roots},
                 {"min_power", o.min_power},
                 {"max_power", o.max_power},
                 {"integer_powers", o.integer_powers},
                 {"box_min", {o.box_min[0], o.box_min[1], o.box_min[2]}},
                 {"box_max", {o.box_max[0], o.box_max[1], o.box_max[2]}},
                 {"seed", o.seed},
                 {"rng", "mt19937_64, u = (x >> 11) * 2^-53"}};
  return p;
}

json VersorPolynomialToJson(const VersorPolynomial& p) {
  json roots = json::array();
  for (const Vec4& r : p.roots) roots.push_back({r[0], r[1], r[2], r[3]});
  json j = {{"format", "quijibo-versor-polynomial"}, {"version", 1}, {"description", p.description},
            {"roots", roots},  {"powers", p.powers},   {"power_scalar", p.power_scalar}};
  if (!p.generator.empty()) j["generator"] = p.generator;
  return j;
}

VersorPolynomial VersorPolynomialFromJson(const json& j, const std::string& source) {
  JsonReader r(j, source);
  if (!j.is_object()) r.fail("", "expected a JSON object (a versor polynomial), found " + JsonReader::describe(j));
  r.allow_keys("", {"format", "version", "description", "roots", "powers", "power_scalar", "generator"});
  if (r.has("/format") && r.string("/format") != "quijibo-versor-polynomial")
    r.fail("/format", "expected \"quijibo-versor-polynomial\"");
  if (r.has("/version") && r.integer("/version") != 1) r.fail("/version", "expected 1 (the only version so far)");
  VersorPolynomial p;
  p.description = r.string_or("/description", "");
  const std::size_t n = r.array_size("/roots");
  if (n == 0) r.fail("/roots", "expected at least one root");
  for (std::size_t i = 0; i < n; ++i) {
    const std::string q = "/roots/" + std::to_string(i);
    const std::size_t k = r.array_size(q);
    if (k != 3 && k != 4) r.fail(q, "expected [w, x, y] or [w, x, y, z], found " + std::to_string(k) + " numbers");
    Vec4 v{0, 0, 0, 0};
    for (std::size_t a = 0; a < k; ++a) v[a] = r.number(q + "/" + std::to_string(a));
    p.roots.push_back(v);
  }
  const std::size_t m = r.array_size("/powers");
  if (m != n) r.fail("/powers", "expected " + std::to_string(n) + " powers (one per root), found " + std::to_string(m));
  for (std::size_t i = 0; i < m; ++i) p.powers.push_back(r.number("/powers/" + std::to_string(i)));
  p.power_scalar = r.number_or("/power_scalar", 1.0);
  if (r.has("/generator")) p.generator = r.at("/generator");
  if (auto why = p.Validate(); !why.empty()) r.fail("", why);
  return p;
}

void WriteVersorPolynomial(const std::string& path, const VersorPolynomial& p) {
  WriteFileAtomically(path, VersorPolynomialToJson(p).dump(1) + "\n");
}

VersorPolynomial ReadVersorPolynomial(const std::string& path) {
  return VersorPolynomialFromJson(ParseJson(ReadFile(path), path), path);
}

// ---- the map ----

std::string ShapeModulusOptions::Validate() const {
  if (auto why = alpha.Validate("alpha"); !why.empty()) return why;
  if (auto why = beta.Validate("beta"); !why.empty()) return why;
  for (double c : origin_offset)
    if (!std::isfinite(c)) return "origin offset must be finite";
  return {};
}

ShapeModulusMap::ShapeModulusMap(ModulusTarget target, const Versor& versor, const ShapeModulusOptions& options)
    : target_(std::move(target)), kind_(versor.kind), noise_(versor.noise), options_(options) {
  if (!target_.phi) throw Error("shape modulus: the target has no signed distance");
  if (auto why = options_.Validate(); !why.empty()) throw Error("shape modulus: " + why);
  if (kind_ == Versor::Kind::kPolynomial) {
    if (auto why = versor.polynomial.Validate(); !why.empty()) throw Error("shape modulus: " + why);
    for (std::size_t i = 0; i < versor.polynomial.roots.size(); ++i) {
      const Vec4& r = versor.polynomial.roots[i];
      roots_.push_back(target_.dimension == 2 ? Quat{r[0], r[1], 0, 0} : Quat{r[0], r[1], r[2], r[3]});
      powers_.push_back(versor.polynomial.powers[i] * versor.polynomial.power_scalar);
    }
  }
  offset4_ = {options_.origin_offset[0], options_.origin_offset[1], options_.origin_offset[2], 0.0};
}

double ShapeModulusMap::LogModulus(const Quat& q) const {
  const Vec3 x = Point(q);
  return options_.alpha(x) * (target_.phi(x) + options_.beta(x));
}

Quat ShapeModulusMap::Direction(const Quat& q0) const {
  const Quat q{q0.w - offset4_[0], q0.x - offset4_[1], q0.y - offset4_[2], q0.z};
  Quat d{1, 0, 0, 0};
  if (kind_ == Versor::Kind::kPolynomial) {
    for (std::size_t i = 0; i < roots_.size(); ++i) {
      const Quat e = q - roots_[i];
      const double n2 = e.norm2();
      if (n2 > 0) d = d * UnitPower(e * (1.0 / std::sqrt(n2)), powers_[i]);
    }
  } else {
    const Vec3 v = noise_({q.w, q.x, q.y});
    d = target_.dimension == 2 ? Quat{v[0], v[1], 0, 0} : Quat{v[0], v[1], v[2], 0};
  }
  // Renormalize (rounding drift); fall back to q's own direction, then to 1 (a root hit exactly,
  // or the noise vanished), as the authors' code does.
  double n2 = d.norm2();
  if (n2 > 0 && std::isfinite(n2)) return d * (1.0 / std::sqrt(n2));
  n2 = q.norm2();
  if (n2 > 0 && std::isfinite(n2)) return q * (1.0 / std::sqrt(n2));
  return {1, 0, 0, 0};
}

Quat ShapeModulusMap::Apply(const Quat& q) const { return Direction(q) * std::exp(LogModulus(q)); }

}  // namespace quijibo
