// From monopoles to the initial rational map (2015 paper §4.4 "Building the initial guess";
// the reference code's conventions, quijibo-code.md §3.4 and §5.2 item 2):
//   - a monopole of weight w > 0 becomes a top root with T_i = amplitude * w, one with w < 0 a
//     bottom root with B_i = amplitude * |w| (default 50; reference 3000, see below); weights are first put in
//     the normalized frame's units (divided by the fractal radius), as the reference fits there;
//   - optionally the reference's leading zero roots: a root at the origin with exponent 1 first in
//     top and in bottom (not amplified);
//   - ln C and the steepness from `scan`: by default (StartScan::kIou) the level set of F with the
//     best one-step IoU, tau = beta = the steepness that keeps the start from saturating, and the
//     zero roots replaced by one top root at the origin (below); or, with tau = beta = 1, the
//     reference's one-dimensional scan (StartScan::kReference): with C = 1, F = log|R|
//     on the scan grid (singular values replaced by the mean), minimize
//     sum -tanh(alpha (F - t)) Wu over t (100 samples over [min F, max F], then three refinements of
//     +-5 steps at a tenth of the step); ln C = -t*. Wu is the un-normalized layer weight
//     (-1/k inside, 0.25/k outside).
#pragma once

#include <string>
#include <vector>

#include "monopole/monopole_fit.h"
#include "quijibo/rational_map.h"
#include "util/settings.h"

