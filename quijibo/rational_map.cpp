#include "quijibo/rational_map.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "util/error.h"
#include "util/io.h"
#include "util/json_reader.h"

namespace quijibo {

using nlohmann::json;

Eigen::VectorXd RationalMap::variables() const {
  Eigen::VectorXd x(variable_count());
  x[VariableIndex::kLnC] = ln_C;
  x[VariableIndex::kTau] = tau;
  x[VariableIndex::kBeta] = beta;
  for (int i = 0; i < top_count(); ++i) x[VariableIndex::top(i)] = top_exponents[i];
  for (int i = 0; i < bottom_count(); ++i) x[VariableIndex::bottom(*this, i)] = bottom_exponents[i];
  return x;
}

void RationalMap::set_variables(const Eigen::VectorXd& x) {
  if (x.size() != variable_count())
    throw Error("variable vector has " + std::to_string(x.size()) + " entries, the map needs " +
                std::to_string(variable_count()));
  ln_C = x[VariableIndex::kLnC];
  tau = x[VariableIndex::kTau];
  beta = x[VariableIndex::kBeta];
  for (int i = 0; i < top_count(); ++i) top_exponents[i] = x[VariableIndex::top(i)];
  for (int i = 0; i < bottom_count(); ++i) bottom_exponents[i] = x[VariableIndex::bottom(*this, i)];
}

Eigen::VectorXd RationalMap::lower_bounds() const {
  Eigen::VectorXd lb = Eigen::VectorXd::Zero(variable_count());
  lb[VariableIndex::kLnC] = -std::numeric_limits<double>::infinity();
  return lb;
}

std::string RationalMap::Validate() const {
  if (top_roots.size() != top_exponents.size()) return "top roots and exponents differ in count";
  if (bottom_roots.size() != bottom_exponents.size())
    return "bottom roots and exponents differ in count";
  if (!std::isfinite(ln_C)) return "ln_C must be finite";
  if (!(tau >= 0 && std::isfinite(tau))) return "tau must be finite and >= 0";
  if (!(beta >= 0 && std::isfinite(beta))) return "beta must be finite and >= 0";
  auto check = [](const std::vector<Vec4>& roots, const std::vector<double>& e,
                  const char* which) -> std::string {
    for (std::size_t i = 0; i < roots.size(); ++i) {
      for (double c : roots[i])
        if (!std::isfinite(c)) return std::string(which) + " root " + std::to_string(i) + " is not finite";
      if (!(e[i] >= 0 && std::isfinite(e[i])))
        return std::string(which) + " exponent " + std::to_string(i) + " must be finite and >= 0";
    }
    return {};
  };
  if (auto s = check(top_roots, top_exponents, "top"); !s.empty()) return s;
  if (auto s = check(bottom_roots, bottom_exponents, "bottom"); !s.empty()) return s;
  if (leading_zero_roots) {
    const Vec4 zero{0, 0, 0, 0};
    if (top_roots.empty() || bottom_roots.empty() || top_roots[0] != zero || bottom_roots[0] != zero)
      return "leading_zero_roots is set but the first top and bottom roots are not at the origin";
  }
  return frame.Validate();
}

json MapToJson(const RationalMap& m) {
  json j;
  j["format"] = "quijibo-map";
  j["version"] = 1;
  j["frame"] = {{"fractal_radius", m.frame.fractal_radius},
                {"padding", m.frame.padding},
                {"scale", m.frame.scale},
                {"translation", m.frame.translation}};
  if (!m.frame.default_origin()) j["frame"]["origin"] = m.frame.origin;
  j["ln_C"] = m.ln_C;
  j["tau"] = m.tau;
  j["beta"] = m.beta;
  j["leading_zero_roots"] = m.leading_zero_roots;
  auto roots = [](const std::vector<Vec4>& r, const std::vector<double>& e) {
    json a = json::array();
    for (std::size_t i = 0; i < r.size(); ++i) a.push_back({{"root", r[i]}, {"exponent", e[i]}});
    return a;
  };
  j["top"] = roots(m.top_roots, m.top_exponents);
  j["bottom"] = roots(m.bottom_roots, m.bottom_exponents);
  j["provenance"] = m.provenance;
  return j;
}

RationalMap MapFromJson(const json& j, const std::string& source) {
  JsonReader r(j, source);
  if (!j.is_object()) r.fail("", "expected a JSON object (a quijibo map), found " + JsonReader::describe(j));
  r.allow_keys("", {"format", "version", "frame", "ln_C", "tau", "beta", "leading_zero_roots",
                    "top", "bottom", "provenance"});
  if (r.string("/format") != "quijibo-map") r.fail("/format", "expected \"quijibo-map\"");
  if (r.integer("/version") != 1) r.fail("/version", "expected 1 (the only version so far)");
  RationalMap m;
  if (r.has("/frame")) {
    r.allow_keys("/frame", {"fractal_radius", "padding", "scale", "translation", "origin"});
    m.frame.fractal_radius = r.number_or("/frame/fractal_radius", m.frame.fractal_radius);
    m.frame.padding = r.number_or("/frame/padding", m.frame.padding);
    m.frame.scale = r.number_or("/frame/scale", m.frame.scale);
    if (r.has("/frame/translation")) {
      if (r.array_size("/frame/translation") != 3)
        r.fail("/frame/translation", "expected an array of 3 numbers");
      for (int a = 0; a < 3; ++a)
        m.frame.translation[a] = r.number("/frame/translation/" + std::to_string(a));
    }
    if (r.has("/frame/origin")) {
      if (r.array_size("/frame/origin") != 3) r.fail("/frame/origin", "expected an array of 3 numbers");
      for (int a = 0; a < 3; ++a) m.frame.origin[a] = r.number("/frame/origin/" + std::to_string(a));
    }
    if (auto why = m.frame.Validate(); !why.empty()) r.fail("/frame", why);
  }
  m.ln_C = r.number("/ln_C");
  m.tau = r.number_at_least("/tau", 0.0);
  m.beta = r.number_at_least("/beta", 0.0);
  m.leading_zero_roots = r.boolean_or("/leading_zero_roots", false);
  auto roots = [&](const std::string& which, std::vector<Vec4>& pos, std::vector<double>& e) {
    const std::size_t n = r.array_size("/" + which);
    for (std::size_t i = 0; i < n; ++i) {
      const std::string p = "/" + which + "/" + std::to_string(i);
      r.allow_keys(p, {"root", "exponent"});
      const std::size_t k = r.array_size(p + "/root");
      if (k != 4 && k != 3)
        r.fail(p + "/root", "expected [x, y, z] or the quaternion [real, i, j, k], found " +
                                std::to_string(k) + " numbers");
      Vec4 q{0, 0, 0, 0};
      for (std::size_t c = 0; c < k; ++c) q[c] = r.number(p + "/root/" + std::to_string(c));
      pos.push_back(q);
      e.push_back(r.number_at_least(p + "/exponent", 0.0));
    }
  };
  roots("top", m.top_roots, m.top_exponents);
  roots("bottom", m.bottom_roots, m.bottom_exponents);
  if (r.has("/provenance")) m.provenance = r.at("/provenance");
  if (auto why = m.Validate(); !why.empty()) r.fail("", why);
  return m;
}

void WriteMap(const std::string& path, const RationalMap& map) {
  if (auto why = map.Validate(); !why.empty()) throw Error(path + ": refusing to write map: " + why);
  WriteFileAtomically(path, MapToJson(map).dump(1) + "\n");
}

RationalMap ReadMap(const std::string& path) {
  return MapFromJson(ParseJson(ReadFile(path), path), path);
}

std::string RandomMapOptions::Validate() const {
  if (top < 0 || bottom < 0) return "root counts must be >= 0";
  if (!(root_radius > 0)) return "root_radius must be > 0";
  if (!(exponent_min >= 0 && exponent_max >= exponent_min)) return "need 0 <= exponent_min <= exponent_max";
  if (leading_zero_roots && (top < 1 || bottom < 1)) return "leading zero roots need a top and a bottom root";
  return {};
}

RationalMap InFrame(const RationalMap& map, const FractalFrame& to) {
  if (auto why = to.Validate(); !why.empty()) throw Error("frame change: " + why);
  const FractalFrame& from = map.frame;
  if (to.scale != from.scale || to.translation != from.translation || to.padding != from.padding)
    throw Error("frame change: the new frame must keep the map's normalization (scale, translation, padding)");
  const double k = to.fractal_radius / from.fractal_radius;
  Vec4 b{0, 0, 0, 0};
  for (int a = 0; a < 3; ++a) b[a] = to.fractal_radius * (from.origin[a] - to.origin[a]);
  RationalMap m = map;
  m.frame = to;
  auto move = [&](std::vector<Vec4>& roots) {
    for (Vec4& r : roots)
      for (int a = 0; a < 4; ++a) r[a] = k * r[a] + b[a];
  };
  move(m.top_roots);
  move(m.bottom_roots);
  double top = 0, bottom = 0;
  for (double e : map.top_exponents) top += e;
  for (double e : map.bottom_exponents) bottom += e;
  m.ln_C = map.ln_C - (map.tau * top - map.beta * bottom) * std::log(k);
  if (b != Vec4{0, 0, 0, 0}) m.leading_zero_roots = false;
  if (!std::isfinite(m.ln_C)) throw Error("frame change: ln C is not finite in the new frame");
  return m;
}

FractalFrame ReferenceFrame(const FractalFrame& frame) {
  FractalFrame f = frame;
  f.origin = {0.5, 0.5, 0.5};
  f.fractal_radius = 3.0 / (1.0 - 2.0 * frame.padding);
  return f;
}

RationalMap IterationMap(const RationalMap& map, IterationFrame frame, double detail, double* lambda) {
  if (lambda) *lambda = 1.0;
  RationalMap m = detail == 0.0 ? map : WithDetail(map, detail, lambda);
  return frame == IterationFrame::kReference ? InFrame(m, ReferenceFrame(m.frame)) : m;
}

double SurfaceSteepness(const RationalMap& map, int lattice) {
  if (lattice < 2) throw Error("surface steepness: the lattice needs at least 2 nodes per axis");
  const double side = map.frame.fractal_radius * (1.0 - 2.0 * map.frame.padding);
  const Vec3 c = map.frame.box_center();
  const double step = side / (lattice - 1);
  auto node = [&](int i, int j, int k) {
    return Vec3{c[0] - side / 2 + i * step, c[1] - side / 2 + j * step, c[2] - side / 2 + k * step};
  };
  const std::int64_t n = lattice;
  std::vector<double> L(std::size_t(n * n * n));
#pragma omp parallel for schedule(static)
  for (std::int64_t id = 0; id < n * n * n; ++id)
    L[std::size_t(id)] = OneStepLogModulus(map, node(int(id % n), int((id / n) % n), int(id / (n * n))));
  // The crossings by linear interpolation along the edges, |grad L| there by central differences.
  std::vector<Vec3> crossings;
  for (std::int64_t id = 0; id < n * n * n; ++id) {
    const int i = int(id % n), j = int((id / n) % n), k = int(id / (n * n));
    const int next[3][3] = {{i + 1, j, k}, {i, j + 1, k}, {i, j, k + 1}};
    for (const auto& q : next) {
      if (q[0] >= lattice || q[1] >= lattice || q[2] >= lattice) continue;
      const double a = L[std::size_t(id)], b = L[std::size_t(q[0] + n * (q[1] + n * q[2]))];
      if (!std::isfinite(a) || !std::isfinite(b) || (a < 0) == (b < 0)) continue;
      const double t = a / (a - b);
      const Vec3 p = node(i, j, k), r = node(q[0], q[1], q[2]);
      crossings.push_back({p[0] + t * (r[0] - p[0]), p[1] + t * (r[1] - p[1]), p[2] + t * (r[2] - p[2])});
    }
  }
  if (crossings.empty()) return 0.0;
  const double h = step * 1e-3;
  std::vector<double> g(crossings.size());
#pragma omp parallel for schedule(static)
  for (std::int64_t m = 0; m < std::int64_t(crossings.size()); ++m) {
    double sq = 0;
    for (int a = 0; a < 3; ++a) {
      Vec3 lo = crossings[std::size_t(m)], hi = lo;
      lo[a] -= h, hi[a] += h;
      const double d = (OneStepLogModulus(map, hi) - OneStepLogModulus(map, lo)) / (2 * h);
      sq += d * d;
    }
    g[std::size_t(m)] = std::sqrt(sq);
  }
  std::nth_element(g.begin(), g.begin() + std::ptrdiff_t(g.size() / 2), g.end());
  return g[g.size() / 2];
}

RationalMap WithDetail(const RationalMap& map, double detail, double* lambda) {
  if (!(detail >= 0) || !std::isfinite(detail)) throw Error("detail must be a finite number >= 0");
  double l = 1.0;
  if (detail > 0) {
    const double width = detail / 100.0 * map.frame.fractal_radius * (1.0 - 2.0 * map.frame.padding);
    const double steep = SurfaceSteepness(map);
    if (steep > 0) l = 2.0 / (width * steep);
  }
  if (lambda) *lambda = l;
  RationalMap m = map;
  m.ln_C *= l, m.tau *= l, m.beta *= l;
  return m;
}

Vec4 TranslationForPotential(const RationalMap& iterated, const Vec3& direction, double potential) {
  const double norm = std::sqrt(direction[0] * direction[0] + direction[1] * direction[1] + direction[2] * direction[2]);
  if (!std::isfinite(norm) || !(norm > 0)) throw Error("translation by potential: the direction must be finite and non-zero");
  if (const std::string why = CheckRange("potential", SettingType::kNumber, potential, kTranslatePotentialRange);
      !why.empty())
    throw Error("translation by potential: " + why);
  const Vec3 u{direction[0] / norm, direction[1] / norm, direction[2] / norm};
  auto L = [&](double s) {
    const double v = OneStepLogModulus(iterated, Vec3{-s * u[0], -s * u[1], -s * u[2]});
    return std::isnan(v) ? std::numeric_limits<double>::infinity() : v;
  };
  const FractalFrame& f = iterated.frame;
  const double side = f.fractal_radius * (1.0 - 2.0 * f.padding);
  const Vec3 c = f.box_center();
  // Far enough to leave the shape box from the origin in any direction.
  const double reach = std::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]) + side * std::sqrt(3.0);
  const double at_origin = L(1e-9 * side);  // beside the origin: zero roots make L there -inf or NaN
  if (!(at_origin < potential))
    throw Error("translation by potential: L at the iteration frame's origin is " + std::to_string(at_origin) +
                ", not below the potential " + std::to_string(potential) +
                " asked for at -t: the origin is outside the set or too near its surface (give the translation "
                "itself, or iterate in the map's frame, whose origin a fit places deep inside the shape)");
  const double h = side / 2048;
  double lo = 0.0, hi = -1.0;
  for (double s = h; s <= reach; s += h) {
    if (L(s) >= potential) {
      hi = s;
      break;
    }
    lo = s;
  }
  if (hi < 0) throw Error("translation by potential: L stays below the potential along the whole ray");
  for (int i = 0; i < 60 && hi - lo > 1e-12 * side; ++i) {
    const double mid = 0.5 * (lo + hi);
    (L(mid) >= potential ? hi : lo) = mid;
  }
  const double s = 0.5 * (lo + hi);
  return {s * u[0], s * u[1], s * u[2], 0.0};
}

