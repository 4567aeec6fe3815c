#include "quijibo/loglinear_energy.h"

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>

#include "util/error.h"

namespace quijibo {

namespace loglinear {

// Out of line on purpose: both evaluators must run the very same instructions (see the header).
__attribute__((noinline)) double Dot(const double* coeff, const double* row, int r) {
  double s = 0;
#pragma omp simd reduction(+ : s)
  for (int j = 0; j < r; ++j) s += coeff[j] * row[j];
  return s;
}

__attribute__((noinline)) void Axpy(double g, const double* row, double* G, int r) {
#pragma omp simd
  for (int j = 0; j < r; ++j) G[j] += g * row[j];
}

__attribute__((noinline)) double VariableL(double lnC, double tau, double beta, double s_top, double s_bottom) {
  return lnC + tau * s_top - beta * s_bottom;
}

__attribute__((noinline)) double Tanh(double alpha, double L, double W, double* g) {
  const double th = std::tanh(alpha * L);
  *g = -alpha * W * (1.0 - th * th);
  return th;
}

__attribute__((noinline)) Fixed EnergyFixed(double th, double W, double scale, bool* nonfinite) {
  const double e = -th * W * scale;
  if (!std::isfinite(e) || std::fabs(e) >= 0x1p126) {
    *nonfinite = true;
    return 0;
  }
  return Fixed(e);
}

__attribute__((noinline)) void AccumulateVariable(double g, double s_top, double s_bottom, double* sums) {
  sums[0] += g;
  sums[1] += g * s_top;
  sums[2] += g * s_bottom;
}

double EnergyScale(double sum_abs_weight) {
  if (!(sum_abs_weight > 0) || !std::isfinite(sum_abs_weight)) return 1.0;
  return std::ldexp(1.0, 100 - std::ilogb(sum_abs_weight) - 1);
}

}  // namespace loglinear

using Storage = LogLinearOptions::Storage;

std::string LogLinearOptions::Validate() const {
  if (!(memory_budget_bytes >= 0)) return "memory budget must be >= 0";
  if (sharing < 1) return "memory budget sharing must be >= 1";
  return {};
}

LogLinearEnergy::LogLinearEnergy(const RationalMap& map, const EnergyGrid& grid,
                                 const EnergyOptions& options, const LogLinearOptions& loglinear)
    : frame_(grid.frame), slice_(grid.slice), eta_(grid.eta), options_(options), storage_(loglinear.storage) {
  const auto start = std::chrono::steady_clock::now();
  if (auto why = options.Validate(); !why.empty()) throw Error("energy options: " + why);
  if (auto why = loglinear.Validate(); !why.empty()) throw Error("loglinear options: " + why);
  if (auto why = map.Validate(); !why.empty()) throw Error("map: " + why);
  total_cells_ = grid.frame.cell_count();
  if (std::int64_t(grid.weight.size()) != total_cells_)
    throw Error("energy grid: weight count does not match the grid");
  nt_ = map.top_count();
  nb_ = map.bottom_count();
  roots_ = map.top_roots;
  roots_.insert(roots_.end(), map.bottom_roots.begin(), map.bottom_roots.end());
  const std::vector<char> singular = SingularCells(map, grid, &singular_);
  for (std::int64_t c = 0; c < total_cells_; ++c)
    if (!singular[c]) {
      cells_.push_back(c);
      weight_.push_back(grid.weight[c]);
    }
  UpdateScale();
  const std::int64_t m = std::int64_t(cells_.size());
  const int r = root_count();
  for (const Vec4& t : roots_) {
    root_x_.push_back(t[0]);
    root_y_.push_back(t[1]);
    root_z_.push_back(t[2]);
    root_w_.push_back(t[3]);
  }
  memory_budget_bytes_ = loglinear.memory_budget_bytes / loglinear.sharing;
  cache_budget_bytes_ = memory_budget_bytes_ / 2;
  if (storage_ == Storage::kAuto) {
    const double matrix = double(m) * r * sizeof(double);
    const double stored_max = loglinear.band ? memory_budget_bytes_ / 8 : memory_budget_bytes_;
    storage_ = matrix <= stored_max ? Storage::kDouble : Storage::kOnTheFly;
    // Not stored to save memory: the band's rows get what a stored matrix could have taken.
    if (matrix <= loglinear.memory_budget_bytes) cache_budget_bytes_ = std::min(cache_budget_bytes_, stored_max);
  }
  if (storage_ == Storage::kDouble || storage_ == Storage::kFloat) {
    if (storage_ == Storage::kDouble) d_double_.resize(std::size_t(m) * r);
    else d_float_.resize(std::size_t(m) * r);
#pragma omp parallel if (m > kEnergyBlock)
    {
      std::vector<double> row(r);
#pragma omp for schedule(static)
      for (std::int64_t a = 0; a < m; ++a) {
        Row(a, row.data());
        if (storage_ == Storage::kDouble) std::copy(row.begin(), row.end(), d_double_.begin() + a * r);
        else
          for (int j = 0; j < r; ++j) d_float_[std::size_t(a) * r + j] = float(row[j]);
      }
    }
  }
  setup_seconds_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

LogLinearEnergy::~LogLinearEnergy() = default;

std::size_t LogLinearEnergy::matrix_bytes() const {
  return d_double_.size() * sizeof(double) + d_float_.size() * sizeof(float);
}

double LogLinearEnergy::LogDistance(const Vec3& p, int j) const {
  const Vec4& t = roots_[std::size_t(j)];
  const double a = p[0] - t[0], b = p[1] - t[1], c = p[2] - t[2], d = slice_ - t[3];
  return 0.5 * std::log(a * a + b * b + c * c + d * d);
}

void LogLinearEnergy::Row(std::int64_t active, double* out) const {
  const Vec3 p = frame_.cell_center(cells_[std::size_t(active)]);
  const int r = root_count();
  // LogDistance's arithmetic in the same order, the squared distances first: they vectorize, and
  // the logarithms then run back to back (the same std::log, so the same bits).
  const double px = p[0], py = p[1], pz = p[2], w = slice_;
  const double *tx = root_x_.data(), *ty = root_y_.data(), *tz = root_z_.data(), *tw = root_w_.data();
#pragma omp simd
  for (int j = 0; j < r; ++j) {
    const double a = px - tx[j], b = py - ty[j], c = pz - tz[j], d = w - tw[j];
    out[j] = a * a + b * b + c * c + d * d;
  }
  for (int j = 0; j < r; ++j) out[j] = 0.5 * std::log(out[j]);
}

void LogLinearEnergy::CacheRows(const std::vector<std::int64_t>& actives, const void* owner, double max_bytes) const {
  if (storage_ != Storage::kOnTheFly) return;
  row_owner_ = owner;
  const int r = root_count();
  const std::size_t row_bytes = std::size_t(r) * sizeof(double);
  const std::size_t cap = std::size_t(std::min(std::min(cache_budget_bytes_, max_bytes) / double(row_bytes),
                                               double(std::numeric_limits<std::int32_t>::max() - 1)));
  if (row_slot_.empty()) row_slot_.assign(cells_.size(), -1);
  // The distinct rows asked for, in order, as many as fit; `fresh`: those not kept yet. Afterwards
  // the cache holds `wanted` <= cap rows and at most a third more not asked for.
  std::vector<char> asked(cells_.size(), 0);
  std::size_t wanted = 0;
  std::vector<std::int64_t> fresh;
  for (std::int64_t a : actives) {
    if (wanted == cap) break;
    if (asked[std::size_t(a)]) continue;
    asked[std::size_t(a)] = 1;
    ++wanted;
    if (row_slot_[std::size_t(a)] < 0) fresh.push_back(a);
  }
  std::size_t rows = row_cell_.size();
  const std::size_t stale = rows - (wanted - fresh.size());
  if (rows + fresh.size() > cap || (stale > 0 && 4 * stale > rows + fresh.size())) {
    // Drop the rows not asked for, moving the others down in slot order (no second copy).
    std::size_t next = 0;
    for (std::size_t slot = 0; slot < rows; ++slot) {
      const std::int64_t a = row_cell_[slot];
      if (!asked[std::size_t(a)]) {
        row_slot_[std::size_t(a)] = -1;
        continue;
      }
      if (next != slot) std::memcpy(Slot(next), Slot(slot), row_bytes);  // next < slot: distinct rows
      row_slot_[std::size_t(a)] = std::int32_t(next);
      row_cell_[next++] = a;
    }
    rows = next;
    row_cell_.resize(rows);
  }
  for (std::int64_t a : fresh) {
    row_slot_[std::size_t(a)] = std::int32_t(row_cell_.size());
    row_cell_.push_back(a);
  }
  const std::size_t chunks = (row_cell_.size() + kChunkRows - 1) / kChunkRows;
  row_chunks_.resize(chunks);  // frees the chunks beyond
  for (auto& chunk : row_chunks_)
    if (!chunk) chunk = std::make_unique_for_overwrite<double[]>(kChunkRows * std::size_t(r));
  const std::int64_t n = std::int64_t(fresh.size());
#pragma omp parallel for schedule(static) if (n > kEnergyBlock)
  for (std::int64_t i = 0; i < n; ++i) {
    const std::int64_t a = fresh[std::size_t(i)];
    Row(a, Slot(std::size_t(row_slot_[std::size_t(a)])));
  }
}

void LogLinearEnergy::CheckX(const Eigen::VectorXd& x) const {
  if (x.size() != 3 + root_count())
    throw Error("energy: variable vector has " + std::to_string(x.size()) + " entries, expected " +
                std::to_string(3 + root_count()));
  for (Eigen::Index i = 0; i < x.size(); ++i)
    if (!std::isfinite(x[i])) throw Error("energy: variable " + std::to_string(i) + " is not finite");
}

void LogLinearEnergy::UpdateScale() {
  double sum = 0;
  for (double w : weight_) sum += std::fabs(w);
  energy_scale_ = loglinear::EnergyScale(sum);
  ++weights_version_;
}

void LogLinearEnergy::SetWeights(const std::vector<double>& grid_weight, double eta) {
  if (std::int64_t(grid_weight.size()) != total_cells_) throw Error("weights do not match the energy grid");
  if (!(eta > 0) || !std::isfinite(eta)) throw Error("eta must be positive and finite");
  for (std::size_t a = 0; a < cells_.size(); ++a) weight_[a] = grid_weight[std::size_t(cells_[a])];
  eta_ = eta;
  UpdateScale();
}

const double* LogLinearEnergy::RowOf(std::int64_t a, double* buffer) const {
  const int r = root_count();
  if (storage_ == Storage::kDouble) return d_double_.data() + std::size_t(a) * r;
  if (storage_ == Storage::kFloat) {
    for (int j = 0; j < r; ++j) buffer[j] = d_float_[std::size_t(a) * r + j];
  } else {
    if (!row_slot_.empty() && row_slot_[std::size_t(a)] >= 0)
      return Slot(std::size_t(row_slot_[std::size_t(a)]));
    Row(a, buffer);
  }
  return buffer;
}

void LogLinearEnergy::Coefficients(const Eigen::VectorXd& x, double* coeff) const {
  for (int j = 0; j < nt_; ++j) coeff[j] = x[1] * x[3 + j];
  for (int j = nt_; j < root_count(); ++j) coeff[j] = -x[2] * x[3 + j];
}

std::vector<double> LogLinearEnergy::LogModulus(const Eigen::VectorXd& x) const {
  CheckX(x);
  const std::int64_t m = std::int64_t(cells_.size());
  const int r = root_count();
  std::vector<double> coeff(r);
  Coefficients(x, coeff.data());
  std::vector<double> L(std::size_t(total_cells_), std::numeric_limits<double>::quiet_NaN());
#pragma omp parallel if (m > kEnergyBlock)
  {
    std::vector<double> buffer(r);
#pragma omp for schedule(static)
    for (std::int64_t a = 0; a < m; ++a)
      L[std::size_t(cells_[a])] = x[0] + loglinear::Dot(coeff.data(), RowOf(a, buffer.data()), r);
  }
  return L;
}

void LogLinearEnergy::BeginVariablePass(const Eigen::VectorXd& x) {
  CheckX(x);
  const std::int64_t m = std::int64_t(cells_.size());
  const int r = root_count();
  s_top_.assign(std::size_t(m), 0.0);
  s_bottom_.assign(std::size_t(m), 0.0);
  const double* e = x.data() + 3;
#pragma omp parallel if (m > kEnergyBlock)
  {
    std::vector<double> buffer(r);
#pragma omp for schedule(static)
    for (std::int64_t a = 0; a < m; ++a) {
      const double* row = RowOf(a, buffer.data());
      double st = 0, sb = 0;
      for (int j = 0; j < nt_; ++j) st += e[j] * row[j];
      for (int j = nt_; j < r; ++j) sb += e[j] * row[j];
      s_top_[a] = st;
      s_bottom_[a] = sb;
    }
  }
  ++variable_version_;
}

Evaluation<double> LogLinearEnergy::Evaluate(const Eigen::VectorXd& x, EnergyMode mode,
                                             bool with_gradient) const {
  return EvaluateCapturing(x, mode, with_gradient, nullptr, nullptr);
}

Evaluation<double> LogLinearEnergy::EvaluateCapturing(const Eigen::VectorXd& x, EnergyMode mode, bool with_gradient,
                                                      double* L_active, double* row_norm) const {
  const auto start = std::chrono::steady_clock::now();
  CheckX(x);
  const bool variable = mode == EnergyMode::kVariable;
  if (variable && !variable_ready()) throw Error("energy: a V-pass evaluation needs BeginVariablePass first");
  std::vector<double> coeff(static_cast<std::size_t>(root_count()));
  Coefficients(x, coeff.data());
  const BlockSums sums = SumBlocks(x, coeff.data(), variable, with_gradient, AllCells(), L_active, row_norm);
  Evaluation<double> ev = Assemble(x, variable, with_gradient, sums.energy, sums.total.data(), sums.nonfinite);
  ev.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return ev;
}

LogLinearEnergy::BlockSums LogLinearEnergy::SumBlocks(const Eigen::VectorXd& x, const double* coeff, bool variable,
                                                      bool with_gradient, const CellBlocks& blocks, double* L_active,
                                                      double* row_norm) const {
  using loglinear::Fixed;
  const std::int64_t m = active_count();
  const int r = root_count();
  const double lnC = x[0], tau = x[1], beta = x[2], alpha = options_.alpha, scale = energy_scale_;
  // Block partials: [sum g, sum g S_T, sum g S_B] and, in full mode, G_r (from total[3]).
  const int nb_vals = 3 + (with_gradient && !variable ? r : 0);
  const std::int64_t nblocks = blocks.count;
  std::vector<double> partial(std::size_t(nblocks * nb_vals), 0.0);
  std::vector<Fixed> block_energy(std::size_t(nblocks), 0);
  std::vector<std::int64_t> block_nonfinite(std::size_t(nblocks), 0);

  // One block needs no threads (and a busy machine makes waking them costly).
#pragma omp parallel if (nblocks > 1)
  {
    std::vector<double> buffer(static_cast<std::size_t>(r));
#pragma omp for schedule(dynamic, 1)
    for (std::int64_t blk = 0; blk < nblocks; ++blk) {
      double* out = partial.data() + blk * nb_vals;
      Fixed energy = 0;
      std::int64_t nonfinite = 0;
      const std::int64_t begin = blocks.offsets ? blocks.offsets[blk] : blk * kEnergyBlock;
      const std::int64_t end = blocks.offsets ? blocks.offsets[blk + 1] : std::min(m, (blk + 1) * kEnergyBlock);
      for (std::int64_t i = begin; i < end; ++i) {
        const std::int64_t a = blocks.cells ? blocks.cells[i] : i;
        if (blocks.rank && blocks.rank[a] >= blocks.below) continue;
        const double* row = nullptr;
        double L;
        if (variable) {
          L = loglinear::VariableL(lnC, tau, beta, s_top_[a], s_bottom_[a]);
        } else {
          row = RowOf(a, buffer.data());
          L = lnC + loglinear::Dot(coeff, row, r);
          if (row_norm) {
            double n2 = 1.0;
#pragma omp simd reduction(+ : n2)
            for (int j = 0; j < r; ++j) n2 += row[j] * row[j];
            row_norm[a] = std::sqrt(n2);
          }
        }
        if (L_active) L_active[a] = L;
        double g;
        const double th = loglinear::Tanh(alpha, L, weight_[a], &g);
        bool bad = false;
        energy += loglinear::EnergyFixed(th, weight_[a], scale, &bad);
        nonfinite += bad;
        if (!with_gradient || g == 0.0) continue;
        if (variable) loglinear::AccumulateVariable(g, s_top_[a], s_bottom_[a], out);
        else {
          out[0] += g;
          loglinear::Axpy(g, row, out + 3, r);
        }
      }
      block_energy[blk] = energy;
      block_nonfinite[blk] = nonfinite;
    }
  }

  // A dense block without evaluated cells adds exact zeros: the visited blocks' sums, in block
  // order, are the dense totals.
  BlockSums sums;
  sums.total.assign(std::size_t(nb_vals), 0.0);
  for (std::int64_t b = 0; b < nblocks; ++b) {
    for (int k = 0; k < nb_vals; ++k) sums.total[k] += partial[std::size_t(b * nb_vals + k)];
    sums.energy += block_energy[b];
    sums.nonfinite += block_nonfinite[b];
  }
  return sums;
}

Evaluation<double> LogLinearEnergy::Assemble(const Eigen::VectorXd& x, bool variable, bool with_gradient,
                                             loglinear::Fixed energy, const double* total,
                                             std::int64_t nonfinite) const {
  Evaluation<double> ev;
  const double inv_eta = 1.0 / eta_;
  const int r = root_count();
  ev.energy = nonfinite > 0 ? std::numeric_limits<double>::quiet_NaN() : double(energy) / energy_scale_ * inv_eta;
  if (with_gradient) {
    ev.gradient = Eigen::VectorXd::Zero(variable ? 3 : r + 3);
    ev.gradient[0] = total[0] * inv_eta;
    if (variable) {
      ev.gradient[1] = total[1] * inv_eta;
      ev.gradient[2] = -total[2] * inv_eta;
    } else {
      const double* G = total + 3;
      const double tau = x[1], beta = x[2];
      double d_tau = 0, d_beta = 0;
      for (int j = 0; j < nt_; ++j) {
        d_tau += x[3 + j] * G[j];
        ev.gradient[3 + j] = tau * G[j] * inv_eta;
      }
      for (int j = nt_; j < r; ++j) {
        d_beta -= x[3 + j] * G[j];
        ev.gradient[3 + j] = -beta * G[j] * inv_eta;
      }
      ev.gradient[1] = d_tau * inv_eta;
      ev.gradient[2] = d_beta * inv_eta;
    }
  }
  ev.counts.cells = total_cells_;
  ev.counts.singular = singular_;
  ev.counts.overflowed = nonfinite;
  return ev;
}

}  // namespace quijibo
