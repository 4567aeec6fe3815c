// RationalMap: the factored quaternion rational map of the 2015 paper (Eqns 4 and 8),
//
//   R(q) = e^C T(q) B(q)^-1,   T(q) = prod_i (q - t_i)^(tau T_i),   B(q) = prod_i (q - b_i)^(beta B_i),
//
// products taken left to right in root order (quaternions do not commute). Roots are quaternions
// in the fractal frame (frame.h), components (real, i, j, k); a root placed at the spatial point
// (x, y, z) is [x, y, z, 0]. With `leading_zero_roots` the first top and the first bottom root are
// the reference code's zero roots (at the origin, exponent 1 initially) and are kept in place.
//
// The optimization variables (paper §4.2) are, in this order,
//   x = [ln C, tau, beta, T_1 .. T_nt, B_1 .. B_nb]
// with ln C free and every other entry >= 0. ln C rather than C is the variable, as in the
// reference code: C spans hundreds of orders of magnitude.
//
// Stored as `map.json` (docs/formats.md), the file every stage reads and writes.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cmath>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "quijibo/frame.h"
#include "quijibo/quaternion.h"
#include "util/settings.h"

namespace quijibo {

using Vec4 = std::array<double, 4>;

struct RationalMap {
  std::vector<Vec4> top_roots;
  std::vector<double> top_exponents;
  std::vector<Vec4> bottom_roots;
  std::vector<double> bottom_exponents;
  double ln_C = 0.0;
  double tau = 1.0;
  double beta = 1.0;
  bool leading_zero_roots = false;
  FractalFrame frame;
  // Free-form record of how the map was made (command, seed, monopole fit, optimizer, ...).
  nlohmann::json provenance = nlohmann::json::object();

  int top_count() const { return int(top_roots.size()); }
  int bottom_count() const { return int(bottom_roots.size()); }
  int root_count() const { return top_count() + bottom_count(); }
  int variable_count() const { return 3 + root_count(); }

  // x = [ln C, tau, beta, T..., B...].
  Eigen::VectorXd variables() const;
  void set_variables(const Eigen::VectorXd& x);
  // Lower bounds of the variables: -inf for ln C, 0 for the rest.
  Eigen::VectorXd lower_bounds() const;

  // Empty string when consistent, else the first problem found.
  std::string Validate() const;
  // Also under this name: optim/, the energy evaluators and the Python module call it so.