RationalMap RandomMap(const RandomMapOptions& o) {
  if (auto why = o.Validate(); !why.empty()) throw Error("random map: " + why);
  // mt19937_64 and hand-made uniform draws: std::uniform_real_distribution's output is not
  // specified bit-for-bit across standard libraries.
  std::mt19937_64 rng(o.seed);
  auto uniform = [&] { return double(rng() >> 11) * 0x1.0p-53; };
  auto root = [&] {
    for (;;) {
      Vec4 p{2 * uniform() - 1, 2 * uniform() - 1, 2 * uniform() - 1, 0.0};
      const double r2 = p[0] * p[0] + p[1] * p[1] + p[2] * p[2];
      if (r2 <= 1.0 && r2 > 0.0) {
        for (int a = 0; a < 3; ++a) p[a] *= o.root_radius;
        return p;
      }
    }
  };
  auto exponent = [&] { return o.exponent_min + (o.exponent_max - o.exponent_min) * uniform(); };
  RationalMap m;
  m.ln_C = o.ln_C;
  m.leading_zero_roots = o.leading_zero_roots;
  for (int i = 0; i < o.top; ++i) {
    const bool zero = o.leading_zero_roots && i == 0;
    m.top_roots.push_back(zero ? Vec4{0, 0, 0, 0} : root());
    m.top_exponents.push_back(zero ? 1.0 : exponent());
  }
  for (int i = 0; i < o.bottom; ++i) {
    const bool zero = o.leading_zero_roots && i == 0;
    m.bottom_roots.push_back(zero ? Vec4{0, 0, 0, 0} : root());
    m.bottom_exponents.push_back(zero ? 1.0 : exponent());
  }
  m.provenance = {{"made_by", "random"}, {"seed", o.seed}, {"top", o.top}, {"bottom", o.bottom},
                  {"root_radius", o.root_radius}, {"exponent_range", {o.exponent_min, o.exponent_max}}};
  return m;
}

}  // namespace quijibo
