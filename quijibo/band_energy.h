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
//
// Blocks (on-the-fly storage, where a dense sweep costs R logarithms per cell: the levels beyond
// 97^3, and with storage kAuto any matrix over an eighth of the memory budget). The grid is cut into blocks of kBandBlockSide^3 cells. Take a block with centre p, whose
// cell centres q = p + delta lie within h of p (delta in the slice), and a root at distance
// d_j > h from p. Two bounds on how far L moves inside the block:
//   first order in each root:  |D_qj - D_pj| <= e_j = -log(1 - h/d_j), so
//                              |L_q - L_p| <= sum_j |coeff_j| e_j;
//   Taylor with remainder:     the Hessian of log|x| has norm 1/|x|^2, so
//                              |D_qj - D_pj - grad D_pj . delta| <= q_j = h^2 / (2 (d_j - h)^2) and
//                              |L_q - L_p| <= h |g| + sum_j |coeff_j| q_j,  g = sum_j coeff_j grad D_pj.
// The second keeps the cancellation between top and bottom roots (g is L's gradient), the first
// is tighter right next to a root; the band takes the smaller, E. The whole block is saturated,
// with the sign of L_p, when |L_p| - E > L_sat (plus the rounding of the sums). Its row norms are
// bounded by N_B = sqrt(1 + sum_j (|D_pj| + e_j)^2) >= N_c, so it stays
// saturated while d(x) <= r_B = slack / N_B, like a cell. An anchor then costs one pass over the
// blocks (~4R operations each) plus the cells of the blocks it could not prove saturated, whose
// rows the dense evaluator caches with the band's and the list's (LogLinearEnergy::CacheRows: the
// cache follows them as they move, ~1 GB for the bunny at 97^3 against 4.4 GB of matrix); the
// list's reach is capped by the smallest r_B. Blocks with a root within h are never saturated; V passes (O(cells) per sweep) do
// not use blocks.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "quijibo/loglinear_energy.h"

namespace quijibo {

inline constexpr double kBandSaturation = 20.0;  // |alpha L| of a saturated cell
inline constexpr int kBandBlockSide = 4;        // cells per block side (on-the-fly storage)

// The blocks of a dense evaluator's grid and what bounds D inside them (see above). Built once per
// grid and map; two bands over one evaluator (a level's and the absolute energy's) can share them.
struct BandBlocks {
  // Blocks of `side`^3 cells over dense's grid; their active cells and bounds for its roots.
  static std::shared_ptr<const BandBlocks> Build(const LogLinearEnergy& dense, int side = kBandBlockSide);
  int roots = 0;
  std::vector<std::int64_t> offsets;  // block b holds actives[offsets[b] .. offsets[b+1])
  std::vector<std::int64_t> actives;  // ascending within a block
  std::vector<double> log_distance;   // D from each block's centre: roots per block
  std::vector<float> reach;           // e_j, rounded up: roots per block
  std::vector<float> curvature;       // q_j, rounded up: roots per block
  std::vector<double> norm;           // N_B; infinite when a root is within the block's reach
  std::vector<double> centre;         // 3 per block (x, y, z; w is the slice)
  std::vector<double> radius;         // h per block
  std::int64_t count() const { return std::int64_t(norm.size()); }
  std::size_t bytes() const;
  // Appends block b's active cells to `out`.
  void AppendCells(std::int64_t b, std::vector<std::int64_t>* out) const {
    out->insert(out->end(), actives.begin() + offsets[std::size_t(b)], actives.begin() + offsets[std::size_t(b + 1)]);
  }
};

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
  long long sweep_cells = 0;    // cells evaluated by sweeps (block sweeps: also 2 per block)
  long long block_sweeps = 0;   // sweeps over blocks (the others are dense)
  long long saturated_blocks = 0, blocks = 0;  // at the last block sweep
  long long sweeps() const { return anchors + far + dense_fallbacks; }
  double mean_fraction() const {  // mean share of the grid a band evaluation evaluates
    const long long n = evaluations - sweeps();
    return n > 0 && cells ? double(exact_cells) / double(n) / double(cells) : 0.0;
  }
  double work_fraction() const {  // cells evaluated / (evaluations x cells): dense = 1
    return evaluations && cells ? (double(exact_cells) + double(sweep_cells)) / double(evaluations) / double(cells) : 0.0;
  }
};

class BandEnergy {
 public:
  // Reads the matrix, weights and V-pass sums of `dense`, which must outlive the band. SetWeights
  // and BeginVariablePass go to `dense`; the band notices them.
  // With on-the-fly storage the band anchors on blocks: `blocks` (BandBlocks::Build(*dense)) or,
  // if null, its own.
  explicit BandEnergy(const LogLinearEnergy* dense, std::shared_ptr<const BandBlocks> blocks = nullptr);

