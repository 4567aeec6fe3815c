// The shape modulus map (Schor and Kim, SGP 2023, §3.1):
//
//   f(q) = r(q) d(q),   r(q) = exp(alpha(x) (phi(x) + beta(x))),   d(q) = p(q) / |p(q)|
//
// phi is the target's signed distance (negative inside), read at x = (q.w, q.x, q.y): the k
// component is dropped (the paper's choice), and 3D points are the slice k = 0, q = [x, y, z, 0].
// alpha ("thinness") and beta ("offset") are constants or ParameterFields, read at the current
// iterate like phi. beta follows the PAPER's formula, exp(alpha (phi + beta)): at large alpha the
// surface sits near the level set phi = -beta, so a NEGATIVE beta moves it outwards. (The 2023
// text says "increasing beta expands the shell outwards", which is what the authors' code does:
// it computes exp(alpha (phi - b)), so their b is our -beta; their baseline b = 0.02 is
// beta = -0.02 here.)
//
// The versor d comes from a "versor polynomial" p(q) = prod_i (q - r_i)^(s P_i), product taken
// left to right (r_i roots with k = 0, P_i powers, s the power scalar, 1 by default), or from
// seeded noise (the 2024 paper's turbulent snowflake). Each factor is computed as the power of
// the UNIT quaternion (q - r_i)/|q - r_i|, by repeated squaring for integer powers: the same
// direction as the authors' polar form, without overflow and without transcendental functions.
//
// Origin translation (2023 Fig. 5): with origin_offset o, phi, alpha, beta and the versor are all
// read at x - o (the whole target moves by o), while the iteration's attracting origin stays at
// 0, so the interior erodes when o leaves the shape's deep interior. (The authors' code moves the
// SDF box by o but the roots by (0, ox, oy) + oz k.)
//
// 2D mode (complex plane, 2024 paper's 2D figures): points (x, y) are q = [x, y, 0, 0]; the
// versor's roots keep only their (w, i) parts and noise versors have no j part, so the iteration
// stays in the complex plane; phi is a 2D signed distance (or the z = 0 slice of a 3D one).
//
// Frames: the shape-modulus tools work in the "unit frame" of the authors' code: the target's
// bounding box centred at the origin and its longest side 100/110 (so alpha and beta mean what
// they mean there). ModulusTargetFromGrid maps a fractal-frame .qgrid into it.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "quijibo/grid.h"
#include "quijibo/quaternion_map.h"
#include "methods/mask.h"