  template <class Real>
  Quaternion<Real> top_root(int i) const {
    const Vec4& r = top_roots[i];
    return {Real(r[0]), Real(r[1]), Real(r[2]), Real(r[3])};
  }
  template <class Real>
  Quaternion<Real> bottom_root(int i) const {
    const Vec4& r = bottom_roots[i];
    return {Real(r[0]), Real(r[1]), Real(r[2]), Real(r[3])};
  }
};

// log|q - r| for the sample quaternion q = [p, slice].
inline double LogDistance(const Vec3& p, const Vec4& r, double slice = 0.0) {
  const double a = p[0] - r[0], b = p[1] - r[1], c = p[2] - r[2], d = slice - r[3];
  return 0.5 * std::log(a * a + b * b + c * c + d * d);
}

// L = log|R(q)| after one application of the map at q = [p, slice], by the identity of design
// brief §3.1 (ln C + tau sum T_i log|q - t_i| - beta sum B_i log|q - b_i|); -inf on a top root,
// +inf on a bottom root. The one-step set is {L < 0}.
inline double OneStepLogModulus(const RationalMap& m, const Vec3& p, double slice = 0.0) {
  double top = 0, bottom = 0;
  for (int i = 0; i < m.top_count(); ++i) top += m.top_exponents[i] * LogDistance(p, m.top_roots[i], slice);
  for (int i = 0; i < m.bottom_count(); ++i) bottom += m.bottom_exponents[i] * LogDistance(p, m.bottom_roots[i], slice);
  return m.ln_C + m.tau * top - m.beta * bottom;
}

// The same map expressed in another fractal frame of the same normalization (frame.h):
// w' = k w + b with k = to.fractal_radius / from.fractal_radius and
// b = to.fractal_radius (from.origin - to.origin). The roots move with the frame (their k
// components scale by k) and ln C absorbs the scale, ln C' = ln C - (tau sum T - beta sum B) ln k,
// so L'(w') = L(w): the one-step set is the same set of user points. The n-step set is not: the
// iteration's unit ball stays at the new origin with radius 1 (fidelity.md §3b, meshing.md
// "Root translation"). Roots that leave the origin stop being zero roots (leading_zero_roots becomes false
// unless b = 0). Throws quijibo::Error when `to` is invalid or its normalization (scale,
// translation, padding) differs from the map's.
RationalMap InFrame(const RationalMap& map, const FractalFrame& to);

// The frame a map is iterated in: its own (as optimized), or the reference code's (ReferenceFrame),
// where the paper's root translations are given.
enum class IterationFrame { kMap, kReference };
inline const EnumNames<IterationFrame> kIterationFrames("iteration frame", {{IterationFrame::kMap, "map"},
                                                                          {IterationFrame::kReference, "reference"}});
inline const std::vector<std::string>& kIterationFrameNames = kIterationFrames.names();
inline IterationFrame ParseIterationFrame(const std::string& name) { return kIterationFrames.Parse(name); }
inline std::string IterationFrameName(IterationFrame frame) { return kIterationFrames.Name(frame); }

// The map as the mesh stage and the fidelity measures iterate it: WithDetail(map, detail), then in
// ReferenceFrame with IterationFrame::kReference; `map` itself when detail is 0 and the frame the
// map's. `lambda` (optional) receives WithDetail's factor (1 for detail 0).
RationalMap IterationMap(const RationalMap& map, IterationFrame frame, double detail, double* lambda = nullptr);

// The reference code's world frame for a map's normalization (quijibo-code.md §2): the origin at
// the centre of the mesh's bounding box and the longest side 3 units (fractal radius 4 with the
// default padding 0.125; 3 / (1 - 2 padding) otherwise), the frame in which the paper's root
// translations (Figs. 1c, 9c, 10c: 1.41, 0.54, 1.07 along z) are given.
FractalFrame ReferenceFrame(const FractalFrame& frame);


// The one-step surface's steepness: the median of |grad L| (per fractal unit) at the points where
// L changes sign along the edges of a `lattice`^3 lattice over the shape box (the cube of side
// fractal_radius (1 - 2 padding) about the frame's box_center()). 0 when L does not change sign
// there. Deterministic; O(lattice^3 roots).
double SurfaceSteepness(const RationalMap& map, int lattice = 48);

// Fractal detail (docs/meshing.md "Detail"): the map with ln C, tau and beta multiplied by
// lambda = 2 / (w |grad L|), w = `detail` percent of the shape box's side and |grad L| the
// SurfaceSteepness, so that the band |L| < 1 about the one-step surface is w wide, whatever the
// optimizer left. L becomes lambda L: the one-step set {L < 0} is exactly the same, but the
// iteration sees a map whose modulus leaves 1 slowly across a wide band (the role of the shape
// modulus' alpha, 2023 §4) and whose versors turn lambda times slower, so the n-step set grows
// folds and flakes at the scale w; a narrow band (lambda > 1 on a gentle map) keeps the n-step set
// on the one-step set (smooth). `detail` 0 returns the map as optimized. Throws
// quijibo::Error for a negative or non-finite detail. `lambda` (optional) receives the factor.
RationalMap WithDetail(const RationalMap& map, double detail, double* lambda = nullptr);

// The default detail of the mesh stage and the fidelity measures: a band 0.25 % of the shape's size,
// narrower than a 97^3 target cell (1 %), so the n-step set keeps to the one-step set whether the
// optimizer left the map steep (the bunny: 0.04 %) or gentle (the genus-3 plate: n = 4 IoU 0.53
// as optimized, 0.88 at 0.25; docs/meshing.md "Detail").
inline constexpr double kSmoothDetail = 0.25;

// Root translation by the potential at -t (docs/meshing.md "Root translation"). Translating the
// roots and the samples by t iterates F(s) = R(s) - t: the inside of the one-step set, where |R| is
// small, is sent to about -t, so where -t lies decides the n-step set. Deep inside the one-step set
// it is the one-step set; outside, it empties; a little inside the surface (L(-t) between about -3
// and -1.5 on a map with `detail`) the inside lands where R's versors decide its fate, and the
// surface grows intricate, as the Julia set of q^2 + c does for c near the Mandelbrot set's edge.
// Inputs: `iterated` the map as it is iterated (IterationMap: its detail and frame), `direction`
// the translation's direction in that frame (x, y, z; its length is ignored), `potential` the
// L = log|R| wanted at -t, in kTranslatePotentialRange.
// Returns t = s u (k = 0), u = direction / |direction|, s the smallest s > 0 with
// L(-s u) = potential (a march of 1/2048 of the shape box's side, then bisection), -s u on the
// ray from the frame's origin. Throws quijibo::Error when the direction is zero or not finite, the
// potential is out of range, L at the origin is not below `potential` (the ray must start inside
// the set, deeper than the potential asked for), or L stays below it out to the box's far corner.
Vec4 TranslationForPotential(const RationalMap& iterated, const Vec3& direction, double potential);
// The potentials TranslationForPotential accepts: [-1000, 0).
inline constexpr ValueRange kTranslatePotentialRange{-1000.0, 0.0, false, true};

// Indices into the variable vector.
struct VariableIndex {
  static constexpr int kLnC = 0, kTau = 1, kBeta = 2, kFirstExponent = 3;
  static int top(int i) { return kFirstExponent + i; }
  static int bottom(const RationalMap& m, int i) { return kFirstExponent + m.top_count() + i; }
};

// Balances the scales of a variable vector x (RationalMap::variables(), `top_count` top exponents
// first) when tau and beta differ by more than the factor `min_ratio` (or one of them is 0): tau =
// beta = c, their geometric mean (or the one that is not 0), and every exponent rescaled so that
// each root's power, tau*T_i and beta*B_j, is unchanged: the same L and map, in variables where top
// and bottom roots move at the same rate (OptimizeOptions::balance_scales). A factor of 2 slows no
// root noticeably; what needs balancing is the monopole start's 100 to 10^4 after its V passes,
// while the log-kernel start's passes keep tau and beta within a fraction of a percent, so its runs
// stay bit for bit what they were. Returns whether x changed.
template <class Vector>
bool BalanceScales(Vector& x, int top_count, double min_ratio = 2.0) {
  using std::sqrt;
  using Scalar = typename Vector::Scalar;
  const Scalar tau = x[VariableIndex::kTau], beta = x[VariableIndex::kBeta];
  const bool both = tau > 0 && beta > 0;
  if (both ? (tau <= beta * Scalar(min_ratio) && beta <= tau * Scalar(min_ratio)) : !(tau > 0 || beta > 0))
    return false;
  const Scalar c = both ? Scalar(sqrt(tau * beta)) : (tau > 0 ? tau : beta);
  const Eigen::Index first = VariableIndex::kFirstExponent, bottoms = x.size() - first - top_count;
  x.segment(first, top_count) *= Scalar(tau / c);
  x.segment(first + top_count, bottoms) *= Scalar(beta / c);
  x[VariableIndex::kTau] = c;
  x[VariableIndex::kBeta] = c;
  return true;
}

// map.json <-> RationalMap. FromJson reports the first problem as
// "<source>: <JSON pointer>: expected ..., found ...", and rejects unknown keys.
nlohmann::json MapToJson(const RationalMap& map);
RationalMap MapFromJson(const nlohmann::json& j, const std::string& source);
void WriteMap(const std::string& path, const RationalMap& map);
RationalMap ReadMap(const std::string& path);

// A seeded random map for tests and benchmarks: roots uniform in the ball of radius
// `root_radius` on the k = 0 hyperplane, exponents uniform in [exponent_min, exponent_max].
struct RandomMapOptions {
  int top = 65;
  int bottom = 43;
  double root_radius = 1.5;
  double exponent_min = 0.5;
  double exponent_max = 3.0;
  double ln_C = 0.0;
  bool leading_zero_roots = false;
  std::uint64_t seed = 1;
  std::string Validate() const;
};
RationalMap RandomMap(const RandomMapOptions& options);

}  // namespace quijibo
