// The exact fast evaluator (design brief §3.1), in double.
//
// Because |p q| = |p| |q| and |p^a| = |p|^a for quaternions, one application of the map has
//   L_c = ln C + tau sum_i T_i D_ci - beta sum_i B_i D_cj,     D_cr = log|q_c - root_r|,
// whatever the order of the products. The roots do not move during the optimization, so D is
// fixed per level: L for all cells is one matrix-vector product and the gradient is one
// transposed product (G_r = sum_c dpsi/dL_c D_cr; dpsi/dT_i = tau G_i, dpsi/dtau = sum T_i G_i,
// and likewise for the bottom roots with a minus sign). Nothing can overflow.
//
// A V pass (only ln C, tau, beta move) needs two sums per cell, S_T and S_B, computed once by
// BeginVariablePass; each evaluation is then O(cells), not O(cells x roots).
//
// The energy is summed exactly (loglinear_kernel.h), so psi does not depend on the order of the
// cells; the narrow band (band_energy.h) reuses this class's matrix and arithmetic.
//
// Storage of D, chosen by measurement (docs/benchmarks.md):
//   kDouble   precomputed, 8 bytes per cell and root (97^3 x 331: 2.4 GB), exact
//   kFloat    precomputed, 4 bytes; ~1e-7 relative error in D (not exact, opt-in)
//   kOnTheFly recomputed at every evaluation, ~5x slower; the narrow band keeps the rows of the
//             cells near the surface (CacheRows, within half the memory budget)
//   kAuto     kDouble if it fits in memory_budget_bytes, else kOnTheFly; read through a narrow
//             band, kDouble only up to an eighth of the budget (docs/benchmarks.md §8 "Memory")
#pragma once

#include <limits>
#include <memory>

#include "quijibo/energy.h"
#include "quijibo/loglinear_kernel.h"
#include "util/settings.h"

namespace quijibo {

struct LogLinearOptions {
  enum class Storage { kAuto, kDouble, kFloat, kOnTheFly };
  Storage storage = Storage::kAuto;
  // For kAuto: the bunny's 97^3 x 601 matrix (4.4 GB) is stored for a dense run; through a band,
  // a run that fits between the nodes peaks at 1.3 GB on the demo (docs/benchmarks.md §18).
  double memory_budget_bytes = 6.0e9;
  // The evaluator is read through a narrow band (band_energy.h), which evaluates a few % of the
  // cells and keeps their rows. kAuto then stores the matrix only when it takes at most
  // memory_budget_bytes / 8 (the coarse levels, where the band's blocks prove few cells saturated
  // and a stored matrix is much faster), and otherwise keeps only the band's rows, within that
  // eighth unless the matrix does not fit the budget at all (then half, as kOnTheFly): the bunny's
  // 97^3 x 601 matrix (4.4 GB) becomes < 1 GB of rows at little cost in time.
  bool band = false;
  // Evaluators of the same size that share the budget (the nodes' and the corners' of a run that
  // fits between the nodes): each stores and caches within its part, budget / sharing.
  int sharing = 1;
  std::string Validate() const;
};
inline const EnumNames<LogLinearOptions::Storage> kStorages("log-distance storage",
                                                            {{LogLinearOptions::Storage::kAuto, "auto"},
                                                             {LogLinearOptions::Storage::kDouble, "double"},
                                                             {LogLinearOptions::Storage::kFloat, "float"},
                                                             {LogLinearOptions::Storage::kOnTheFly, "on-the-fly"}},
                                                            {{LogLinearOptions::Storage::kOnTheFly, "none"}});
inline const std::vector<std::string>& kStorageNames = kStorages.names();
inline LogLinearOptions::Storage ParseStorage(const std::string& name) { return kStorages.Parse(name); }
inline std::string StorageName(LogLinearOptions::Storage s) { return kStorages.Name(s); }

class LogLinearEnergy {
 public:
  LogLinearEnergy(const RationalMap& map, const EnergyGrid& grid, const EnergyOptions& options = {},
                  const LogLinearOptions& loglinear = {});
  ~LogLinearEnergy();

