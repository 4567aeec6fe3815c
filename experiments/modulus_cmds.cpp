// `quijibo modulus`, `quijibo portal`, `quijibo compare` and `quijibo bench modulus`: the shape
// modulus (2023) and portals (2024), in 2D (PNG) and 3D (PLY through the shared mesher), and a
// side-by-side comparison with a QUIJIBO map. Conventions: docs/modulus-portals.md.
#include <omp.h>
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <random>
#include <sstream>
#include <unordered_map>

#include "experiments/cli.h"
#include "experiments/modulus_cmds.h"
#include "mesh/julia_field.h"
#include "mesh/fidelity.h"
#include "mesh/marching_cubes.h"
#include "mesh/sdf.h"
#include "mesh/sdf_command.h"
#include "mesh/triangle_mesh.h"
#include "quijibo/energy.h"
#include "quijibo/error.h"
#include "quijibo/io.h"
#include "quijibo/json_reader.h"
#include "quijibo/quaternion_map.h"
#include "quijibo/modulus.h"
#include "quijibo/portal.h"
#include "quijibo/target.h"

namespace quijibo::cli {

using nlohmann::json;

namespace {

double Now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}
double CpuSeconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return double(u.ru_utime.tv_sec) + 1e-6 * u.ru_utime.tv_usec + double(u.ru_stime.tv_sec) + 1e-6 * u.ru_stime.tv_usec;
}

bool EndsWith(std::string s, const std::string& ext) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return s.size() >= ext.size() && s.compare(s.size() - ext.size(), ext.size(), ext) == 0;
}
bool IsMeshFile(const std::string& s) {
  return EndsWith(s, ".obj") || EndsWith(s, ".ply") || EndsWith(s, ".stl") || EndsWith(s, ".off");
}

// Files written by one command, removed again if a later step fails (no partial output).
class Outputs {
 public:
  void Add(const std::string& path) { written_.push_back(path); }
  void Rollback() {
    for (const auto& p : written_) std::filesystem::remove(p);
    written_.clear();
  }
  void Commit() { written_.clear(); }
  ~Outputs() { Rollback(); }

 private:
  std::vector<std::string> written_;
};

// A mesh in the unit frame (bounding box centred at the origin, longest side 100/110: the authors'
// set-up) and its signed distance on the cube [-0.5, 0.5]^3 at `sdf_resolution` cells.
std::shared_ptr<ScalarGrid> UnitFrameMeshSdf(const std::string& path, int sdf_resolution, TriangleMesh* unit_mesh,
                                             double* scale, Vec3* center) {
  MeshReadReport rep;
  TriangleMesh mesh = ReadMesh(path, &rep);
  const BoundingBox bb = ComputeBoundingBox(mesh);
  double longest = 0;
  for (int a = 0; a < 3; ++a) longest = std::max(longest, bb.max[a] - bb.min[a]);
  if (!(longest > 0)) throw Error(path + ": the mesh's bounding box is a point");
  const double s = kUnitFrameLongestSide / longest;
  Vec3 c;
  for (int a = 0; a < 3; ++a) c[a] = 0.5 * (bb.min[a] + bb.max[a]);
  for (Vec3& v : mesh.vertices)
    for (int a = 0; a < 3; ++a) v[a] = s * (v[a] - c[a]);
  SdfOptions so;
  so.name = path;
  auto grid = std::make_shared<ScalarGrid>(SignedDistance(mesh, GridFrame::Cube(sdf_resolution, {0, 0, 0}, 1.0), so));
  if (unit_mesh) *unit_mesh = std::move(mesh);
  if (scale) *scale = s;
  if (center) *center = c;
  return grid;
}

// What a loaded target is and how it maps to the unit frame.
struct LoadedTarget {
  ModulusTarget target;
  std::shared_ptr<ScalarGrid> grid;      // the SDF, when there is one
  double unit_per_grid = 1.0;            // unit-frame length per grid-frame length
  TriangleMesh mesh_unit;                // the target mesh in the unit frame (mesh targets only)
  json info = json::object();
};

// A mesh (normalized so its bbox is centred at the origin with longest side 100/110, SDF on the
// cube [-0.5, 0.5]^3 at `sdf_resolution`: the authors' set-up), a .qgrid from `quijibo sdf`
// (fractal frame, mapped into the unit frame with its frame file), or an analytic target.
LoadedTarget LoadModulusTarget(const std::string& spec, int sdf_resolution) {
  LoadedTarget t;
  if (IsMeshFile(spec)) {
    double s = 1;
    Vec3 c{0, 0, 0};
    t.grid = UnitFrameMeshSdf(spec, sdf_resolution, &t.mesh_unit, &s, &c);
    t.target = ModulusTargetFromUnitGrid(t.grid);
    t.info = {{"kind", "mesh"},
              {"file", spec},
              {"unit_frame", {{"scale", s}, {"mesh_center", {c[0], c[1], c[2]}}}},
              {"sdf_resolution", sdf_resolution}};
  } else if (EndsWith(spec, ".qgrid")) {
    t.grid = std::make_shared<ScalarGrid>(ReadGrid(spec));
    FractalFrame f;
    const std::string frame_path = FrameJsonPathFor(spec);
    const bool have_frame = std::filesystem::exists(frame_path);
    if (have_frame) f = ReadFrameJson(frame_path);
    t.target = ModulusTargetFromGrid(t.grid, f.fractal_radius, f.padding, &t.unit_per_grid);
    t.info = {{"kind", "qgrid"}, {"file", spec}, {"frame_file", have_frame ? frame_path : "(none: defaults)"},
              {"unit_per_fractal", t.unit_per_grid}};
  } else {
    t.target = AnalyticModulusTarget(spec);
    t.info = {{"kind", "analytic"}, {"spec", spec}};
  }
  t.target.name = spec;
  return t;
}

// The versor: a polynomial file, or a generated polynomial (roots in the target's box).
struct VersorArgs {
  std::string poly;
  int roots = 10;
  double min_power = 2, max_power = 12;
  bool real_powers = false;
  std::uint64_t seed = 1;
  std::string write_poly;
  double noise_frequency = 0;  // > 0: noise versor instead
  int noise_octaves = 1;
};

