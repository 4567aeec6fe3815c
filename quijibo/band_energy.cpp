#include "quijibo/band_energy.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include "quijibo/error.h"

namespace quijibo {

using loglinear::Fixed;

namespace {
constexpr std::int32_t kOutside = std::numeric_limits<std::int32_t>::max();
constexpr double kUnit = std::numeric_limits<double>::epsilon() / 2;  // u
}  // namespace

BandEnergy::BandEnergy(const LogLinearEnergy* dense) : dense_(dense) {
  if (!dense) throw Error("band: no dense evaluator");
  if (dense->active_count() >= kOutside) throw Error("band: too many cells");
  stats_.cells = dense->active_count();
}

void BandEnergy::ResetStats() {
  const long long band = stats_.band_cells;
  stats_ = BandStats{};
  stats_.cells = dense_->active_count();
  stats_.band_cells = band;
}

double BandEnergy::Displacement(const Eigen::VectorXd& x, const double* coeff) const {
  double d = 0;
  if (anchor_variable_) {
    for (int k = 0; k < 3; ++k) d += (x[k] - x0_[k]) * (x[k] - x0_[k]);
  } else {
    d = (x[0] - x0_[0]) * (x[0] - x0_[0]);
    for (int j = 0; j < dense_->root_count(); ++j) d += (coeff[j] - coeff0_[j]) * (coeff[j] - coeff0_[j]);
  }
  // The sum's own rounding: relative (R + 2) u at most.
  return std::sqrt(d) * (1.0 + 4.0 * (dense_->root_count() + 2) * kUnit);
}

double BandEnergy::RoundingBound(const Eigen::VectorXd& x, const double* coeff) const {
  double v = x[0] * x[0];
  int terms = 3;
  if (anchor_variable_) {
    v += x[1] * x[1] + x[2] * x[2];
  } else {
    terms = dense_->root_count() + 1;
    for (int j = 0; j < dense_->root_count(); ++j) v += coeff[j] * coeff[j];
  }
  return 4.0 * terms * kUnit * std::sqrt(v) * norm_max_;
}

Evaluation<double> BandEnergy::Sweep(const Eigen::VectorXd& x, bool variable, bool with_gradient) {
  const std::int64_t m = dense_->active_count();
  scratch_.resize(std::size_t(m));
  const bool need_norms = !variable && row_norm_.empty();
  if (need_norms) row_norm_.resize(std::size_t(m));
  return dense_->EvaluateCapturing(x, variable ? EnergyMode::kVariable : EnergyMode::kFull, with_gradient,
                                   scratch_.data(), need_norms ? row_norm_.data() : nullptr);
}

void BandEnergy::Adopt(const Eigen::VectorXd& x, bool variable, double energy) {
  const std::int64_t m = dense_->active_count();
  const int r = dense_->root_count();
  anchor_variable_ = variable;
  variable_version_ = dense_->variable_version();
  anchor_energy_ = energy;
  anchor_weights_version_ = dense_->weights_version();
  x0_.assign(x.data(), x.data() + 3);
  coeff0_.resize(static_cast<std::size_t>(r));
  dense_->Coefficients(x, coeff0_.data());
  std::swap(L0_, scratch_);
  norm_.resize(std::size_t(m));
  if (variable) {
    for (std::int64_t a = 0; a < m; ++a) {
      const double st = dense_->s_top(a), sb = dense_->s_bottom(a);
      norm_[a] = std::sqrt(1.0 + st * st + sb * sb);
    }
  } else {
    std::copy(row_norm_.begin(), row_norm_.end(), norm_.begin());
  }
  norm_max_ = 0;
  for (double n : norm_) norm_max_ = std::max(norm_max_, n);

  // Band, radii and the sorted list.
  const double l_sat = kBandSaturation / dense_->alpha();
  const double e0 = RoundingBound(x, coeff0_.data());
  rank_.assign(std::size_t(m), kOutside);
  std::vector<std::pair<double, std::int64_t>> items;
  items.reserve(std::size_t(m));
  band_count_ = 0;
  for (std::int64_t a = 0; a < m; ++a) {
    const double s = std::fabs(L0_[a]) - l_sat - e0;
    if (!(s > 0)) {  // also NaN
      rank_[a] = -1;
      ++band_count_;
    } else {
      items.emplace_back(s / norm_[a], a);
    }
  }
  const std::int64_t n = std::int64_t(items.size());
  const std::int64_t K = std::min<std::int64_t>(n, std::max<std::int64_t>(band_count_, m / 16));
  if (K < n) {
    std::nth_element(items.begin(), items.begin() + K, items.end());
    list_cap_ = items[std::size_t(K)].first;
    for (std::int64_t i = K + 1; i < n; ++i) list_cap_ = std::min(list_cap_, items[std::size_t(i)].first);
  } else {
    list_cap_ = std::numeric_limits<double>::infinity();
  }
  std::sort(items.begin(), items.begin() + K);
  list_r_.resize(std::size_t(K));
  list_cell_.resize(std::size_t(K));
  for (std::int64_t i = 0; i < K; ++i) {
    list_r_[i] = items[std::size_t(i)].first;
    list_cell_[i] = items[std::size_t(i)].second;
    rank_[std::size_t(list_cell_[i])] = std::int32_t(i);
  }

  // The candidates in cell order, grouped by the dense evaluator's blocks.
  candidates_.clear();
  block_ids_.clear();
  block_offsets_.clear();
  for (std::int64_t a = 0; a < m; ++a) {
    if (rank_[a] == kOutside) continue;
    const std::int64_t b = a / kEnergyBlock;
    if (block_ids_.empty() || block_ids_.back() != b) {
      block_ids_.push_back(b);
      block_offsets_.push_back(std::int64_t(candidates_.size()));
    }
    candidates_.push_back(a);
  }
  block_offsets_.push_back(std::int64_t(candidates_.size()));
  // Without a stored matrix, keep the candidates' rows (computing them is the costly part).
  compact_rows_ = !variable && dense_->storage() != LogLinearOptions::Storage::kDouble;
  candidate_rows_.clear();
  if (compact_rows_) {
    const std::int64_t nc = std::int64_t(candidates_.size());
    candidate_rows_.resize(std::size_t(nc) * r);
#pragma omp parallel if (nc > kEnergyBlock)
    {
      std::vector<double> buffer(static_cast<std::size_t>(r));
#pragma omp for schedule(static)
      for (std::int64_t i = 0; i < nc; ++i) {
        const double* row = dense_->RowOf(candidates_[i], buffer.data());
        std::copy(row, row + r, candidate_rows_.begin() + i * r);
      }
    }
  }
  weights_version_ = ~std::uint64_t(0);  // constants follow the new band
  extra_ = 0;
  anchored_ = true;
  stats_.band_cells = band_count_;
}

void BandEnergy::UpdateConstants() {
  const std::int64_t m = dense_->active_count();
  const double scale = dense_->energy_scale();
  // A saturated cell's term is the dense evaluator's with tanh = sign(L) exactly.
  auto term = [&](std::int64_t a) {
    bool bad = false;
    return loglinear::EnergyFixed(L0_[a] > 0 ? 1.0 : -1.0, dense_->weight(a), scale, &bad);
  };
  const_total_ = 0;
  for (std::int64_t a = 0; a < m; ++a)
    if (rank_[a] >= 0) const_total_ += term(a);
  prefix_.assign(list_cell_.size() + 1, 0);
  for (std::size_t i = 0; i < list_cell_.size(); ++i) prefix_[i + 1] = prefix_[i] + term(list_cell_[i]);
  weights_version_ = dense_->weights_version();
}

Evaluation<double> BandEnergy::Evaluate(const Eigen::VectorXd& x, EnergyMode mode, bool with_gradient) {
  const auto start = std::chrono::steady_clock::now();
  dense_->CheckX(x);
  const bool variable = mode == EnergyMode::kVariable;
  if (variable && !dense_->variable_ready())
    throw Error("energy: a V-pass evaluation needs BeginVariablePass first");
  const int r = dense_->root_count();
  const std::int64_t m = dense_->active_count();
  std::vector<double> coeff(static_cast<std::size_t>(r));
  dense_->Coefficients(x, coeff.data());
  ++stats_.evaluations;
  auto finish = [&](Evaluation<double> ev) {
    ev.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return ev;
  };
  if (!anchored_ || variable != anchor_variable_ || (variable && variable_version_ != dense_->variable_version())) {
    Evaluation<double> ev = Sweep(x, variable, with_gradient);
    Adopt(x, variable, ev.energy);
    ++stats_.anchors;
    return finish(ev);
  }
  if (RoundingBound(x, coeff.data()) > 0.9 / dense_->alpha()) {
    ++stats_.dense_fallbacks;
    return finish(dense_->Evaluate(x, mode, with_gradient));
  }
  // Cells of the list with r_c <= d(x) may have left saturation: evaluate them.
  const double d = Displacement(x, coeff.data());
  const std::int64_t k = std::upper_bound(list_r_.begin(), list_r_.end(), d) - list_r_.begin();
  const bool beyond = k == std::int64_t(list_r_.size()) && d >= list_cap_;
  if (beyond || extra_ + k > m) {
    Evaluation<double> ev = Sweep(x, variable, with_gradient);
    const bool adopt = !beyond || anchor_weights_version_ != dense_->weights_version() || !(ev.energy > anchor_energy_);
    if (adopt) {
      Adopt(x, variable, ev.energy);
      ++stats_.anchors;
      ++(beyond ? stats_.anchors_reach : stats_.anchors_work);
    } else {
      ++stats_.far;
    }
    return finish(ev);
  }
  extra_ += k;
  if (weights_version_ != dense_->weights_version()) UpdateConstants();

  const double lnC = x[0], tau = x[1], beta = x[2], alpha = dense_->alpha(), scale = dense_->energy_scale();
  const int nb_vals = 3 + (with_gradient && !variable ? r : 0);
  const std::int64_t nblocks = std::int64_t(block_ids_.size());
  std::vector<double> partial(std::size_t(nblocks * nb_vals), 0.0);
  std::vector<Fixed> block_energy(std::size_t(nblocks), 0);
  std::vector<std::int64_t> block_nonfinite(std::size_t(nblocks), 0);
  const std::int32_t kk = std::int32_t(k);
#pragma omp parallel if (nblocks > 1)
  {
    std::vector<double> buffer(static_cast<std::size_t>(r));
#pragma omp for schedule(dynamic, 1)
    for (std::int64_t bi = 0; bi < nblocks; ++bi) {
      double* out = partial.data() + bi * nb_vals;
      Fixed energy = 0;
      std::int64_t nonfinite = 0;
      for (std::int64_t i = block_offsets_[bi]; i < block_offsets_[bi + 1]; ++i) {
        const std::int64_t a = candidates_[i];
        if (rank_[a] >= kk) continue;  // provably saturated: in the constant
        const double* row = nullptr;
        double L;
        if (variable) {
          L = loglinear::VariableL(lnC, tau, beta, dense_->s_top(a), dense_->s_bottom(a));
        } else {
          row = compact_rows_ ? candidate_rows_.data() + i * r : dense_->RowOf(a, buffer.data());
          L = lnC + loglinear::Dot(coeff.data(), row, r);
        }
        const double W = dense_->weight(a);
        double g;
        const double th = loglinear::Tanh(alpha, L, W, &g);
        bool bad = false;
        energy += loglinear::EnergyFixed(th, W, scale, &bad);
        nonfinite += bad;
        if (!with_gradient || g == 0.0) continue;
        if (variable) loglinear::AccumulateVariable(g, dense_->s_top(a), dense_->s_bottom(a), out);
        else {
          out[0] += g;
          loglinear::Axpy(g, row, out + 3, r);
        }
      }
      block_energy[bi] = energy;
      block_nonfinite[bi] = nonfinite;
    }
  }
  // Blocks without candidates add exact zeros in the dense sums: summing the others in block order
  // gives the dense totals.
  std::vector<double> total(std::size_t(nb_vals), 0.0);
  Fixed energy = const_total_ - prefix_[std::size_t(k)];
  std::int64_t nonfinite = 0;
  for (std::int64_t bi = 0; bi < nblocks; ++bi) {
    for (int j = 0; j < nb_vals; ++j) total[j] += partial[std::size_t(bi * nb_vals + j)];
    energy += block_energy[bi];
    nonfinite += block_nonfinite[bi];
  }
  const long long exact = band_count_ + k;
  stats_.exact_cells += exact;
  stats_.max_exact = std::max(stats_.max_exact, exact);
  return finish(dense_->Assemble(x, variable, with_gradient, energy, total.data(), nonfinite));
}

}  // namespace quijibo