  // psi and its gradient at x = [ln C, tau, beta, T..., B...]. kVariable mode needs
  // BeginVariablePass first and uses only x[0..2]; its gradient has 3 entries.
  Evaluation<double> Evaluate(const Eigen::VectorXd& x, EnergyMode mode = EnergyMode::kFull,
                              bool with_gradient = true) const;
  // Evaluate, also writing L of every active cell to L_active (if not null) and, in full mode,
  // sqrt(1 + sum_r D_cr^2) to row_norm (if not null): what the narrow band's anchor needs.
  Evaluation<double> EvaluateCapturing(const Eigen::VectorXd& x, EnergyMode mode, bool with_gradient,
                                       double* L_active, double* row_norm) const;
  // Fixes the exponents T and B of x for the following kVariable evaluations: O(cells x roots).
  void BeginVariablePass(const Eigen::VectorXd& x);

  // Replaces the weights (one per grid cell, as EnergyGrid::weight) and eta, e.g. for the
  // reweighted pass; D is kept.
  void SetWeights(const std::vector<double>& grid_weight, double eta);
  // L = log|R(q_c)| at x for every grid cell (singular cells: NaN).
  std::vector<double> LogModulus(const Eigen::VectorXd& x) const;

  LogLinearOptions::Storage storage() const { return storage_; }
  std::size_t matrix_bytes() const;
  double setup_seconds() const { return setup_seconds_; }

  int root_count() const { return nt_ + nb_; }
  int top_count() const { return nt_; }

  // What the narrow band (band_energy.h) reads. "Active" cells are the non-singular ones, in grid
  // order; a = 0 .. active_count()-1.
  std::int64_t active_count() const { return std::int64_t(cells_.size()); }
  std::int64_t cell_of(std::int64_t a) const { return cells_[std::size_t(a)]; }
  double weight(std::int64_t a) const { return weight_[std::size_t(a)]; }
  double s_top(std::int64_t a) const { return s_top_[std::size_t(a)]; }
  double s_bottom(std::int64_t a) const { return s_bottom_[std::size_t(a)]; }
  double alpha() const { return options_.alpha; }
  double energy_scale() const { return energy_scale_; }
  // The D row of active cell a: a pointer into the matrix or the row cache, or `buffer`
  // (root_count() entries) filled.
  const double* RowOf(std::int64_t a, double* buffer) const;
  // On-the-fly storage: keeps the rows of the active cells `actives` (duplicates allowed), so that
  // RowOf returns them without logarithms: rows already kept stay, missing ones are computed.
  // Rows that `actives` does not list are dropped once they would make up a quarter of the cache,
  // so that it follows the band rather than accumulating. At most half the memory budget: beyond
  // it, as many of `actives`, from the first, as fit (so list them most used first). Other
  // storages: nothing. Not to be called while RowOf runs. `owner` (a band) is remembered, so that
  // a band over a shared evaluator can leave another band's rows alone; max_bytes caps the cache
  // below its budget for this request.
  void CacheRows(const std::vector<std::int64_t>& actives, const void* owner = nullptr,
                 double max_bytes = std::numeric_limits<double>::infinity()) const;
  // Who last called CacheRows (null: nobody).
  const void* row_owner() const { return row_owner_; }
  // The evaluator's part of the memory budget (LogLinearOptions::memory_budget_bytes / sharing).
  double memory_budget_bytes() const { return memory_budget_bytes_; }
  std::size_t cached_row_bytes() const { return row_cell_.size() * std::size_t(root_count()) * sizeof(double); }
  // The grid and the roots (the band's blocks bound D from them).
  const GridFrame& frame() const { return frame_; }
  double slice() const { return slice_; }
  const std::vector<Vec4>& roots() const { return roots_; }
  // D of a point of the slice and root j, as Row computes it for a cell centre.
  double LogDistance(const Vec3& p, int j) const;
  // Change counters: SetWeights and BeginVariablePass bump them (the band's cached state keys on them).
  std::uint64_t weights_version() const { return weights_version_; }
  std::uint64_t variable_version() const { return variable_version_; }
  bool variable_ready() const { return s_top_.size() == cells_.size(); }
  // coeff = [tau T, -beta B] of x.
  void Coefficients(const Eigen::VectorXd& x, double* coeff) const;