  // psi and its gradient, equal to dense->Evaluate(x, mode, with_gradient).
  Evaluation<double> Evaluate(const Eigen::VectorXd& x, EnergyMode mode = EnergyMode::kFull,
                              bool with_gradient = true);
  // One evaluation that leaves the band as it was (no anchor): over the blocks where there are
  // blocks, else dense. For isolated points, such as the absolute energy's. Unless another band
  // keeps the dense evaluator's rows, it keeps the rows it evaluated (within an eighth of the
  // memory budget): the next isolated point evaluates much the same cells.
  Evaluation<double> EvaluateOnce(const Eigen::VectorXd& x, bool with_gradient = false);
  // The next evaluation anchors (a dense sweep), e.g. at the start of a pass.
  void Invalidate() { anchored_ = false; }
  const BandStats& stats() const { return stats_; }
  void ResetStats();
  // L at x on the dense evaluator's grid (NaN at singular cells), exact where it is computed; with
  // blocks, +-infinity in the blocks proven saturated (|L| > L_sat there; its sign is exact).
  std::vector<double> LogModulus(const Eigen::VectorXd& x) const;
  // The blocks (null unless the storage is on-the-fly).
  const std::shared_ptr<const BandBlocks>& blocks() const { return blocks_; }

 private:
  // An evaluation that records L (in scratch_) and the row norms: dense (the norms only the first
  // time) or, with blocks in full mode, over the blocks and the cells of the unproven ones.
  Evaluation<double> Sweep(const Eigen::VectorXd& x, bool variable, bool with_gradient);
  // keep_rows: the dense evaluator keeps the rows the sweep evaluates (CacheRows), beside the
  // anchor's. EvaluateOnce keeps only this sweep's, within an eighth of the memory budget, and
  // only where no anchoring band keeps the evaluator's rows (a pass at the finest level).
  Evaluation<double> BlockSweep(const Eigen::VectorXd& x, bool with_gradient, bool keep_rows);
  // Proves blocks saturated at x: sign (0: not proven) and radius r_B of each; returns the largest
  // N_B of the saturated blocks.
  double ScanBlocks(const Eigen::VectorXd& x, const double* coeff, std::vector<signed char>* sign,
                    std::vector<double>* radius) const;
  // Makes the last sweep's x the anchor.
  void Adopt(const Eigen::VectorXd& x, bool variable, double energy);
  void UpdateConstants();
  void UpdateBlockConstants();
  // On the fly: has the dense evaluator keep the anchor's rows (sets row_order_).
  void KeepRows();
  // Groups `cells` (ascending) by the dense evaluator's kEnergyBlock blocks: the offsets of
  // CellBlocks.
  static std::vector<std::int64_t> Group(const std::vector<std::int64_t>& cells);
  // `cells` grouped as by Group (offsets) for LogLinearEnergy::SumBlocks, without the cells whose
  // rank_ is `below` or more (all cells if `below` < 0).
  LogLinearEnergy::CellBlocks Blocks(const std::vector<std::int64_t>& cells, const std::vector<std::int64_t>& offsets,
                                     std::int32_t below) const;
  // ||v(x) - v(x0)||_2 and ||v(x)||_2 (see above).
  double Displacement(const Eigen::VectorXd& x, const double* coeff) const;
  double RoundingBound(const Eigen::VectorXd& x, const double* coeff) const;

  const LogLinearEnergy* dense_;
  bool anchored_ = false, anchor_variable_ = false;
  std::uint64_t variable_version_ = 0, weights_version_ = ~std::uint64_t(0);
  std::vector<double> x0_, coeff0_;          // the anchor (V pass: ln C, tau, beta)
  std::vector<double> row_norm_;             // N_c of the full mode (fixed per level)
  std::vector<double> norm_;                 // N_c of the anchor's mode
  double norm_max_ = 0;
  std::vector<double> L0_, scratch_;         // L_c at the anchor; of the last sweep
  double anchor_energy_ = 0;
  std::uint64_t anchor_weights_version_ = 0;
  std::vector<std::int32_t> rank_;           // -1: band; position in the list; INT32_MAX: neither
  std::vector<double> list_r_;               // radii of the list's items, ascending
  std::vector<std::int64_t> list_cell_;      // the list's items: a cell, or -1 - b for block b
  std::vector<std::int64_t> list_cells_prefix_;  // cells in the first k items
  double list_cap_ = 0;                      // every cell beyond the list has r_c >= list_cap_
  std::vector<std::int64_t> candidates_;     // band and list cells, ascending
  std::vector<std::int64_t> block_offsets_;  // candidates_ grouped by kEnergyBlock blocks
  std::vector<std::int64_t> row_order_;      // on the fly: the anchor's candidates, most used first
  loglinear::Fixed const_total_ = 0;         // energy of all saturated (non-band) cells
  std::vector<loglinear::Fixed> prefix_;     // energy of the first k list items
  long long extra_ = 0;                      // list cells evaluated since the anchor
  long long anchor_cost_ = 0;                // cells an anchor evaluates (ski rental)
  std::int64_t band_count_ = 0;
  // Blocks: shared geometry; per block the sign of a saturated block (0: its cells are exact)
  // and its radius, at the anchor and at the last block sweep (pending until adopted).
  std::shared_ptr<const BandBlocks> blocks_;
  std::vector<signed char> block_sign_, pending_sign_;
  std::vector<double> pending_radius_;        // r_B of the saturated blocks (kept by Adopt)
  double pending_norm_max_ = 0;
  bool anchor_blocked_ = false, pending_blocked_ = false;
  std::vector<std::int64_t> exact_, pending_exact_;  // cells of unproven blocks, ascending
  std::vector<loglinear::Fixed> block_energy_plus_, block_energy_minus_;  // sum of a block's terms at th = +-1
  std::uint64_t block_weights_version_ = ~std::uint64_t(0);
  BandStats stats_;
};

}  // namespace quijibo
