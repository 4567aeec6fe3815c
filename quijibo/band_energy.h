// The narrow band of the log-linear evaluator (issue 15): only cells whose tanh is not saturated
// are evaluated; the others add a constant and no gradient. Same energy and gradient as the dense
// LogLinearEnergy, bit for bit (loglinear_kernel.h), at a fraction of the work once the fit has
// formed (on an optimized bunny map ~3 % of the 97^3 cells are unsaturated).
//
// Saturation. For |alpha L| >= 19.07, tanh(alpha L) is exactly +-1 in double, so the dense
// evaluator's term is exactly -+W and its gradient weight exactly 0. The band calls a cell
// saturated when |L| >= L_sat = kBandSaturation / alpha (20 / alpha), which leaves 0.93 / alpha for
// rounding in L.
//
// The bound. At an anchor x0 the band computes L_c(x0) for every cell (one dense sweep). Write
// u_c = (1, D_c1, ..., D_cR) and v(x) = (ln C, tau T, -beta B); then L_c(x) = u_c . v(x) and, by
// Cauchy-Schwarz,
//     |L_c(x) - L_c(x0)| <= ||v(x) - v(x0)||_2 ||u_c||_2 = d(x) N_c.
// In a V pass (exponents fixed) u_c = (1, S_T, S_B) and v = (ln C, tau, beta). With the slack
// s_c = |L_c(x0)| - L_sat - e0 (e0 bounds the rounding of L at x0), a cell stays saturated while
// d(x) <= r_c = s_c / N_c. Cells with s_c <= 0 form the band and are always evaluated; the next
// cells by radius r_c (a sorted list of about 1/16 of the grid) are evaluated exactly at x when
// r_c <= d(x): a binary search. All other cells have r_c > d(x) and are provably saturated. When
// d(x) passes the list's end, or the cells evaluated beyond the band since the anchor add up to more
// than one dense sweep (ski rental: the band never costs more than twice the best anchoring), the
// evaluation is a dense sweep that also records L. It becomes the new anchor unless it was beyond
// reach and its energy is above the anchor's (a rejected line-search trial: the search comes back
// towards the anchor). If the rounding bound of L at x exceeds 0.9 / alpha (absurd maps) the
// evaluation is dense.
//
// Rounding: |L computed - L| <= (R+2) u ||v||_2 N_c for a dot product of R+1 terms; the band uses
// 4 (R+1) u ||v||_2 max_c N_c.
#pragma once

#include <cstdint>
#include <vector>

#include "quijibo/loglinear_energy.h"

namespace quijibo {

inline constexpr double kBandSaturation = 20.0;  // |alpha L| of a saturated cell

struct BandStats {
  long long evaluations = 0;    // all evaluations
  long long anchors = 0;        // dense sweeps that (re)built the band
  long long anchors_reach = 0;  // ... because x moved beyond the list's reach
  long long anchors_work = 0;   // ... because the list's cells had cost a dense sweep
  long long far = 0;            // dense sweeps beyond reach that did not move the anchor
  long long dense_fallbacks = 0;
  long long exact_cells = 0;    // cells evaluated by band evaluations, summed
  long long max_exact = 0;      // most cells of one band evaluation
  long long band_cells = 0;     // unsaturated cells at the last anchor
  long long cells = 0;          // active cells of the grid
  long long sweeps() const { return anchors + far + dense_fallbacks; }
  double mean_fraction() const {  // mean share of the grid a band evaluation evaluates
    const long long n = evaluations - sweeps();
    return n > 0 && cells ? double(exact_cells) / double(n) / double(cells) : 0.0;
  }
  double work_fraction() const {  // cells evaluated / (evaluations x cells): dense = 1
    return evaluations && cells ? (double(exact_cells) + double(sweeps()) * double(cells)) / double(evaluations) / double(cells) : 0.0;
  }
};

class BandEnergy {
 public:
  // Reads the matrix, weights and V-pass sums of `dense`, which must outlive the band. SetWeights
  // and BeginVariablePass go to `dense`; the band notices them.
  explicit BandEnergy(const LogLinearEnergy* dense);

  // psi and its gradient, equal to dense->Evaluate(x, mode, with_gradient).
  Evaluation<double> Evaluate(const Eigen::VectorXd& x, EnergyMode mode = EnergyMode::kFull,
                              bool with_gradient = true);
  // The next evaluation anchors (a dense sweep), e.g. at the start of a pass.
  void Invalidate() { anchored_ = false; }
  const BandStats& stats() const { return stats_; }
  void ResetStats();

 private:
  // A dense evaluation that records L (in scratch_) and, the first time, the row norms.
  Evaluation<double> Sweep(const Eigen::VectorXd& x, bool variable, bool with_gradient);
  // Makes the last sweep's x the anchor.
  void Adopt(const Eigen::VectorXd& x, bool variable, double energy);
  void UpdateConstants();
  // ||v(x) - v(x0)||_2 and ||v(x)||_2 (see above).
  double Displacement(const Eigen::VectorXd& x, const double* coeff) const;
  double RoundingBound(const Eigen::VectorXd& x, const double* coeff) const;

  const LogLinearEnergy* dense_;
  bool anchored_ = false, anchor_variable_ = false, compact_rows_ = false;
  std::uint64_t variable_version_ = 0, weights_version_ = ~std::uint64_t(0);
  std::vector<double> x0_, coeff0_;          // the anchor (V pass: ln C, tau, beta)
  std::vector<double> row_norm_;             // N_c of the full mode (fixed per level)
  std::vector<double> norm_;                 // N_c of the anchor's mode
  double norm_max_ = 0;
  std::vector<double> L0_, scratch_;         // L_c at the anchor; of the last sweep
  double anchor_energy_ = 0;
  std::uint64_t anchor_weights_version_ = 0;
  std::vector<std::int32_t> rank_;           // -1: band; position in the list; INT32_MAX: neither
  std::vector<double> list_r_;               // radii r_c of the list, ascending
  std::vector<std::int64_t> list_cell_;      // the list's cells
  double list_cap_ = 0;                      // every cell beyond the list has r_c >= list_cap_
  std::vector<std::int64_t> candidates_;     // band and list cells, ascending
  std::vector<std::int64_t> block_ids_, block_offsets_;  // kEnergyBlock blocks holding candidates
  std::vector<double> candidate_rows_;       // their D rows when the matrix is not stored
  loglinear::Fixed const_total_ = 0;         // energy of all saturated (non-band) cells
  std::vector<loglinear::Fixed> prefix_;     // energy of the first k list cells
  long long extra_ = 0;                      // list cells evaluated since the anchor
  std::int64_t band_count_ = 0;
  BandStats stats_;
};

}  // namespace quijibo
