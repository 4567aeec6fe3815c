// Regions of space for the shape modulus and portals: masks (sphere, box, half-space, SDF) given
// by a signed distance (negative inside), the cubic blend that feathers them, seeded gradient
// noise, and spatially varying parameters (alpha, beta) built from masks (2023 Figs. 7, 13).
//
// In 2D (the complex plane) points are (x, y, 0): a sphere is a disc, a box a rectangle.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "quijibo/grid.h"
#include "util/json_reader.h"

namespace quijibo {

// The smooth cubic step 3t^2 - 2t^3 of t clamped to [0, 1]; C1 at both ends.
inline double SmoothStep(double t) {
  t = t < 0.0 ? 0.0 : (t > 1.0 ? 1.0 : t);
  return t * t * (3.0 - 2.0 * t);
}

// A region given by its signed distance d(x) (negative inside; exact for sphere, box and
// half-space, whatever the SDF grid holds for "sdf").
struct Mask {
  enum class Type { kSphere, kBox, kHalfspace, kSdf };
  Type type = Type::kSphere;
  Vec3 center{0.0, 0.0, 0.0};       // sphere, box; sdf: where the grid's origin is placed
  double radius = 1.0;              // sphere
  Vec3 half_extent{0.5, 0.5, 0.5};  // box (axis aligned)
  Vec3 normal{1.0, 0.0, 0.0};       // half-space n.x <= offset is inside (n normalized on read)
  double offset = 0.0;
  std::shared_ptr<const ScalarGrid> sdf;  // "sdf": the grid, sampled in the modulus frame ...
  double sdf_scale = 1.0;                 // ... as sdf_scale * grid((x - center) / sdf_scale)
  std::string sdf_path;                   // for JSON output

  double distance(const Vec3& p) const;
  std::string Validate() const;
};

// Loads the grid of an "sdf" mask from its file (path already resolved against base_dir). The
// default reads a .qgrid as is; the commands pass one that also accepts meshes
// (`MakeMaskGridLoader`, methods/modulus_target.h), which mask.cpp alone cannot turn into an SDF.
using MaskGridLoader = std::function<std::shared_ptr<const ScalarGrid>(const std::string& path)>;

// {"type":"sphere","center":[x,y,z],"radius":r} | {"type":"box","center":..,"half_extent":..}
// | {"type":"halfspace","normal":..,"offset":o}
// | {"type":"sdf","file":"a.qgrid","scale":s,"center":[..]}   (scale 1 and centre 0 by default)
// 2D documents may give 2-vectors (z = 0). Relative SDF paths are taken relative to base_dir.
Mask MaskFromJson(const JsonReader& r, const std::string& pointer, const std::string& base_dir,
                  const MaskGridLoader& load = {});
nlohmann::json MaskToJson(const Mask& m);

// Seeded 3D gradient noise (Perlin's improved noise, with gradients from a hashed lattice rather
// than a permutation table): values roughly in [-1, 1], 0 at lattice points, C2 (quintic fade).
// Deterministic for a given seed on every platform.
class GradientNoise {
 public:
  explicit GradientNoise(std::uint64_t seed = 1) : seed_(seed) {}
  double operator()(const Vec3& p) const;
  // Sum of `octaves` octaves, frequency doubling and amplitude halving.
  double fbm(const Vec3& p, int octaves) const;

 private:
  std::uint64_t seed_;
};

// Three independent noise channels (seeds seed, seed+1, seed+2): a vector field.
struct NoiseField {
  std::uint64_t seed = 1;
  double frequency = 1.0;  // lattice cells per unit length
  int octaves = 1;
  Vec3 operator()(const Vec3& p) const;
};

// A scalar parameter that may vary in space: `value` blended towards each region's value in turn,
//   v = value; for each region: v = (1 - w) v + w value_r,  w = SmoothStep((-d_r(x)) / feather_r + 1/2)
// i.e. w = 1 deeper than feather/2 inside the region's mask, 0 beyond feather/2 outside, and the
// cubic in between (the paper's "cubic interpolant"). A half-space region with a wide feather is
// a cubic ramp (the dragon of Fig. 7).
struct ParameterField {
  struct Region {
    Mask mask;
    double value = 0.0;
    double feather = 0.1;
  };
  double value = 0.0;
  std::vector<Region> regions;

  ParameterField() = default;
  ParameterField(double constant) : value(constant) {}  // NOLINT: a number is a constant field
  bool constant() const { return regions.empty(); }
  double operator()(const Vec3& p) const {
    if (regions.empty()) return value;
    return EvaluateRegions(p);
  }
  std::string Validate(const std::string& name) const;

 private:
  double EvaluateRegions(const Vec3& p) const;
};

// A number, or {"value": v, "regions": [{"mask": {...}, "value": v, "feather": f}, ...]}.
ParameterField ParameterFieldFromJson(const JsonReader& r, const std::string& pointer,
                                      const std::string& base_dir, const MaskGridLoader& load = {});
nlohmann::json ParameterFieldToJson(const ParameterField& f);

// Reads a 2- or 3-vector at pointer (z = 0 when 2).
Vec3 ReadVec3(const JsonReader& r, const std::string& pointer);

}  // namespace quijibo