void AddVersorOptions(CLI::App* c, VersorArgs& v) {
  c->add_option("--poly", v.poly, "Versor polynomial JSON (else one is generated)");
  c->add_option("--roots", v.roots, "Generated: number of roots")->capture_default_str()->check(CLI::Range(1, 10000));
  c->add_option("--min-power", v.min_power, "Generated: smallest power")->capture_default_str();
  c->add_option("--max-power", v.max_power, "Generated: largest power (inclusive for integers)")->capture_default_str();
  c->add_flag("--real-powers", v.real_powers, "Generated: real powers in [min, max) instead of integers");
  c->add_option("--seed", v.seed, "Generated: seed")->capture_default_str();
  c->add_option("--write-poly", v.write_poly, "Write the (generated) polynomial here");
  c->add_option("--noise-versor", v.noise_frequency, "Use a noise versor of this frequency instead of a polynomial");
  c->add_option("--noise-octaves", v.noise_octaves, "Octaves of the noise versor")->capture_default_str()->check(CLI::Range(1, 16));
}

Versor MakeVersor(const VersorArgs& a, const ModulusTarget& target) {
  Versor v;
  if (a.noise_frequency > 0) {
    v.kind = Versor::Kind::kNoise;
    v.noise.frequency = a.noise_frequency;
    v.noise.octaves = a.noise_octaves;
    v.noise.seed = a.seed;
    return v;
  }
  if (!a.poly.empty()) {
    v.polynomial = ReadVersorPolynomial(a.poly);
    return v;
  }
  VersorGeneratorOptions g;
  g.roots = a.roots;
  g.min_power = a.min_power;
  g.max_power = a.max_power;
  g.integer_powers = !a.real_powers;
  g.seed = a.seed;
  g.box_min = target.box_min;
  g.box_max = target.box_max;
  v.polynomial = GenerateVersorPolynomial(g);
  v.polynomial.description = "generated for target " + target.name;
  return v;
}

// The Julia field of a map as a BatchField on points p (mesh frame): q = [s p, 0].
BatchField MakeField(std::shared_ptr<const QuaternionMap> map, const IterationOptions& o, double point_scale) {
  BatchField f;
  f.iso = 0.0;
  f.value_margin = kLogModulusValueMargin;
  f.evaluate = [map, o, point_scale](const Vec3* p, std::size_t n, double* out) {
    for (std::size_t i = 0; i < n; ++i)
      out[i] = IterateField(*map, {point_scale * p[i][0], point_scale * p[i][1], point_scale * p[i][2], 0.0}, o);
  };
  return f;
}

struct OutputArgs {
  std::string out;
  int resolution = 256;
  int png_size = 1600;
  std::vector<double> box;  // 4 (2D) or 6 (3D) numbers
  int iterations = 3;
  double escape = 20;
  MeshingOptions meshing;  // 3D: the shared mesher options (box and resolution set in Produce)
};

void AddOutputOptions(CLI::App* c, OutputArgs& o, bool required_out = true) {
  auto* opt = c->add_option("-o,--out", o.out, ".png (2D, complex plane) or .ply (3D mesh)");
  if (required_out) opt->required();
  c->add_option("-r,--resolution", o.resolution, "3D: marching cubes cells along the box's longest side")
      ->capture_default_str()->check(CLI::Range(4, 8192));
  c->add_option("--png-size", o.png_size, "2D: pixels per side")->capture_default_str()->check(CLI::Range(8, 32768));
  c->add_option("--box", o.box, "Region: x0 y0 x1 y1 (2D) or x0 y0 z0 x1 y1 z1 (3D), unit frame");
  c->add_option("--iterations", o.iterations, "Map applications")->capture_default_str()->check(CLI::Range(1, 100000));
  c->add_option("--escape", o.escape, "Escape radius")->capture_default_str();
  AddMesherOptions(c, o.meshing);
}

// Renders (2D) or meshes (3D) the field of `map`; returns a JSON report. Writes nothing.
struct Product {
  std::string kind;  // "png" or "ply"
  Image image{1, 1};
  TriangleMesh mesh;
  json report;
};

Product Produce(std::shared_ptr<const QuaternionMap> map, const OutputArgs& o, const ModulusTarget& target,
                bool two_d) {
  IterationOptions jo;
  jo.iterations = o.iterations;
  jo.escape_radius = o.escape;
  if (auto why = jo.validate(); !why.empty()) throw Error(why);
  Product p;
  const double t0 = Now(), c0 = CpuSeconds();
  // Default region: the target's box grown by 15% of its longest side on every side.
  double longest = 0;
  for (int a = 0; a < (two_d ? 2 : 3); ++a) longest = std::max(longest, target.box_max[a] - target.box_min[a]);
  if (two_d) {
    View2D v;
    if (!o.box.empty()) {
      if (o.box.size() != 4) throw Error("--box needs 4 numbers in 2D (x0 y0 x1 y1)");
      v.x_min = o.box[0], v.y_min = o.box[1], v.x_max = o.box[2], v.y_max = o.box[3];
    } else {
      const double half = 0.5 * longest * 1.3;
      const double cx = 0.5 * (target.box_min[0] + target.box_max[0]), cy = 0.5 * (target.box_min[1] + target.box_max[1]);
      v.x_min = cx - half, v.x_max = cx + half, v.y_min = cy - half, v.y_max = cy + half;
    }
    v.width = v.height = o.png_size;
    if (auto why = v.validate(); !why.empty()) throw Error(why);
    const std::vector<double> field = SampleField2D(*map, jo, v);
    std::int64_t inside = 0;
    for (double f : field) inside += f < 0;
    p.kind = "png";
    p.image = FieldImage(field, v, std::log(o.escape));
    p.report = {{"pixels", field.size()}, {"inside_pixels", inside}, {"view", {v.x_min, v.y_min, v.x_max, v.y_max}}};
  } else {
    MeshingOptions mo = o.meshing;
    if (!o.box.empty()) {
      if (o.box.size() != 6) throw Error("--box needs 6 numbers in 3D (x0 y0 z0 x1 y1 z1)");
      mo.min_corner = {o.box[0], o.box[1], o.box[2]};
      mo.max_corner = {o.box[3], o.box[4], o.box[5]};
    } else {
      for (int a = 0; a < 3; ++a) {
        mo.min_corner[a] = target.box_min[a] - 0.15 * longest;
        mo.max_corner[a] = target.box_max[a] + 0.15 * longest;
      }
    }
    mo.resolution = o.resolution;
    if (auto why = mo.validate(); !why.empty()) throw Error("meshing: " + why);
    MeshingSummary ms;
    p.mesh = MeshField(MakeField(map, jo, 1.0), mo, &ms);
    p.kind = "ply";
    p.report = MesherSummaryJson(ms, mo);
    p.report["box"] = {mo.min_corner[0], mo.min_corner[1], mo.min_corner[2], mo.max_corner[0], mo.max_corner[1], mo.max_corner[2]};
    p.report["resolution"] = mo.resolution;
    p.report["nodes_evaluated"] = ms.nodes_evaluated;
    p.report["bisection_evaluations"] = ms.bisection_evaluations;
    p.report["non_finite_values"] = ms.non_finite_values;
  }
  p.report["seconds"] = Now() - t0;
  p.report["cpu_seconds"] = CpuSeconds() - c0;
  p.report["iterations"] = o.iterations;
  p.report["escape_radius"] = o.escape;
  return p;
}

