// The initial map fitted in L's own kernel (the default initial guess; design brief §3.3).
//
// One application of the map has log-modulus L(x) = ln C + sum_i e_i log|x - p_i| (tau = beta = 1,
// e_i = T_i for a top root, -B_i for a bottom root), which is *linear* in ln C and the e_i. So
// instead of fitting the 1/r potential and reusing its charges as exponents (the paper's proxy,
// which comes out inverted on shapes such as a scanned armadillo), we fit L itself to what the
// energy wants: L < 0 inside, L > 0 outside, crossing zero on the surface.
//
//   roots      pairs on the surface's normals: for each of `roots / 2` blue-noise surface samples,
//              one root `offset` inside and one `offset` outside, the offset shortened where the
//              shape (or the gap beside it) is thinner, so a finger's root stays in the finger
//   target g   s * clamp(phi / delta, -1, 1): linear across a band of half-width delta around the
//              surface, where tanh(alpha L) keeps a gradient, and +-s beyond it
//   loss       sum_rows w_r (L_r - g_r)^2 + ridge * |e|^2, with w_r = volume_r / max(h, |phi_r|)
//              (the paper's W = 1/phi), inside and outside rows scaled to equal total weight (as the
//              energy's eta normalization); beyond the band the loss is one-sided: a row whose L
//              already has the right sign and |L| >= s drops out (active-set iterations), so the
//              fit is not spent flattening L far from the shape
//   refinement where cells end on the wrong side, more root pairs at the surface points
//              nearest them, and the fit again (refine_rounds)
//   far field  rows on two spheres around the box ask L >= s, so the set stays bounded
//              (sum e_i > 0 makes |R| grow at infinity)
//   origin     optionally a fixed top root at the fractal origin (see origin_root), its term
//              taken out of the target before the fit
// The sign of a fitted e_i makes its root a top (e > 0) or bottom (e < 0) root.
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "quijibo/frame.h"
#include "quijibo/grid.h"
#include "quijibo/rational_map.h"
#include "quijibo/target.h"

namespace quijibo::monopole {

struct KernelFitOptions {
  // Root pairs are spaced at most `spacing` times their size (the shorter of their two offsets)
  // apart: a pair shapes L over about its size, so thin walls, where the offsets shorten, get
  // denser pairs. That rule sets how many roots a shape gets, kept in [roots, max_roots]
  // (roots = max_roots: exactly that many, spread by the same rule).
  int roots = 400;             // at least this many root positions (pairs: roots / 2), in [8, 4000]
  int max_roots = 1000;        // at most max(roots, max_roots), in [8, 4000]
  double spacing = 2.5;        // largest pair spacing / pair size, in [1, 100]
  double offset_cells = 2.0;   // distance of a root from the surface, in cells of the target grid
  double band_cells = 3.0;     // delta, the half-width of the linear band, in cells
  double amplitude = 0.3;      // s, |L| at the band's edge (tanh(alpha s) = tanh(3) with alpha 10)
  double ridge = 1e-4;         // Tikhonov weight relative to the mean diagonal of the normal matrix
  int max_band_rows = 60000;   // band cells kept (evenly subsampled beyond this)
  int coarse_stride = 3;       // beyond the band, one cell in stride^3
  int active_set_iterations = 6;
  // Rounds that add root pairs where the fit is on the wrong side of the surface (at most
  // roots / 4 new roots per round, a pair's width from existing pairs). Off by default: on the
  // thin-walled mug two rounds raise the start's IoU from 0.57 to 0.69, on the chair they find no
  // room, and they add up to half as many roots again (docs/benchmarks.md §7).
  int refine_rounds = 0;
  double refine_above = 0.0;  // refine only while more than this fraction of the fit's inside or
                              // outside cells (by weight) is on the wrong side
  // A top root of exponent 1 at the fractal origin (placed deep inside the shape), first in the
  // product: it makes the origin a zero of R, so the orbits the map traps there converge. The
  // reference's pair of zero roots (exponent 1 top and bottom) is neutral only while tau = beta;
  // once the optimizer scales them apart the origin can become a pole and the n-step set turns
  // to dust (measured on the hand: n-step IoU 0.02).
  bool origin_root = true;
  // On a thin-walled target (quijibo/target.h: most of the inside within four cells of the
  // surface) the pairs are spaced kThinWallSpacing times as far apart and max_roots is doubled (at
  // most 4000): walls a few cells thick need denser pairs than the rule's 2.5 sizes to be
  // shaped at all (the chair: start IoU 0.75 -> 0.82; docs/fidelity.md §9). kAuto decides from
  // the target; the other kinds of target keep the rule as set.
  AutoSwitch thin_walls = AutoSwitch::kAuto;
  static constexpr double kThinWallSpacing = 0.6;
  std::uint64_t seed = 1;      // blue-noise sampling of the surface
  std::string Validate() const;
};

struct KernelFitSummary {
  int rows = 0, band_rows = 0, far_rows = 0;
  int iterations = 0;          // active-set iterations done (all rounds)
  int refine_rounds = 0;       // rounds that added roots
  double spacing = 0;          // the spacing ratio used (larger than asked when max_roots binds)
  bool thin_walls = false;     // the thin-wall spacing was used (KernelFitOptions::thin_walls)
  double wall_depth_cells = 0; // WallDepthCells of the target
  int top = 0, bottom = 0;     // fitted roots by sign (without the zero roots)
  double exponent_sum = 0;     // sum e_i: > 0 keeps the set bounded
  double rms_band = 0;         // weighted RMS of L - g on the band rows
  double sign_agreement = 0;   // fraction of fit rows (by weight) where sign(L) = sign(phi)
  double seconds = 0;
};

// The initial map for the closed (or winding-number signed) surface `vertices`/`triangles`,
// both in the fractal frame of `frame`, whose signed distance `sdf` (negative inside) is given on
// the target grid. Throws quijibo::Error on invalid options or a field without inside cells.
RationalMap KernelFitMap(const std::vector<Vec3>& vertices, const std::vector<std::array<int, 3>>& triangles,
                         const ScalarGrid& sdf, const FractalFrame& frame, const KernelFitOptions& options = {},
                         KernelFitSummary* summary = nullptr);

// How a map starts on a target: the one-step log-modulus L on the cells of `sdf` (a slice
// S = 0), compared inside (phi < 0) and outside.
struct StartCheck {
  double median_inside = 0, median_outside = 0;
  double iou = 0;          // of {L < 0} and {phi < 0} on the grid
  double saturated = 0;    // fraction of cells with |alpha L| > 18 (tanh flat to 1e-15)
  bool inverted = false;   // L is not lower inside than outside (medians)
  // psi of the start under the default weights (kDefaultWeightField) on the grid's cells, counted
  // from the better trivial set: >= 0 is no better than the empty set, which the passes then reach.
  double psi = 0;
  // psi as a run with the default energy counts it at its start: on the cells and on their interior
  // corners (`between_nodes` "on", CornerGrid). The two can differ in sign on a start as good as the
  // empty set (the dragon's monopole start: -0.0011 on the cells, +0.00016 with the corners). NaN
  // unless asked for (`between_nodes`): the corners cost a second evaluation of L.
  double psi_between_nodes = std::numeric_limits<double>::quiet_NaN();
};
StartCheck CheckStart(const RationalMap& map, const ScalarGrid& sdf, double alpha = 10.0, bool between_nodes = false);

}  // namespace quijibo::monopole