  // The cells a block sum visits. Block b holds positions offsets[b] .. offsets[b+1] (offsets
  // null: b kEnergyBlock .. (b+1) kEnergyBlock, clipped to the active cells); position i is
  // active cell cells[i] (cells null: i). With rank, cells whose rank is >= below are skipped
  // (the band's provably saturated ones). Blocks are the dense evaluator's kEnergyBlock blocks,
  // or subsets of them in cell order: that is what makes the sums agree bit for bit.
  struct CellBlocks {
    std::int64_t count = 0;
    const std::int64_t* offsets = nullptr;
    const std::int64_t* cells = nullptr;
    const std::int32_t* rank = nullptr;
    std::int32_t below = 0;
  };
  // Sums over the visited cells: the exact energy, the totals Assemble takes and the non-finite
  // count.
  struct BlockSums {
    loglinear::Fixed energy = 0;
    std::vector<double> total;
    std::int64_t nonfinite = 0;
  };
  // The one cell loop of the dense evaluator and the band: per block and in cell order, L (from
  // coeff = Coefficients(x), or the V-pass sums), tanh, the energy term and the gradient sums;
  // then the blocks' sums in block order. Also writes L of each visited cell to L_active and, in
  // full mode, sqrt(1 + sum_r D_cr^2) to row_norm (each if not null).
  BlockSums SumBlocks(const Eigen::VectorXd& x, const double* coeff, bool variable, bool with_gradient,
                      const CellBlocks& blocks, double* L_active, double* row_norm) const;
  // All active cells in kEnergyBlock blocks (what a dense evaluation visits).
  CellBlocks AllCells() const { return {(active_count() + kEnergyBlock - 1) / kEnergyBlock}; }
  void CheckX(const Eigen::VectorXd& x) const;
  // The evaluation from its sums: energy (in 1/energy_scale units) and, per mode, totals =
  // [sum g, sum g S_T, sum g S_B] (V pass) or [sum g, 0, 0, G_1..G_R] (full).
  Evaluation<double> Assemble(const Eigen::VectorXd& x, bool variable, bool with_gradient,
                              loglinear::Fixed energy, const double* totals, std::int64_t nonfinite) const;

 private:
  void Row(std::int64_t active, double* out) const;  // D row of an active cell
  void UpdateScale();

  int nt_ = 0, nb_ = 0;
  std::vector<Vec4> roots_;            // top then bottom
  std::vector<std::int64_t> cells_;    // grid index of each active (non-singular) cell
  std::vector<double> weight_;         // W of each active cell
  GridFrame frame_;
  double slice_ = 0, eta_ = 1;
  std::int64_t total_cells_ = 0, singular_ = 0;
  EnergyOptions options_;
  LogLinearOptions::Storage storage_;
  std::vector<double> d_double_;
  std::vector<float> d_float_;
  std::vector<double> s_top_, s_bottom_;  // V-pass sums
  double cache_budget_bytes_ = 0;
  // The row cache in chunks of kChunkRows rows: it grows and shrinks without copying itself, so
  // its peak memory is its size.
  static constexpr std::size_t kChunkRows = 256;
  double* Slot(std::size_t slot) const {
    return row_chunks_[slot / kChunkRows].get() + (slot % kChunkRows) * std::size_t(root_count());
  }
  mutable std::vector<std::int32_t> row_slot_;  // per active cell: its slot in the cache, or -1
  mutable std::vector<std::int64_t> row_cell_;  // per slot: its active cell
  mutable std::vector<std::unique_ptr<double[]>> row_chunks_;
  mutable const void* row_owner_ = nullptr;
  double memory_budget_bytes_ = 0;
  // The roots by component (x, y, z, w), so that a row's squared distances vectorize.
  std::vector<double> root_x_, root_y_, root_z_, root_w_;
  double energy_scale_ = 1;
  std::uint64_t weights_version_ = 0, variable_version_ = 0;
  double setup_seconds_ = 0;
};

}  // namespace quijibo