void WriteProduct(const Product& p, const std::string& path, Outputs& outs) {
  if (p.kind == "png") {
    if (!EndsWith(path, ".png")) throw Error("2D output must be a .png, found \"" + path + "\"");
    WritePng(path, p.image);
  } else {
    if (!EndsWith(path, ".ply")) throw Error("3D output must be a .ply, found \"" + path + "\"");
    WritePly(path, p.mesh);
  }
  outs.Add(path);
}

// ---------------------------------------------------------------- portal specs

struct PortalScene {
  std::shared_ptr<const QuaternionMap> map;
  ModulusTarget target;  // for the default region (and phi)
  bool two_d = false;
  json spec;             // the spec, as read or as built by the preset
  VersorPolynomial poly;  // when generated (to write with --write-poly)
  OutputArgs defaults;
};

// Builds the base map and portals from a spec document (format in docs/modulus-portals.md).
PortalScene SceneFromSpec(const json& doc, const std::string& source, int sdf_resolution) {
  JsonReader r(doc, source);
  if (!doc.is_object()) r.fail("", "expected a JSON object (a portal spec)");
  r.allow_keys("", {"format", "version", "description", "target", "map", "alpha", "beta", "origin_offset", "versor",
                    "iterations", "escape_radius", "box", "portals", "dimension"});
  if (r.string("/format") != "quijibo-portals") r.fail("/format", "expected \"quijibo-portals\"");
  if (r.integer("/version") != 1) r.fail("/version", "expected 1 (the only version so far)");
  const std::string dir = std::filesystem::path(source).parent_path().string();
  auto rel = [&](const std::string& p) {
    std::filesystem::path f(p);
    return (f.is_relative() && !dir.empty()) ? (std::filesystem::path(dir) / f).string() : p;
  };
  PortalScene s;
  s.spec = doc;
  const MaskGridLoader load_mask = MakeMaskGridLoader(sdf_resolution);
  std::shared_ptr<const QuaternionMap> base;
  std::function<double(const Quat&)> base_set;
  if (r.has("/map")) {
    if (r.has("/target")) r.fail("/map", "give either \"map\" (a QUIJIBO map) or \"target\", not both");
    auto rm = std::make_shared<RationalQuaternionMap>(ReadMap(rel(r.string("/map"))));
    base = rm;
    base_set = [rm](const Quat& q) { return rm->LogModulus(q); };
    s.target.box_min = {-1.5, -1.5, -1.5};
    s.target.box_max = {1.5, 1.5, 1.5};
    s.target.dimension = int(r.number_or("/dimension", 3));
  } else {
    const std::string t = r.string("/target");
    LoadedTarget lt = LoadModulusTarget(IsMeshFile(t) || EndsWith(t, ".qgrid") ? rel(t) : t, sdf_resolution);
    s.target = lt.target;
    if (r.has("/dimension")) s.target.dimension = int(r.integer("/dimension"));
    ShapeModulusOptions so;
    if (r.has("/alpha")) so.alpha = ParameterFieldFromJson(r, "/alpha", dir, load_mask);
    if (r.has("/beta")) so.beta = ParameterFieldFromJson(r, "/beta", dir, load_mask);
    if (r.has("/origin_offset")) so.origin_offset = ReadVec3(r, "/origin_offset");
    if (auto why = so.validate(); !why.empty()) r.fail("", why);
    Versor v;
    if (r.has("/versor")) {
      r.allow_keys("/versor", {"polynomial", "generate", "noise"});
      if (r.has("/versor/polynomial")) {
        v.polynomial = ReadVersorPolynomial(rel(r.string("/versor/polynomial")));
      } else if (r.has("/versor/noise")) {
        r.allow_keys("/versor/noise", {"frequency", "octaves", "seed"});
        v.kind = Versor::Kind::kNoise;
        v.noise.frequency = r.number_or("/versor/noise/frequency", 4.0);
        v.noise.octaves = int(r.number_or("/versor/noise/octaves", 1));
        v.noise.seed = std::uint64_t(r.number_or("/versor/noise/seed", 1));
      } else {
        const std::string g = "/versor/generate";
        VersorGeneratorOptions go;
        go.box_min = s.target.box_min;
        go.box_max = s.target.box_max;
        if (r.has(g)) {
          r.allow_keys(g, {"roots", "min_power", "max_power", "integer_powers", "seed"});
          go.roots = int(r.number_or(g + "/roots", go.roots));
          go.min_power = r.number_or(g + "/min_power", go.min_power);
          go.max_power = r.number_or(g + "/max_power", go.max_power);
          go.integer_powers = r.boolean_or(g + "/integer_powers", true);
          go.seed = std::uint64_t(r.number_or(g + "/seed", 1));
        }
        if (auto why = go.validate(); !why.empty()) r.fail(g, why);
        v.polynomial = GenerateVersorPolynomial(go);
        s.poly = v.polynomial;
      }
    } else {
      VersorGeneratorOptions go;
      go.box_min = s.target.box_min;
      go.box_max = s.target.box_max;
      v.polynomial = GenerateVersorPolynomial(go);
      s.poly = v.polynomial;
    }
    auto sm = std::make_shared<ShapeModulusMap>(s.target, v, so);
    base = sm;
    // The base set's signed function, in distance units: phi + beta (= log|f| / alpha).
    auto beta = so.beta;
    auto offset = so.origin_offset;
    auto phi = s.target.phi;
    base_set = [phi, beta, offset](const Quat& q) {
      const Vec3 x{q.w - offset[0], q.x - offset[1], q.y - offset[2]};
      return phi(x) + beta(x);
    };
  }
  s.two_d = s.target.dimension == 2;
  std::vector<Portal> portals;
  const std::size_t n = r.has("/portals") ? r.array_size("/portals") : 0;
  for (std::size_t i = 0; i < n; ++i) portals.push_back(PortalFromJson(r, "/portals/" + std::to_string(i), dir, load_mask));
  s.map = std::make_shared<PortalMap>(base, std::move(portals), base_set);
  s.defaults.iterations = int(r.number_or("/iterations", 20));
  s.defaults.escape = r.number_or("/escape_radius", 20.0);
  if (r.has("/box")) {
    const std::size_t k = r.array_size("/box");
    if (k != 4 && k != 6) r.fail("/box", "expected 4 (2D) or 6 (3D) numbers");
    for (std::size_t i = 0; i < k; ++i) s.defaults.box.push_back(r.number("/box/" + std::to_string(i)));
  }
  return s;
}