namespace quijibo::monopole {

// How the start's level and steepness are chosen from the monopoles' field F = sum w_i log|q - m_i|.
enum class StartScan {
  // The set {F < t} with the highest one-step IoU against the target's inside on the target grid,
  // made as steep as the log-kernel start: the median |alpha L| over the cells within two cells
  // of the surface is 1 (tanh 0.76), so the start has a gradient on the surface (docs/fidelity.md §12).
  // `amplitude` is not used: the steepness replaces it.
  kIou,
  // The reference's 1-D scan of ln C at the given amplitude (the header's comment).
  kReference,
};
inline const EnumNames<StartScan> kStartScans("start scan", {{StartScan::kIou, "iou"}, {StartScan::kReference, "reference"}});
inline const std::vector<std::string>& kStartScanNames = kStartScans.names();
inline StartScan ParseStartScan(const std::string& name) { return kStartScans.Parse(name); }
inline std::string StartScanName(StartScan s) { return kStartScans.Name(s); }

struct InitialGuessOptions {
  // The "initial bulk scalar amplitude". The reference runs 3000 (its cfg comments: 50 "reliable",
  // 2000 "best"); with our fit, 1000 and above leave L = log|R| so steep that tanh saturates in
  // nearly every cell and the F pass has no gradient to follow (measured in docs/benchmarks.md),
  // so the default is the reference's "reliable" 50.
  double amplitude = 50.0;
  bool leading_zero_roots = true;  // reference: on
  int scan_resolution = 25;        // grid of the ln C scan (reference: 25)
  static constexpr ValueRange kScanResolutionRange{4, 512};
  double alpha = 10.0;
  StartScan scan = StartScan::kIou;
  // Every monopole becomes a top and a bottom root, the second at exponent 0, so the bounded
  // optimizer (exponents >= 0) can turn a monopole's sign. The P fit's charges are all but all
  // positive (a conductor's), and top roots alone cannot carve a concavity; the paper's bottom roots
  // "hollow out" the concave regions (docs/fidelity.md §12).
  bool both_signs = true;
  // Bottom roots (exponent 0) where the start's set spills out of the shape: at most this many
  // surface points whose outward point `hollow_offset_cells` away is inside the start's set {L < 0}
  // get a bottom root there. The P fit's monopoles sit where a conductor's charge is, on convex parts;
  // a concavity the start fills has none near it, and the paper's bottom roots that "hollow out"
  // the concave regions need to be there for the optimizer to grow (docs/fidelity.md §12).
  int hollow_roots = 200;
  static constexpr ValueRange kHollowRootsRange{0, 4000};
  double hollow_offset_cells = 2.0;
  static constexpr ValueRange kHollowOffsetRange{0.0, 20.0};
  // Top roots (exponent 0) where the start's set falls short of the shape: at most this many surface
  // points whose inward point `attract_offset_cells` deep (halved up to twice where the part is
  // thinner) is inside the shape and outside the start's set {L < 0} get a top root there. The
  // paper's attractive roots "pull J towards thin, convex features"; a thin part the start's hull
  // misses (a leg, a spike) has no monopole of weight to pull, so the optimizer had nothing to grow.
  int attract_roots = 200;
  static constexpr ValueRange kAttractRootsRange{0, 4000};
  double attract_offset_cells = 2.0;
  static constexpr ValueRange kAttractOffsetRange{0.0, 20.0};
  // With `scan` kIou: the hollow and attract roots start at one common exponent, the one whose start
  // has the best one-step IoU (ScanOffsetExponents), not at 0, where a root far from the start's set
  // has no gradient once the V pass steepens L (docs/fidelity.md §12).
  bool offset_scan = true;
  std::string Validate() const;
};

struct LnCScan {
  double ln_C = 0;
  double energy = 0;  // the scan's objective at the optimum (un-normalized weights; kReference)
  int singular_cells = 0;
  // kIou: the best set's one-step IoU on the target grid and the factor the exponents were scaled by.
  double iou = 0;
  double steepness = 1;
};

// kIou's scan: for F of `map` (its exponents, tau = beta = 1, ln C = 0) on the grid of `sdf`, the
// level t maximizing the IoU of {F < t} with {phi < 0}, and the factor s making the median of
// alpha s |F - t| over the cells with |phi| <= 2 cells equal to 1. Returns ln C = -s t, the IoU and s
// (the caller sets tau = beta = s).
LnCScan ScanLevelByIou(const RationalMap& map, const ScalarGrid& sdf, double alpha);

// The initial map. `monopoles` in the fractal frame of `frame`; `sdf` the target on its grid.
RationalMap InitialMap(const std::vector<Monopole>& monopoles, const FractalFrame& frame,
                       const ScalarGrid& sdf, const InitialGuessOptions& options = {},
                       LnCScan* scan = nullptr);

// Adds `options.hollow_roots` bottom roots of exponent 0 to `map` (the start, in the frame of `sdf`):
// taken in the given order from `surface` (points on the target surface, blue noise in a random
// order), those whose point p + d n, d = hollow_offset_cells * sdf spacing along the outward normal
// n (the sdf's gradient), is outside the shape (sdf > 0) and inside the start's set
// (OneStepLogModulus < 0); the root goes at that outward point. Returns how many were added.
int AddHollowRoots(RationalMap& map, const ScalarGrid& sdf, const std::vector<Vec3>& surface,
                   const InitialGuessOptions& options);

// Adds `options.attract_roots` top roots of exponent 0 to `map`, the inward mirror of AddHollowRoots:
// from `surface` in order, those whose point p - d n, d = attract_offset_cells * sdf spacing (d/2,
// then d/4, where that point is not inside: a part thinner than d), is inside the shape (sdf < 0)
// and outside the start's set (OneStepLogModulus > 0); the root goes at that inward point. Returns
// how many were added.
int AddAttractRoots(RationalMap& map, const ScalarGrid& sdf, const std::vector<Vec3>& surface,
                    const InitialGuessOptions& options);

// Roots added to a map together: top roots [top_begin, top_end) and bottom roots [bottom_begin, bottom_end).
struct RootGroup {
  int top_begin = 0, top_end = 0, bottom_begin = 0, bottom_end = 0;
  int size() const { return top_end - top_begin + bottom_end - bottom_begin; }
};

struct OffsetExponentScan {
  int hollow = 0, attract = 0;    // the offset roots scanned
  double exponent = 0;            // their common exponent chosen
  double iou_before = 0, iou = 0; // the start's best one-step IoU with the offset roots at 0, and at `exponent`
};

// The hollow roots (`hollow`: bottom roots where the start spills) and the attract roots (`attract`:
// top roots where it falls short) of the start `map` (tau = beta, as InitialMap makes it) get one
// common exponent, chosen with the level of L as ScanLevelByIou does: the one whose start has the
// best one-step IoU on the grid of `sdf`, among 0 and the mean nonzero exponent times 2^-10 .. 2^6.
// Exponent 0 is a candidate, so the start's IoU never falls. Sets the exponents, ln C and tau = beta
// = the steepness of the chosen set.
OffsetExponentScan ScanOffsetExponents(RationalMap& map, const ScalarGrid& sdf, const RootGroup& hollow,
                                       const RootGroup& attract, double alpha);

// The reference's 1-D scan for ln C of `map` (its exponents, tau = beta = 1 as given).
LnCScan ScanLnC(const RationalMap& map, const ScalarGrid& sdf, int resolution, double alpha);

}  // namespace quijibo::monopole