namespace quijibo {

// The target's longest side in the unit frame (the authors' 100/110).
inline constexpr double kUnitFrameLongestSide = 100.0 / 110.0;

// phi and the box the target occupies (roots are drawn in it, meshes and images cover it).
struct ModulusTarget {
  std::function<double(const Vec3&)> phi;
  Vec3 box_min{-0.5, -0.5, -0.5}, box_max{0.5, 0.5, 0.5};
  std::string name;
  int dimension = 3;
};

// The region the shape modulus is drawn over by default, as a --box: the target's box grown by 15 %
// of its longest side on every side (3D: x0 y0 z0 x1 y1 z1), or the square about its centre of that
// size (`two_d`: x0 y0 x1 y1, the longest side of x and y).
std::vector<double> ModulusRegion(const ModulusTarget& target, bool two_d);

// A fractal-frame SDF grid (as written by `quijibo sdf`) seen in the unit frame: u = k w with
// k = kUnitFrameLongestSide / (fractal_radius (1 - 2 padding)), phi(u) = k * sdf(u / k), extended
// beyond the grid by the distance to its box (ExtendedSample). The box is the grid's inside cells'
// bounding box. Returns k through `scale` if given.
ModulusTarget ModulusTargetFromGrid(std::shared_ptr<const ScalarGrid> grid, double fractal_radius,
                                    double padding, double* scale = nullptr);
// Same for a grid already in the unit frame (scale 1).
ModulusTarget ModulusTargetFromUnitGrid(std::shared_ptr<const ScalarGrid> grid);
// Analytic targets: "sphere[:radius=r]" (3D), "hexagram[:size=s]" (2D; s = side of each of its
// two triangles), "disc[:radius=r]" (2D).
ModulusTarget AnalyticModulusTarget(const std::string& spec);

// The authors' frame (compatibility; docs/modulus-portals.md): their code reads its SDF file back
// transposed (written z fastest, read x fastest: it sees phi(z, y, x)) and stretched (their reader
// puts node i of n at -0.5 + i / (n - 1) on the unit box, their SDF generator spaced the nodes
// 1 / sdf_resolution from -0.5), and clamps queries to the box. The returned target reads `target`
// the way their code reads its file: phi'(x, y, z) = phi(g(z), g(y), g(x)) with
// g(t) = -0.5 + (clamp(t, -0.5, 0.5) + 0.5) (nodes - 1) / sdf_resolution; its box is the image of
// the target's box. The versor's roots are NOT moved (neither are they in their code). Throws
// quijibo::Error for invalid options and for 2D targets.
//
// Their SDF also keeps the distances of the mesh file's own units, and their code uses them
// unscaled in exp(a (d - b)). With s = unit_scale (unit-frame length per unit of the file the SDF
// was made from), d = phi / s, so their (a, b) are alpha = a / s, beta = -b s here:
// AuthorsParameters converts them.
struct AuthorsFrame {
  int sdf_resolution = 100;  // their sdfGen resolution (node spacing 1 / sdf_resolution)
  // Nodes per side of their .f3d; 0 means sdf_resolution. Their sdfGen truncates a float ratio, so
  // the count depends on the mesh: 100 for data/bunny.obj at 100, 99 for the reference notes'
  // pre-normalized bunny.
  int nodes = 0;
  double unit_scale = 1.0;  // s, > 0 (a mesh target: its normalization scale)
  int node_count() const { return nodes > 0 ? nodes : sdf_resolution; }
  std::string Validate() const;
};
ModulusTarget InAuthorsFrame(const ModulusTarget& target, const AuthorsFrame& frame);

// Signed distance to a simple polygon (vertices in order, either orientation), negative inside.
double PolygonSdf(const std::vector<std::array<double, 2>>& polygon, double x, double y);
// The hexagram (two equilateral triangles of side s, centroids at the origin, one pointing up),
// as its 12-vertex outline, counter-clockwise.
std::vector<std::array<double, 2>> HexagramPolygon(double side);

// ---- versor polynomial ----

struct VersorPolynomial {
  std::vector<Vec4> roots;     // quaternions [w, x, y, z]; generated ones have z (k) = 0
  std::vector<double> powers;  // one per root
  double power_scalar = 1.0;
  std::string description;
  nlohmann::json generator = nlohmann::json::object();  // how it was made (options, seed)
  std::string Validate() const;
};

// Roots uniform in the box [box_min, box_max] (k = 0), powers uniform: integers in
// [min_power, max_power] (inclusive) when integer_powers, else reals in [min_power, max_power).
// std::mt19937_64(seed) with hand-made draws, u = (rng() >> 11) 2^-53: the same polynomial on
// every platform (the authors' code seeds from std::random_device). Draw order: for each root,
// its x, y, z, then its power.
struct VersorGeneratorOptions {
  int roots = 10;
  double min_power = 2.0, max_power = 12.0;
  bool integer_powers = true;
  Vec3 box_min{-0.5, -0.5, -0.5}, box_max{0.5, 0.5, 0.5};
  std::uint64_t seed = 1;
  std::string Validate() const;
};
VersorPolynomial GenerateVersorPolynomial(const VersorGeneratorOptions& options);

// JSON: {"format":"quijibo-versor-polynomial","version":1,"description":..,"roots":[[w,x,y,z],..],
// "powers":[..],"power_scalar":1,"generator":{..}}. Reading also accepts the bare form of
// data/sm-baseline-poly10.json (description, roots, powers; no format/version). Errors name the
// file and the JSON pointer.
nlohmann::json VersorPolynomialToJson(const VersorPolynomial& p);
VersorPolynomial VersorPolynomialFromJson(const nlohmann::json& j, const std::string& source);
void WriteVersorPolynomial(const std::string& path, const VersorPolynomial& p);
VersorPolynomial ReadVersorPolynomial(const std::string& path);

// ---- versor field d(q) ----

struct Versor {
  enum class Kind { kPolynomial, kNoise };
  Kind kind = Kind::kPolynomial;
  VersorPolynomial polynomial;
  NoiseField noise;  // kNoise: d = normalize(noise(x)) as [n0, n1, n2, 0] (2D: [n0, n1, 0, 0])
};

// ---- the map ----

struct ShapeModulusOptions {
  ParameterField alpha = ParameterField(30.0);
  ParameterField beta = ParameterField(0.0);  // paper's sign: exp(alpha (phi + beta))
  Vec3 origin_offset{0.0, 0.0, 0.0};
  std::string Validate() const;
};

// The authors' a and b (fields too: every value of a field is converted, masks and feathers kept,
// which converts the blended field exactly) as this toolkit's alpha and beta: alpha = a / s,
// beta = -b s, s = frame.unit_scale (see AuthorsFrame). The origin offset is kept.
ShapeModulusOptions AuthorsParameters(const ShapeModulusOptions& theirs, const AuthorsFrame& frame);

class ShapeModulusMap : public QuaternionMap {
 public:
  ShapeModulusMap(ModulusTarget target, const Versor& versor, const ShapeModulusOptions& options);
  Quat Apply(const Quat& q) const override;
  // The parts, for pictures (2024 Figs. 7, 8) and tests.
  double LogModulus(const Quat& q) const;  // alpha (phi + beta) at the iterate
  Quat Direction(const Quat& q) const;     // d(q), unit
  const ModulusTarget& target() const { return target_; }
  int dimension() const { return target_.dimension; }

 private:
  Vec3 Point(const Quat& q) const {
    return {q.w - options_.origin_offset[0], q.x - options_.origin_offset[1], q.y - options_.origin_offset[2]};
  }
  ModulusTarget target_;
  Versor::Kind kind_;
  std::vector<Quat> roots_;
  std::vector<double> powers_;
  NoiseField noise_;
  ShapeModulusOptions options_;
  Vec4 offset4_{};
};

}  // namespace quijibo