// The Koch snowflake preset (2024 Figs. 4, 7, 8): hexagram of side 1 plus six portals.
json KochSpec(double alpha, double beta, bool turbulent, double feather) {
  json portals = json::array();
  for (const Portal& p : KochPortals(1.0, feather)) portals.push_back(PortalToJson(p));
  json spec = {{"format", "quijibo-portals"},
               {"version", 1},
               {"description", std::string("Koch snowflake (2024 paper Figs. 4, 7") + (turbulent ? ", 8: turbulent)" : ")")},
               {"target", "hexagram:size=1"},
               {"alpha", alpha},
               {"beta", beta},
               {"iterations", 30},
               {"escape_radius", 20.0},
               {"box", {-0.62, -0.62, 0.62, 0.62}},
               {"portals", portals}};
  if (turbulent)
    spec["versor"] = {{"noise", {{"frequency", 6.0}, {"octaves", 2}, {"seed", 1}}}};
  else
    spec["versor"] = {{"generate", {{"roots", 10}, {"min_power", 2}, {"max_power", 12}, {"seed", 1}}}};
  return spec;
}

// ---------------------------------------------------------------- compare helpers

// Nearest-neighbour distances from points a to the point set b (uniform hash grid).
std::vector<double> NearestDistances(const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
  std::vector<double> out(a.size(), std::numeric_limits<double>::infinity());
  if (b.empty() || a.empty()) return out;
  Vec3 lo = b[0], hi = b[0];
  for (const Vec3& p : b)
    for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], p[k]), hi[k] = std::max(hi[k], p[k]);
  double vol = 1;
  for (int k = 0; k < 3; ++k) vol *= std::max(hi[k] - lo[k], 1e-9);
  const double cell = std::max(std::cbrt(vol / double(b.size())) * 2.0, 1e-9);
  auto key = [&](long long i, long long j, long long k) {
    return std::uint64_t(i) * 73856093ULL ^ std::uint64_t(j) * 19349663ULL ^ std::uint64_t(k) * 83492791ULL;
  };
  auto idx = [&](double x, int k) { return (long long)std::floor((x - lo[k]) / cell); };
  std::unordered_multimap<std::uint64_t, int> grid;
  grid.reserve(b.size());
  for (int i = 0; i < int(b.size()); ++i) grid.emplace(key(idx(b[i][0], 0), idx(b[i][1], 1), idx(b[i][2], 2)), i);
#pragma omp parallel for schedule(dynamic, 256)
  for (long long n = 0; n < (long long)a.size(); ++n) {
    const Vec3& p = a[n];
    const long long ci = idx(p[0], 0), cj = idx(p[1], 1), ck = idx(p[2], 2);
    double best2 = std::numeric_limits<double>::infinity();
    for (int r = 0; r < 100000; ++r) {
      // Scan the shell of cells at Chebyshev radius r; stop when no closer point can remain.
      for (long long i = ci - r; i <= ci + r; ++i)
        for (long long j = cj - r; j <= cj + r; ++j)
          for (long long k = ck - r; k <= ck + r; ++k) {
            if (std::max({std::llabs(i - ci), std::llabs(j - cj), std::llabs(k - ck)}) != r) continue;
            auto range = grid.equal_range(key(i, j, k));
            for (auto it = range.first; it != range.second; ++it) {
              const Vec3& q = b[it->second];
              const double d2 = (p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) + (p[2] - q[2]) * (p[2] - q[2]);
              best2 = std::min(best2, d2);
            }
          }
      if (std::isfinite(best2) && std::sqrt(best2) <= r * cell) break;
    }
    out[n] = std::sqrt(best2);
  }
  return out;
}

double Mean(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x;
  return v.empty() ? std::nan("") : s / double(v.size());
}

// The 2015 energy psi = (1/eta) sum_c -tanh(a L_c) W_c with the grid's weights.
double Psi(const EnergyGrid& g, const std::vector<double>& L, double a) {
  double s = 0;
  for (std::size_t c = 0; c < L.size(); ++c)
    if (std::isfinite(L[c])) s += -std::tanh(a * L[c]) * g.weight[c];
  return s / g.eta;
}

// z = 0 slice of a field on a grid box, inside black, the target's outline red.
Image SliceImage(const std::function<double(const Vec3&)>& field, const ScalarGrid& sdf, int size) {
  Image img(size, size);
  const Vec3 lo = sdf.frame.min_corner;
  const Vec3 e = sdf.frame.extent();
  const double side = std::max(e[0], e[1]);
  std::vector<double> f(std::size_t(size) * size), s(f.size());
#pragma omp parallel for schedule(dynamic, 4)
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      const Vec3 p{lo[0] + side * (x + 0.5) / size, lo[1] + side * (size - y - 0.5) / size, 0.0};
      f[std::size_t(y) * size + x] = field(p);
      s[std::size_t(y) * size + x] = ExtendedSample(sdf, p);
    }
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      const std::size_t i = std::size_t(y) * size + x;
      img.pixels[i] = f[i] < 0 ? Rgb{0, 0, 0} : Rgb{235, 235, 235};
      const bool edge = (x + 1 < size && (s[i] < 0) != (s[i + 1] < 0)) || (y + 1 < size && (s[i] < 0) != (s[i + size] < 0));
      if (edge) img.pixels[i] = {220, 30, 30};
    }
  return img;
}

}  // namespace

MaskGridLoader MakeMaskGridLoader(int sdf_resolution) {
  auto cache = std::make_shared<std::map<std::string, std::shared_ptr<const ScalarGrid>>>();
  return [cache, sdf_resolution](const std::string& path) -> std::shared_ptr<const ScalarGrid> {
    if (!IsMeshFile(path)) return std::make_shared<ScalarGrid>(ReadGrid(path));
    auto it = cache->find(path);
    if (it == cache->end()) it = cache->emplace(path, UnitFrameMeshSdf(path, sdf_resolution, nullptr, nullptr, nullptr)).first;
    return it->second;
  };
}

void ReadModulusParams(const std::string& path, ShapeModulusOptions& so, int sdf_resolution) {
  const json doc = ParseJson(ReadFile(path), path);
  JsonReader r(doc, path);
  if (!doc.is_object()) r.fail("", "expected a JSON object");
  r.allow_keys("", {"alpha", "beta", "origin_offset"});
  const std::string dir = std::filesystem::path(path).parent_path().string();
  const MaskGridLoader load = MakeMaskGridLoader(sdf_resolution);
  if (r.has("/alpha")) so.alpha = ParameterFieldFromJson(r, "/alpha", dir, load);
  if (r.has("/beta")) so.beta = ParameterFieldFromJson(r, "/beta", dir, load);
  if (r.has("/origin_offset")) so.origin_offset = ReadVec3(r, "/origin_offset");
  if (auto why = so.validate(); !why.empty()) r.fail("", why);
}

void AddModulusCommands(CLI::App& app) {
  // ------------------------------------------------------------------ modulus
  {
    struct Args {
      std::string target, params;
      int sdf_resolution = 100;
      double alpha = 30, beta = 0;
      std::vector<double> offset;
      std::vector<int> authors_frame;  // sdf resolution[, nodes]
      bool two_d = false;
      VersorArgs versor;
      OutputArgs out;
    };
    auto a = std::make_shared<Args>();
    CLI::App* c = app.add_subcommand("modulus",
                                     "Shape modulus Julia set (Schor and Kim 2023) of a target: 2D PNG or 3D PLY");
    c->add_option("target", a->target, "Mesh (.obj/.ply/.stl/.off), .qgrid from `quijibo sdf`, or sphere/disc/hexagram")
        ->required();
    c->add_option("--alpha", a->alpha, "Thinness alpha")->capture_default_str();
    c->add_option("--beta", a->beta, "Offset beta, paper's sign: exp(alpha (phi + beta))")->capture_default_str();
    c->add_option("--params", a->params, "JSON with alpha/beta fields and origin_offset (overrides --alpha/--beta)");
    c->add_option("--offset", a->offset, "Origin translation ox oy oz (2023 Fig. 5)")->expected(3);
    c->add_option("--sdf-resolution", a->sdf_resolution, "Mesh targets: SDF cells on [-0.5,0.5]^3")
        ->capture_default_str()->check(CLI::Range(8, 2048));
    c->add_flag("--2d", a->two_d, "Complex plane (slice z = 0 of a 3D target); implied by a .png output");
    c->add_option("--authors-frame", a->authors_frame,
                  "Compatibility: read the target the way the authors' code reads its SDF file (x and z swapped, "
                  "stretched by (NODES-1)/RES; docs/modulus-portals.md). RES = their sdfGen resolution, NODES = "
                  "nodes per side of their .f3d (default RES-1)")
        ->expected(1, 2)
        ->delimiter(',');
    AddVersorOptions(c, a->versor);
    AddOutputOptions(c, a->out);
    c->callback([a] {
      Outputs outs;
      LoadedTarget lt = LoadModulusTarget(a->target, a->sdf_resolution);
      const bool two_d = a->two_d || EndsWith(a->out.out, ".png") || lt.target.dimension == 2;
      if (two_d && !EndsWith(a->out.out, ".png")) throw Error("2D output must be a .png, found \"" + a->out.out + "\"");
      if (lt.target.dimension == 2 && !two_d) throw Error("a 2D target needs a .png output");
      lt.target.dimension = two_d ? 2 : 3;
      ShapeModulusOptions so;
      so.alpha = a->alpha;
      so.beta = a->beta;
      if (!a->offset.empty()) so.origin_offset = {a->offset[0], a->offset[1], a->offset[2]};
      if (!a->params.empty()) ReadModulusParams(a->params, so, a->sdf_resolution);
      const Versor v = MakeVersor(a->versor, lt.target);  // roots in the target's own frame
      if (!a->authors_frame.empty()) {
        if (two_d) throw Error("--authors-frame is for 3D targets");
        AuthorsFrame af;
        af.sdf_resolution = a->authors_frame[0];
        af.nodes = a->authors_frame.size() > 1 ? a->authors_frame[1] : af.sdf_resolution - 1;
        lt.target = InAuthorsFrame(lt.target, af);
        lt.info["authors_frame"] = {{"sdf_resolution", af.sdf_resolution}, {"nodes", af.nodes}};
      }
      auto map = std::make_shared<ShapeModulusMap>(lt.target, v, so);
      Product p = Produce(map, a->out, lt.target, two_d);
      if (!a->versor.write_poly.empty()) {
        if (v.kind != Versor::Kind::kPolynomial) throw Error("--write-poly needs a polynomial versor");
        WriteVersorPolynomial(a->versor.write_poly, v.polynomial);
        outs.Add(a->versor.write_poly);
      }
      WriteProduct(p, a->out.out, outs);
      outs.Commit();
      json rep = {{"command", "modulus"}, {"target", lt.info}, {"output", a->out.out}, {"result", p.report},
                  {"alpha", ParameterFieldToJson(so.alpha)}, {"beta", ParameterFieldToJson(so.beta)}};
      std::printf("%s\n", rep.dump(1).c_str());
    });
  }
  // ------------------------------------------------------------------ portal
  {
    struct Args {
      std::string spec, write_spec;
      bool koch = false, turbulent = false;
      double alpha = std::nan(""), beta = 0.0, feather = 0.005;
      int sdf_resolution = 100;
      std::string write_poly;
      OutputArgs out;
    };
    auto a = std::make_shared<Args>();
    CLI::App* c = app.add_subcommand("portal", "Portals (Schor and Kim 2024) in a shape modulus or QUIJIBO map: 2D PNG or 3D PLY");
    c->add_option("spec", a->spec, "Portal spec JSON (docs/modulus-portals.md)");
    c->add_flag("--koch", a->koch, "Preset: the Koch snowflake (hexagram + six portals, alpha 3000)");
    c->add_flag("--turbulent", a->turbulent, "With --koch: low alpha (30) and a noise versor (2024 Fig. 8)");
    c->add_option("--alpha", a->alpha, "Override the spec's alpha");
    c->add_option("--feather", a->feather, "With --koch: feather of the portal edges")->capture_default_str();
    c->add_option("--write-spec", a->write_spec, "Also write the spec used (e.g. the preset) here");
    c->add_option("--sdf-resolution", a->sdf_resolution, "Mesh targets: SDF cells on [-0.5,0.5]^3")->capture_default_str();
    c->add_option("--write-poly", a->write_poly, "Write the generated versor polynomial here");
    AddOutputOptions(c, a->out);
    auto* iters = c->get_option("--iterations");
    auto* escape = c->get_option("--escape");
    c->callback([a, iters, escape] {
      Outputs outs;
      json doc;
      std::string source;
      if (a->koch) {
        if (!a->spec.empty()) throw Error("give either a spec file or --koch, not both");
        doc = KochSpec(a->turbulent ? 30.0 : 3000.0, a->beta, a->turbulent, a->feather);
        source = "--koch preset";
      } else {
        if (a->spec.empty()) throw Error("a portal spec file (or --koch) is required");
        if (a->turbulent) throw Error("--turbulent goes with --koch");
        source = a->spec;
        doc = ParseJson(ReadFile(a->spec), a->spec);
      }
      if (!std::isnan(a->alpha)) doc["alpha"] = a->alpha;
      PortalScene s = SceneFromSpec(doc, source, a->sdf_resolution);
      OutputArgs o = a->out;
      if (iters->count() == 0) o.iterations = s.defaults.iterations;
      if (escape->count() == 0) o.escape = s.defaults.escape;
      if (o.box.empty()) o.box = s.defaults.box;
      if (!s.two_d && o.box.size() == 4) o.box.clear();
      if (s.two_d && !EndsWith(o.out, ".png")) throw Error("a 2D scene needs a .png output");
      if (!s.two_d && !EndsWith(o.out, ".ply")) throw Error("a 3D scene needs a .ply output");
      Product p = Produce(s.map, o, s.target, s.two_d);
      if (!a->write_spec.empty()) {
        WriteFileAtomically(a->write_spec, doc.dump(1) + "\n");
        outs.Add(a->write_spec);
      }
      if (!a->write_poly.empty()) {
        if (s.poly.roots.empty()) throw Error("--write-poly: the spec's versor is not a generated polynomial");
        WriteVersorPolynomial(a->write_poly, s.poly);
        outs.Add(a->write_poly);
      }
      WriteProduct(p, o.out, outs);
      outs.Commit();
      json rep = {{"command", "portal"}, {"spec", source}, {"output", o.out}, {"result", p.report}};
      std::printf("%s\n", rep.dump(1).c_str());
    });
  }
  // ------------------------------------------------------------------ compare
  {
    struct Args {
      std::string target, map, poly, out_dir, params;
      double alpha = 30, beta = -0.02, energy_alpha = 10, quijibo_seconds = std::nan("");
      int sm_iterations = 3, qj_iterations = 3, resolution = 128, samples = 100000, png_size = 512;
      double sm_escape = 20, qj_escape = 2000;
      std::string weights = "layer";
    };
    auto a = std::make_shared<Args>();
    CLI::App* c = app.add_subcommand(
        "compare", "QUIJIBO map vs shape modulus on one target: fit time, psi, IoU, Chamfer, pictures");
    c->add_option("--target", a->target, ".qgrid from `quijibo sdf` (fractal frame; its .frame.json is used)")->required();
    c->add_option("--map", a->map, "QUIJIBO map.json (fractal frame)")->required();
    c->add_option("--poly", a->poly, "Versor polynomial JSON (else generated, seed 1, in the target's box)");
    c->add_option("--params", a->params, "JSON with alpha/beta fields and origin_offset");
    c->add_option("--alpha", a->alpha, "Shape modulus alpha")->capture_default_str();
    c->add_option("--beta", a->beta, "Shape modulus beta (paper's sign)")->capture_default_str();
    c->add_option("--sm-iterations", a->sm_iterations, "Shape modulus iterations")->capture_default_str();
    c->add_option("--sm-escape", a->sm_escape, "Shape modulus escape radius")->capture_default_str();
    c->add_option("--quijibo-iterations", a->qj_iterations, "QUIJIBO iterations")->capture_default_str();
    c->add_option("--quijibo-escape", a->qj_escape, "QUIJIBO escape radius")->capture_default_str();
    c->add_option("--quijibo-seconds", a->quijibo_seconds, "QUIJIBO fit time (else summary.json next to the map)");
    c->add_option("--energy-alpha", a->energy_alpha, "tanh sharpness of psi (2015: 10)")->capture_default_str();
    c->add_option("--weights", a->weights, "Weight field of psi: layer or inverse")->capture_default_str();
    c->add_option("-r,--resolution", a->resolution, "Marching cubes cells along the grid box")->capture_default_str();
    c->add_option("--samples", a->samples, "Surface samples per mesh for Chamfer")->capture_default_str();
    c->add_option("--png-size", a->png_size, "Pixels of each slice picture")->capture_default_str();
    c->add_option("-o,--out", a->out_dir, "Output folder (compare.md, compare.json, PNGs, PLYs)")->required();
    c->callback([a] {
      Outputs outs;
      const auto grid = std::make_shared<ScalarGrid>(ReadGrid(a->target));
      const RationalMap rmap = ReadMap(a->map);
      // QUIJIBO fit time.
      json qj_fit = nullptr;
      if (!std::isnan(a->quijibo_seconds)) {
        qj_fit = a->quijibo_seconds;
      } else {
        const auto summary = std::filesystem::path(a->map).parent_path() / "summary.json";
        if (std::filesystem::exists(summary)) {
          const json sj = ParseJson(ReadFile(summary.string()), summary.string());
          JsonReader sr(sj, summary.string());
          if (sr.has("/seconds")) qj_fit = sr.number("/seconds");
        }
      }
      // Shape modulus "fit": load the target into the unit frame and get a versor.
      double t0 = Now();
      FractalFrame f;
      if (std::filesystem::exists(FrameJsonPathFor(a->target))) f = ReadFrameJson(FrameJsonPathFor(a->target));
      double k = 1;
      ModulusTarget target = ModulusTargetFromGrid(grid, f.fractal_radius, f.padding, &k);
      VersorArgs va;
      va.poly = a->poly;
      const Versor v = MakeVersor(va, target);
      ShapeModulusOptions so;
      so.alpha = a->alpha;
      so.beta = a->beta;
      if (!a->params.empty()) ReadModulusParams(a->params, so, 100);
      auto sm = std::make_shared<ShapeModulusMap>(target, v, so);
      const double sm_fit = Now() - t0;
      auto qj = std::make_shared<RationalQuaternionMap>(rmap);
      IterationOptions sjo{a->sm_iterations, a->sm_escape}, qjo{a->qj_iterations, a->qj_escape};
      if (auto why = sjo.validate(); !why.empty()) throw Error(why);
      if (auto why = qjo.validate(); !why.empty()) throw Error(why);
      // Fields on the grid (fractal frame): one application (the 2015 energy's L) and n iterates.
      const EnergyGrid eg = MakeEnergyGrid(*grid, ParseWeightField(a->weights));
      const std::int64_t cells = eg.frame.cell_count();
      std::vector<double> qj1(cells), qjn(cells), sm1(cells), smn(cells);
#pragma omp parallel for schedule(dynamic, 1024)
      for (std::int64_t c = 0; c < cells; ++c) {
        const Vec3 w = eg.frame.cell_center(c);
        const Quat qw{w[0], w[1], w[2], eg.slice}, qu{k * w[0], k * w[1], k * w[2], 0.0};
        qj1[c] = qj->LogModulus(qw);
        qjn[c] = IterateField(*qj, qw, qjo);
        sm1[c] = sm->LogModulus(qu);
        smn[c] = IterateField(*sm, qu, sjo);
      }
      auto iou = [&](const std::vector<double>& fld) {
        std::int64_t both = 0, either = 0;
        for (std::int64_t c = 0; c < cells; ++c) {
          const bool a1 = fld[c] < 0, b1 = grid->values[c] < 0;
          both += a1 && b1;
          either += a1 || b1;
        }
        return either ? double(both) / double(either) : 0.0;
      };
      // Meshes over the grid's box, in the fractal frame.
      MeshingOptions mo;
      mo.min_corner = grid->frame.min_corner;
      for (int ax = 0; ax < 3; ++ax) mo.max_corner[ax] = mo.min_corner[ax] + grid->frame.extent()[ax];
      mo.resolution = a->resolution;
      BatchField target_field;
      target_field.evaluate = [grid](const Vec3* p, std::size_t n, double* out) {
        for (std::size_t i = 0; i < n; ++i) out[i] = ExtendedSample(*grid, p[i]);
      };
      MeshingSummary ms_t, ms_q, ms_s;
      const TriangleMesh target_mesh = MeshField(target_field, mo, &ms_t);
      double m0 = Now(), c0 = CpuSeconds();
      const TriangleMesh qj_mesh = MeshField(MakeField(qj, qjo, 1.0), mo, &ms_q);
      const double qj_mesh_s = Now() - m0, qj_mesh_cpu = CpuSeconds() - c0;
      m0 = Now(), c0 = CpuSeconds();
      const TriangleMesh sm_mesh = MeshField(MakeField(sm, sjo, k), mo, &ms_s);
      const double sm_mesh_s = Now() - m0, sm_mesh_cpu = CpuSeconds() - c0;
      const auto ts = SampleSurface(target_mesh, a->samples, 1);
      auto chamfer = [&](const TriangleMesh& m) -> json {
        const auto ms = SampleSurface(m, a->samples, 2);
        if (ms.empty()) return {{"to_target", nullptr}, {"from_target", nullptr}, {"chamfer", nullptr}};
        const double to = Mean(NearestDistances(ms, ts)), from = Mean(NearestDistances(ts, ms));
        return {{"to_target", to}, {"from_target", from}, {"chamfer", to + from}};
      };
      const json qj_ch = chamfer(qj_mesh), sm_ch = chamfer(sm_mesh);
      const Image qj_img = SliceImage([&](const Vec3& p) { return IterateField(*qj, {p[0], p[1], p[2], 0}, qjo); }, *grid, a->png_size);
      const Image sm_img = SliceImage([&](const Vec3& p) { return IterateField(*sm, {k * p[0], k * p[1], k * p[2], 0}, sjo); }, *grid, a->png_size);
      auto method = [&](const std::string& name, json fit, double psi1, double psin, double io, const json& ch,
                        const TriangleMesh& m, double ms, double mcpu, const std::string& png, const std::string& ply) {
        return json{{"method", name}, {"fit_seconds", fit}, {"psi_one_application", psi1}, {"psi_iterated", psin},
                    {"iou", io}, {"chamfer", ch}, {"triangles", m.triangles.size()}, {"mesh_seconds", ms},
                    {"mesh_cpu_seconds", mcpu}, {"picture", png}, {"mesh", ply}};
      };
      const double diag = std::hypot(grid->frame.extent()[0], grid->frame.extent()[1], grid->frame.extent()[2]);
      json report = {
          {"target", a->target},
          {"map", a->map},
          {"grid", {{"dims", grid->frame.dims}, {"spacing", grid->frame.spacing}, {"box_diagonal", diag}}},
          {"energy", {{"alpha", a->energy_alpha}, {"weights", a->weights}, {"eta", eg.eta}}},
          {"mesh_resolution", a->resolution},
          {"unit_per_fractal", k},
          {"shape_modulus", {{"alpha", ParameterFieldToJson(so.alpha)}, {"beta", ParameterFieldToJson(so.beta)},
                             {"iterations", sjo.iterations}, {"escape_radius", sjo.escape_radius},
                             {"versor", v.polynomial.description}}},
          {"quijibo", {{"iterations", qjo.iterations}, {"escape_radius", qjo.escape_radius}}},
          {"target_mesh_triangles", target_mesh.triangles.size()},
          {"methods", json::array({method("QUIJIBO", qj_fit, Psi(eg, qj1, a->energy_alpha), Psi(eg, qjn, a->energy_alpha),
                                          iou(qjn), qj_ch, qj_mesh, qj_mesh_s, qj_mesh_cpu, "quijibo.png", "quijibo.ply"),
                                   method("shape modulus", sm_fit, Psi(eg, sm1, a->energy_alpha), Psi(eg, smn, a->energy_alpha),
                                          iou(smn), sm_ch, sm_mesh, sm_mesh_s, sm_mesh_cpu, "modulus.png", "modulus.ply")})}};
      // Markdown.
      std::ostringstream md;
      auto num = [](const json& j, int prec = 4) {
        if (j.is_null()) return std::string("n/a");
        char b[64];
        std::snprintf(b, sizeof b, "%.*g", prec, j.get<double>());
        return std::string(b);
      };
      md << "# QUIJIBO vs shape modulus on " << a->target << "\n\n"
         << "Map: `" << a->map << "`. Grid " << grid->frame.dims[0] << "x" << grid->frame.dims[1] << "x"
         << grid->frame.dims[2] << " (the target SDF's cells). psi: 2015 energy, tanh sharpness "
         << a->energy_alpha << ", " << a->weights << " weights. Chamfer in fractal-frame units (box diagonal "
         << num(diag) << "), mean nearest-sample distance each way, " << a->samples << " samples per mesh; meshes at "
         << a->resolution << " cells. Inside = log|q_n| < 0.\n\n"
         << "| | QUIJIBO | shape modulus |\n|---|---:|---:|\n";
      const json& q = report["methods"][0];
      const json& s = report["methods"][1];
      md << "| time to fit (s) | " << num(q["fit_seconds"]) << " | " << num(s["fit_seconds"]) << " |\n"
         << "| psi, one application (2015 energy) | " << num(q["psi_one_application"]) << " | " << num(s["psi_one_application"]) << " |\n"
         << "| psi, n iterates | " << num(q["psi_iterated"]) << " | " << num(s["psi_iterated"]) << " |\n"
         << "| IoU inside vs target (grid) | " << num(q["iou"]) << " | " << num(s["iou"]) << " |\n"
         << "| Chamfer to + from target | " << num(q["chamfer"]["chamfer"]) << " | " << num(s["chamfer"]["chamfer"]) << " |\n"
         << "| triangles | " << q["triangles"].get<std::size_t>() << " | " << s["triangles"].get<std::size_t>() << " |\n"
         << "| meshing wall / CPU (s) | " << num(q["mesh_seconds"]) << " / " << num(q["mesh_cpu_seconds"]) << " | "
         << num(s["mesh_seconds"]) << " / " << num(s["mesh_cpu_seconds"]) << " |\n"
         << "| picture (slice z = 0; red = target) | ![](quijibo.png) | ![](modulus.png) |\n";
      std::filesystem::create_directories(a->out_dir);
      auto path = [&](const std::string& n) { return (std::filesystem::path(a->out_dir) / n).string(); };
      WritePng(path("quijibo.png"), qj_img), outs.Add(path("quijibo.png"));
      WritePng(path("modulus.png"), sm_img), outs.Add(path("modulus.png"));
      WritePly(path("quijibo.ply"), qj_mesh), outs.Add(path("quijibo.ply"));
      TriangleMesh sm_fractal = sm_mesh;  // already in the fractal frame (points scaled by k inside the field)
      WritePly(path("modulus.ply"), sm_fractal), outs.Add(path("modulus.ply"));
      WriteFileAtomically(path("compare.json"), report.dump(1) + "\n"), outs.Add(path("compare.json"));
      WriteFileAtomically(path("compare.md"), md.str()), outs.Add(path("compare.md"));
      outs.Commit();
      std::printf("%s", md.str().c_str());
    });
  }
  // ------------------------------------------------------------------ bench modulus
  if (CLI::App* bench = app.get_subcommand("bench")) {
    struct Args {
      std::string target = "data/bunny.obj", poly = "data/sm-baseline-poly10.json", out_json;
      int resolution = 400, sdf_resolution = 100, repeats = 1, iterations = 3;
      double alpha = 30, beta = -0.02, escape = 20;
      bool mesh = false;
    };
    auto a = std::make_shared<Args>();
    CLI::App* b = bench->add_subcommand(
        "modulus", "Shape modulus field cost: dense res^3 evaluation (OpenMP), CPU seconds via getrusage");
    b->add_option("--target", a->target, "Target mesh")->capture_default_str();
    b->add_option("--poly", a->poly, "Versor polynomial")->capture_default_str();
    b->add_option("-r,--resolution", a->resolution, "Nodes per side of [-0.5,0.5]^3")->capture_default_str()->check(CLI::Range(2, 4096));
    b->add_option("--sdf-resolution", a->sdf_resolution, "SDF cells")->capture_default_str();
    b->add_option("--alpha", a->alpha, "alpha")->capture_default_str();
    b->add_option("--beta", a->beta, "beta (paper's sign)")->capture_default_str();
    b->add_option("--iterations", a->iterations, "iterations")->capture_default_str();
    b->add_option("--escape", a->escape, "escape radius")->capture_default_str();
    b->add_option("--repeats", a->repeats, "Repeats (median reported)")->capture_default_str()->check(CLI::Range(1, 20));
    b->add_flag("--mesh", a->mesh, "Also run MeshField at the same resolution and report CPU per triangle");
    b->add_option("--json", a->out_json, "Write the results here");
    b->callback([a] {
      LoadedTarget lt = LoadModulusTarget(a->target, a->sdf_resolution);
      Versor v;
      v.polynomial = ReadVersorPolynomial(a->poly);
      ShapeModulusOptions so;
      so.alpha = a->alpha;
      so.beta = a->beta;
      auto map = std::make_shared<ShapeModulusMap>(lt.target, v, so);
      IterationOptions jo{a->iterations, a->escape};
      const int n = a->resolution;
      // The authors' node placement: min + i span / res, i < res, on [-0.5, 0.5]^3.
      std::vector<double> wall, cpu;
      std::int64_t inside = 0;
      std::vector<std::int64_t> iters(a->iterations + 1, 0);
      for (int rep = 0; rep < a->repeats; ++rep) {
        const double w0 = Now(), c0 = CpuSeconds();
        std::int64_t in = 0;
        std::vector<std::int64_t> it(a->iterations + 1, 0);
#pragma omp parallel
        {
          std::vector<std::int64_t> local(a->iterations + 1, 0);
          std::int64_t lin = 0;
#pragma omp for schedule(dynamic, 1) collapse(2)
          for (int z = 0; z < n; ++z)
            for (int y = 0; y < n; ++y)
              for (int x = 0; x < n; ++x) {
                int used = 0;
                const double f = IterateField(*map, {-0.5 + double(x) / n, -0.5 + double(y) / n, -0.5 + double(z) / n, 0.0}, jo, &used);
                lin += f < 0;
                ++local[used];
              }
#pragma omp critical
          {
            in += lin;
            for (int i = 0; i <= a->iterations; ++i) it[i] += local[i];
          }
        }
        wall.push_back(Now() - w0);
        cpu.push_back(CpuSeconds() - c0);
        inside = in;
        iters = it;
      }
      auto median = [](std::vector<double> x) {
        std::sort(x.begin(), x.end());
        return x[x.size() / 2];
      };
      const double nodes = double(n) * n * n;
      json rep = {{"target", a->target}, {"poly", a->poly}, {"resolution", n}, {"nodes", nodes},
                  {"alpha", a->alpha}, {"beta", a->beta}, {"iterations", a->iterations}, {"escape_radius", a->escape},
                  {"repeats", a->repeats}, {"threads", omp_get_max_threads()},
                  {"wall_seconds_median", median(wall)}, {"cpu_seconds_median", median(cpu)},
                  {"cpu_us_per_node", 1e6 * median(cpu) / nodes}, {"inside_nodes", inside},
                  {"iterations_histogram", iters}};
      if (a->mesh) {
        MeshingOptions mo;
        mo.min_corner = {-0.5, -0.5, -0.5};
        mo.max_corner = {0.5, 0.5, 0.5};
        mo.resolution = n;
        MeshingSummary ms;
        const double w0 = Now(), c0 = CpuSeconds();
        const TriangleMesh m = MeshField(MakeField(map, jo, 1.0), mo, &ms);
        const double w = Now() - w0, c = CpuSeconds() - c0;
        rep["mesh"] = {{"triangles", m.triangles.size()}, {"wall_seconds", w}, {"cpu_seconds", c},
                       {"cpu_us_per_triangle", 1e6 * c / std::max<double>(1, m.triangles.size())},
                       {"reference_cpu_us_per_triangle", 1e6 * 338.1 / 2381944},
                       {"nodes_evaluated", ms.nodes_evaluated}, {"bisection_evaluations", ms.bisection_evaluations},
                       {"summary", ms.report()}};
      }
      if (!a->out_json.empty()) WriteFileAtomically(a->out_json, rep.dump(1) + "\n");
      std::printf("%s\n", rep.dump(1).c_str());
    });
  }
}

}  // namespace quijibo::cli
