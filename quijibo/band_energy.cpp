#include "quijibo/band_energy.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include "util/error.h"

namespace quijibo {

using loglinear::Fixed;

namespace {
constexpr std::int32_t kOutside = std::numeric_limits<std::int32_t>::max();
constexpr double kUnit = std::numeric_limits<double>::epsilon() / 2;  // u
// Absolute room for the rounding of a computed log-distance (a few u of |D| <= ~50) in e_j and
// the block norm: far above it, far below any slack that matters.
constexpr double kLogRoom = 1e-12;
}  // namespace

std::size_t BandBlocks::bytes() const {
  return (offsets.size() + actives.size()) * sizeof(std::int64_t) +
         (log_distance.size() + norm.size() + centre.size() + radius.size()) * sizeof(double) +
         (reach.size() + curvature.size()) * sizeof(float);
}

std::shared_ptr<const BandBlocks> BandBlocks::Build(const LogLinearEnergy& dense, int side) {
  if (side < 1) throw Error("band: block side must be >= 1");
  auto blocks = std::make_shared<BandBlocks>();
  const GridFrame& f = dense.frame();
  const int r = dense.root_count();
  blocks->roots = r;
  const int n[3] = {(f.dims[0] + side - 1) / side, (f.dims[1] + side - 1) / side, (f.dims[2] + side - 1) / side};
  const std::int64_t nb = std::int64_t(n[0]) * n[1] * n[2];
  const std::int64_t m = dense.active_count();
  auto block_of = [&](std::int64_t cell) {
    const std::int64_t i = cell % f.dims[0], j = (cell / f.dims[0]) % f.dims[1], k = cell / (std::int64_t(f.dims[0]) * f.dims[1]);
    return i / side + n[0] * (j / side + std::int64_t(n[1]) * (k / side));
  };
  // Counting sort of the active cells by block; ascending within a block since a ascends.
  blocks->offsets.assign(std::size_t(nb + 1), 0);
  for (std::int64_t a = 0; a < m; ++a) ++blocks->offsets[std::size_t(block_of(dense.cell_of(a)) + 1)];
  for (std::int64_t b = 0; b < nb; ++b) blocks->offsets[std::size_t(b + 1)] += blocks->offsets[std::size_t(b)];
  blocks->actives.resize(std::size_t(m));
  {
    std::vector<std::int64_t> next(blocks->offsets.begin(), blocks->offsets.end() - 1);
    for (std::int64_t a = 0; a < m; ++a) blocks->actives[std::size_t(next[std::size_t(block_of(dense.cell_of(a)))]++)] = a;
  }
  blocks->log_distance.resize(std::size_t(nb) * r);
  blocks->reach.resize(std::size_t(nb) * r);
  blocks->curvature.resize(std::size_t(nb) * r);
  blocks->norm.resize(std::size_t(nb));
  blocks->centre.resize(std::size_t(nb) * 3);
  blocks->radius.resize(std::size_t(nb));
  const float inf = std::numeric_limits<float>::infinity();
  // A float bound >= v (beyond float's range: infinity, as converting would be undefined).
  auto up = [&](double v) {
    return v < double(std::numeric_limits<float>::max()) ? std::nextafter(float(v), inf) : inf;
  };
#pragma omp parallel for schedule(dynamic, 16)
  for (std::int64_t b = 0; b < nb; ++b) {
    const int bi = int(b % n[0]), bj = int((b / n[0]) % n[1]), bk = int(b / (std::int64_t(n[0]) * n[1]));
    // Index ranges [lo, hi] of the block's cells; the centre of their centres and the reach h.
    const int lo[3] = {bi * side, bj * side, bk * side};
    const int hi[3] = {std::min(f.dims[0], lo[0] + side) - 1, std::min(f.dims[1], lo[1] + side) - 1,
                       std::min(f.dims[2], lo[2] + side) - 1};
    Vec3 p;
    double h2 = 0;
    for (int k = 0; k < 3; ++k) {
      p[k] = f.min_corner[k] + f.spacing * (0.5 * (lo[k] + hi[k]) + 0.5);
      const double half = 0.5 * f.spacing * (hi[k] - lo[k]);
      h2 += half * half;
    }
    // Rounded up: every cell centre is within h of p.
    const double h = std::sqrt(h2) * (1 + 1e-12) + 1e-300;
    for (int k = 0; k < 3; ++k) blocks->centre[std::size_t(b * 3 + k)] = p[k];
    blocks->radius[std::size_t(b)] = h;
    double* D = blocks->log_distance.data() + b * r;
    float* e = blocks->reach.data() + b * r;
    float* q = blocks->curvature.data() + b * r;
    double n2 = 1.0;
    for (int j = 0; j < r; ++j) {
      D[j] = dense.LogDistance(p, j);
      const Vec4& t = dense.roots()[std::size_t(j)];
      const double ax = p[0] - t[0], ay = p[1] - t[1], az = p[2] - t[2], aw = dense.slice() - t[3];
      const double d = std::sqrt(ax * ax + ay * ay + az * az + aw * aw) * (1 - 1e-12);  // rounded down
      if (!(d > h)) {
        e[j] = q[j] = inf;
        n2 = std::numeric_limits<double>::infinity();
        continue;
      }
      const double reach = -std::log1p(-h / d) * (1 + 1e-12) + kLogRoom;
      e[j] = up(reach);
      q[j] = up(h * h / (2 * (d - h) * (d - h)) * (1 + 1e-12) + kLogRoom);
      // |D_cj| <= |D_pj| + e_j for the block's cells.
      const double M = std::fabs(D[j]) + reach;
      n2 += M * M;
    }
    blocks->norm[std::size_t(b)] = std::sqrt(n2) * (1 + 1e-12);
  }
  return blocks;
}

BandEnergy::BandEnergy(const LogLinearEnergy* dense, std::shared_ptr<const BandBlocks> blocks) : dense_(dense) {
  if (!dense) throw Error("band: no dense evaluator");
  if (dense->active_count() >= kOutside) throw Error("band: too many cells");
  stats_.cells = dense->active_count();
  if (dense->storage() == LogLinearOptions::Storage::kOnTheFly) {
    blocks_ = blocks ? std::move(blocks) : BandBlocks::Build(*dense);
    if (blocks_->roots != dense->root_count() || std::int64_t(blocks_->actives.size()) != dense->active_count())
      throw Error("band: the blocks belong to another evaluator");
    stats_.blocks = blocks_->count();
  }
}

void BandEnergy::ResetStats() {
  const long long band = stats_.band_cells;
  stats_ = BandStats{};
  stats_.cells = dense_->active_count();
  stats_.band_cells = band;
  stats_.blocks = blocks_ ? blocks_->count() : 0;
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

std::vector<std::int64_t> BandEnergy::Group(const std::vector<std::int64_t>& cells) {
  std::vector<std::int64_t> offsets;
  for (std::size_t i = 0; i < cells.size(); ++i)
    if (i == 0 || cells[i] / kEnergyBlock != cells[i - 1] / kEnergyBlock) offsets.push_back(std::int64_t(i));
  offsets.push_back(std::int64_t(cells.size()));
  return offsets;
}

LogLinearEnergy::CellBlocks BandEnergy::Blocks(const std::vector<std::int64_t>& cells,
                                               const std::vector<std::int64_t>& offsets, std::int32_t below) const {
  LogLinearEnergy::CellBlocks blocks;
  blocks.count = std::int64_t(offsets.size()) - 1;
  blocks.offsets = offsets.data();
  blocks.cells = cells.data();
  if (below >= 0) {
    blocks.rank = rank_.data();
    blocks.below = below;
  }
  return blocks;
}

Evaluation<double> BandEnergy::Sweep(const Eigen::VectorXd& x, bool variable, bool with_gradient) {
  const std::int64_t m = dense_->active_count();
  scratch_.resize(std::size_t(m));
  if (blocks_ && !variable) return BlockSweep(x, with_gradient, true);
  pending_blocked_ = false;
  stats_.sweep_cells += m;
  const bool need_norms = !variable && row_norm_.empty();
  if (need_norms) row_norm_.resize(std::size_t(m));
  return dense_->EvaluateCapturing(x, variable ? EnergyMode::kVariable : EnergyMode::kFull, with_gradient,
                                   scratch_.data(), need_norms ? row_norm_.data() : nullptr);
}

void BandEnergy::UpdateBlockConstants() {
  if (block_weights_version_ == dense_->weights_version()) return;
  const std::int64_t nb = blocks_->count();
  const double scale = dense_->energy_scale();
  block_energy_plus_.assign(std::size_t(nb), 0);
  block_energy_minus_.assign(std::size_t(nb), 0);
#pragma omp parallel for schedule(dynamic, 64)
  for (std::int64_t b = 0; b < nb; ++b) {
    Fixed plus = 0, minus = 0;
    for (std::int64_t i = blocks_->offsets[std::size_t(b)]; i < blocks_->offsets[std::size_t(b + 1)]; ++i) {
      const double W = dense_->weight(blocks_->actives[std::size_t(i)]);
      bool bad = false;
      plus += loglinear::EnergyFixed(1.0, W, scale, &bad);
      minus += loglinear::EnergyFixed(-1.0, W, scale, &bad);
    }
    block_energy_plus_[std::size_t(b)] = plus;
    block_energy_minus_[std::size_t(b)] = minus;
  }
  block_weights_version_ = dense_->weights_version();
}

double BandEnergy::ScanBlocks(const Eigen::VectorXd& x, const double* coeff, std::vector<signed char>* sign,
                              std::vector<double>* radius) const {
  const std::int64_t nb = blocks_->count();
  const int r = dense_->root_count();
  const double l_sat = kBandSaturation / dense_->alpha();
  const std::vector<Vec4>& roots = dense_->roots();
  const double slice = dense_->slice();
  sign->assign(std::size_t(nb), 0);
  radius->assign(std::size_t(nb), 0.0);
  double norm_max = 0;
#pragma omp parallel for schedule(static) reduction(max : norm_max)
  for (std::int64_t b = 0; b < nb; ++b) {
    const double N = blocks_->norm[std::size_t(b)];
    if (!std::isfinite(N)) continue;
    const double* D = blocks_->log_distance.data() + b * r;
    const float* e = blocks_->reach.data() + b * r;
    const float* q = blocks_->curvature.data() + b * r;
    const double px = blocks_->centre[std::size_t(b * 3)], py = blocks_->centre[std::size_t(b * 3 + 1)],
                 pz = blocks_->centre[std::size_t(b * 3 + 2)], h = blocks_->radius[std::size_t(b)];
    double L = x[0], E1 = 0, Q = 0, gx = 0, gy = 0, gz = 0, mag = std::fabs(x[0]);
    for (int j = 0; j < r; ++j) {
      const double c = coeff[j], ac = std::fabs(c);
      L += c * D[j];
      E1 += ac * e[j];
      Q += ac * q[j];
      mag += ac * (std::fabs(D[j]) + e[j]);
      // grad D_pj = (p - root_j) / |p - root_j|^2, in the slice's three directions.
      const Vec4& t = roots[std::size_t(j)];
      const double ax = px - t[0], ay = py - t[1], az = pz - t[2], aw = slice - t[3];
      const double s = c / (ax * ax + ay * ay + az * az + aw * aw);
      gx += s * ax;
      gy += s * ay;
      gz += s * az;
    }
    const double E = std::min(E1, h * std::sqrt(gx * gx + gy * gy + gz * gz) + Q);
    // The rounding of L_p, of E and of the cells' own L (sums of R+1 terms of at most this
    // magnitude; |grad D_pj| h <= e_j), with room.
    const double slack = std::fabs(L) - E * (1 + 8.0 * (r + 2) * kUnit) - l_sat - 16.0 * (r + 2) * kUnit * mag;
    if (!(slack > 0)) continue;
    (*sign)[std::size_t(b)] = L > 0 ? 1 : -1;
    (*radius)[std::size_t(b)] = slack / N;
    norm_max = std::max(norm_max, N);
  }
  return norm_max;
}

std::vector<double> BandEnergy::LogModulus(const Eigen::VectorXd& x) const {
  if (!blocks_) return dense_->LogModulus(x);
  dense_->CheckX(x);
  const int r = dense_->root_count();
  std::vector<double> coeff(static_cast<std::size_t>(r));
  dense_->Coefficients(x, coeff.data());
  std::vector<signed char> sign;
  std::vector<double> radius;
  ScanBlocks(x, coeff.data(), &sign, &radius);
  std::vector<double> L(std::size_t(dense_->frame().cell_count()), std::numeric_limits<double>::quiet_NaN());
  std::vector<std::int64_t> exact;
  for (std::int64_t b = 0; b < blocks_->count(); ++b) {
    const std::int64_t begin = blocks_->offsets[std::size_t(b)], end = blocks_->offsets[std::size_t(b + 1)];
    if (sign[std::size_t(b)] == 0) {
      blocks_->AppendCells(b, &exact);
      continue;
    }
    const double value = sign[std::size_t(b)] * std::numeric_limits<double>::infinity();
    for (std::int64_t i = begin; i < end; ++i) L[std::size_t(dense_->cell_of(blocks_->actives[std::size_t(i)]))] = value;
  }
  const std::int64_t n = std::int64_t(exact.size());
#pragma omp parallel if (n > kEnergyBlock)
  {
    std::vector<double> buffer(static_cast<std::size_t>(r));
#pragma omp for schedule(static)
    for (std::int64_t i = 0; i < n; ++i) {
      const std::int64_t a = exact[std::size_t(i)];
      L[std::size_t(dense_->cell_of(a))] = x[0] + loglinear::Dot(coeff.data(), dense_->RowOf(a, buffer.data()), r);
    }
  }
  return L;
}

Evaluation<double> BandEnergy::BlockSweep(const Eigen::VectorXd& x, bool with_gradient, bool keep_rows) {
  const std::int64_t m = dense_->active_count();
  const std::int64_t nb = blocks_->count();
  const int r = dense_->root_count();
  std::vector<double> coeff(static_cast<std::size_t>(r));
  dense_->Coefficients(x, coeff.data());
  double norm_max = ScanBlocks(x, coeff.data(), &pending_sign_, &pending_radius_);
  pending_exact_.clear();
  long long saturated = 0;
  for (std::int64_t b = 0; b < nb; ++b) {
    if (pending_sign_[std::size_t(b)] != 0) {
      ++saturated;
      continue;
    }
    blocks_->AppendCells(b, &pending_exact_);
  }
  std::sort(pending_exact_.begin(), pending_exact_.end());
  stats_.saturated_blocks = saturated;
  ++stats_.block_sweeps;
  stats_.sweep_cells += std::int64_t(pending_exact_.size()) + 2 * nb;

  if (keep_rows) {
    // The anchor's rows (its band, list and unproven blocks) and this sweep's: the next sweeps
    // evaluate much the same cells, and a sweep that does not anchor (a line search's far trial)
    // must not push out the rows the evaluations around the anchor read.
    std::vector<std::int64_t> rows = row_order_;
    if (anchor_blocked_) rows.insert(rows.end(), exact_.begin(), exact_.end());
    rows.insert(rows.end(), pending_exact_.begin(), pending_exact_.end());
    dense_->CacheRows(rows, this);
  } else if (dense_->row_owner() == nullptr || dense_->row_owner() == this) {
    // An isolated evaluation (the absolute energy at the coarse levels, every few dozen
    // iterations) evaluates nearly the same cells as the last one: keep them, within an eighth of
    // the budget, unless a band that anchors keeps this evaluator's rows.
    dense_->CacheRows(pending_exact_, this, dense_->memory_budget_bytes() / 8);
  }
  row_norm_.resize(std::size_t(m));
  const std::vector<std::int64_t> offsets = Group(pending_exact_);
  const LogLinearEnergy::BlockSums sums = dense_->SumBlocks(x, coeff.data(), false, with_gradient,
                                                            Blocks(pending_exact_, offsets, -1), scratch_.data(),
                                                            row_norm_.data());
  Fixed energy = sums.energy;
  for (std::int64_t a : pending_exact_) norm_max = std::max(norm_max, row_norm_[std::size_t(a)]);
  // The saturated blocks' cells: -+W each, exactly as the dense evaluator's terms.
  UpdateBlockConstants();
  for (std::int64_t b = 0; b < nb; ++b) {
    const signed char s = pending_sign_[std::size_t(b)];
    if (s > 0) energy += block_energy_plus_[std::size_t(b)];
    else if (s < 0) energy += block_energy_minus_[std::size_t(b)];
  }
  pending_norm_max_ = norm_max;
  pending_blocked_ = true;
  // The proof also needs the cells' rounding at x below 0.9 / alpha (as in Evaluate).
  const double saved_norm_max = norm_max_;
  const bool saved_variable = anchor_variable_;
  norm_max_ = norm_max;
  anchor_variable_ = false;
  const double rounding = RoundingBound(x, coeff.data());
  norm_max_ = saved_norm_max;
  anchor_variable_ = saved_variable;
  if (rounding > 0.9 / dense_->alpha()) {
    pending_blocked_ = false;
    pending_exact_.clear();
    ++stats_.dense_fallbacks;
    stats_.sweep_cells += m;
    return dense_->Evaluate(x, EnergyMode::kFull, with_gradient);
  }
  return dense_->Assemble(x, false, with_gradient, energy, sums.total.data(), sums.nonfinite);
}

void BandEnergy::Adopt(const Eigen::VectorXd& x, bool variable, double energy) {
  const std::int64_t m = dense_->active_count();
  const int r = dense_->root_count();
  anchor_variable_ = variable;
  anchor_blocked_ = !variable && pending_blocked_;
  variable_version_ = dense_->variable_version();
  anchor_energy_ = energy;
  anchor_weights_version_ = dense_->weights_version();
  x0_.assign(x.data(), x.data() + 3);
  coeff0_.resize(static_cast<std::size_t>(r));
  dense_->Coefficients(x, coeff0_.data());
  std::swap(L0_, scratch_);
  L0_.resize(std::size_t(m));
  norm_.resize(std::size_t(m));
  if (anchor_blocked_) {
    std::swap(exact_, pending_exact_);
    std::swap(block_sign_, pending_sign_);
    norm_max_ = pending_norm_max_;
    for (std::int64_t a : exact_) norm_[std::size_t(a)] = row_norm_[std::size_t(a)];
  } else {
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
  }

  // Band, radii and the sorted list of items: cells, or whole saturated blocks of a block anchor
  // (item id -1 - b), each evaluated exactly once d(x) reaches its radius.
  const double l_sat = kBandSaturation / dense_->alpha();
  const double e0 = RoundingBound(x, coeff0_.data());
  rank_.assign(std::size_t(m), kOutside);
  std::vector<std::pair<double, std::int64_t>> items;
  band_count_ = 0;
  auto classify = [&](std::int64_t a) {
    const double s = std::fabs(L0_[a]) - l_sat - e0;
    if (!(s > 0)) {  // also NaN
      rank_[a] = -1;
      ++band_count_;
    } else {
      items.emplace_back(s / norm_[a], a);
    }
  };
  auto item_cells = [&](std::int64_t id) {
    return id >= 0 ? std::int64_t(1) : blocks_->offsets[std::size_t(-id)] - blocks_->offsets[std::size_t(-id - 1)];
  };
  const std::int64_t budget = std::max<std::int64_t>(band_count_, m / 16);
  std::int64_t K;
  if (anchor_blocked_) {
    items.reserve(exact_.size() + block_sign_.size());
    for (std::int64_t a : exact_) classify(a);
    for (std::int64_t bl = 0; bl < blocks_->count(); ++bl)
      if (block_sign_[std::size_t(bl)] != 0) items.emplace_back(pending_radius_[std::size_t(bl)], -1 - bl);
    // The smallest radii, up to `budget` cells.
    std::sort(items.begin(), items.end());
    std::int64_t cells = 0;
    K = 0;
    while (K < std::int64_t(items.size()) && cells + item_cells(items[std::size_t(K)].second) <= budget)
      cells += item_cells(items[std::size_t(K++)].second);
    list_cap_ = K < std::int64_t(items.size()) ? items[std::size_t(K)].first : std::numeric_limits<double>::infinity();
  } else {
    items.reserve(std::size_t(m));
    for (std::int64_t a = 0; a < m; ++a) classify(a);
    const std::int64_t n = std::int64_t(items.size());
    K = std::min<std::int64_t>(n, budget);
    if (K < n) {
      std::nth_element(items.begin(), items.begin() + K, items.end());
      list_cap_ = items[std::size_t(K)].first;
      for (std::int64_t i = K + 1; i < n; ++i) list_cap_ = std::min(list_cap_, items[std::size_t(i)].first);
    } else {
      list_cap_ = std::numeric_limits<double>::infinity();
    }
    std::sort(items.begin(), items.begin() + K);
  }
  list_r_.resize(std::size_t(K));
  list_cell_.resize(std::size_t(K));
  list_cells_prefix_.assign(std::size_t(K) + 1, 0);
  for (std::int64_t i = 0; i < K; ++i) {
    list_r_[i] = items[std::size_t(i)].first;
    const std::int64_t id = list_cell_[i] = items[std::size_t(i)].second;
    list_cells_prefix_[std::size_t(i) + 1] = list_cells_prefix_[std::size_t(i)] + item_cells(id);
    if (id >= 0) {
      rank_[std::size_t(id)] = std::int32_t(i);
    } else {
      for (std::int64_t j = blocks_->offsets[std::size_t(-id - 1)]; j < blocks_->offsets[std::size_t(-id)]; ++j)
        rank_[std::size_t(blocks_->actives[std::size_t(j)])] = std::int32_t(i);
    }
  }

  // The candidates in cell order, grouped by the dense evaluator's blocks; their rows cached.
  candidates_.clear();
  if (anchor_blocked_) {
    for (std::int64_t a : exact_)
      if (rank_[a] != kOutside) candidates_.push_back(a);
    for (std::int64_t id : list_cell_)
      if (id < 0) blocks_->AppendCells(-id - 1, &candidates_);
    std::sort(candidates_.begin(), candidates_.end());
  } else {
    for (std::int64_t a = 0; a < m; ++a)
      if (rank_[a] != kOutside) candidates_.push_back(a);
  }
  block_offsets_ = Group(candidates_);
  if (!variable && dense_->storage() == LogLinearOptions::Storage::kOnTheFly) KeepRows();
  anchor_cost_ = anchor_blocked_ ? std::int64_t(exact_.size()) + 2 * blocks_->count() : m;
  weights_version_ = ~std::uint64_t(0);  // constants follow the new band
  extra_ = 0;
  anchored_ = true;
  stats_.band_cells = band_count_;
}

void BandEnergy::KeepRows() {
  // Most used first: the band's rows, the list's by radius, then those of the blocks the anchor
  // could not prove saturated (every block sweep evaluates them).
  row_order_.clear();
  for (std::int64_t a : candidates_)
    if (rank_[a] < 0) row_order_.push_back(a);
  for (std::int64_t id : list_cell_) {
    if (id >= 0) row_order_.push_back(id);
    else blocks_->AppendCells(-id - 1, &row_order_);
  }
  std::vector<std::int64_t> rows = row_order_;
  rows.insert(rows.end(), exact_.begin(), exact_.end());
  dense_->CacheRows(rows, this);
}

void BandEnergy::UpdateConstants() {
  const std::int64_t m = dense_->active_count();
  const double scale = dense_->energy_scale();
  // A saturated cell's term is the dense evaluator's with tanh = sign(L) exactly.
  auto term = [&](std::int64_t a) {
    bool bad = false;
    return loglinear::EnergyFixed(L0_[a] > 0 ? 1.0 : -1.0, dense_->weight(a), scale, &bad);
  };
  auto item_term = [&](std::int64_t id) -> Fixed {
    if (id >= 0) return term(id);
    const std::size_t bl = std::size_t(-id - 1);
    return block_sign_[bl] > 0 ? block_energy_plus_[bl] : block_energy_minus_[bl];
  };
  const_total_ = 0;
  if (anchor_blocked_) {
    UpdateBlockConstants();
    for (std::int64_t bl = 0; bl < blocks_->count(); ++bl)
      if (block_sign_[std::size_t(bl)] != 0) const_total_ += item_term(-1 - bl);
    for (std::int64_t a : exact_)
      if (rank_[a] >= 0) const_total_ += term(a);
  } else {
    for (std::int64_t a = 0; a < m; ++a)
      if (rank_[a] >= 0) const_total_ += term(a);
  }
  prefix_.assign(list_cell_.size() + 1, 0);
  for (std::size_t i = 0; i < list_cell_.size(); ++i) prefix_[i + 1] = prefix_[i] + item_term(list_cell_[i]);
  weights_version_ = dense_->weights_version();
}

Evaluation<double> BandEnergy::EvaluateOnce(const Eigen::VectorXd& x, bool with_gradient) {
  dense_->CheckX(x);
  ++stats_.evaluations;
  ++stats_.far;  // a sweep that does not anchor
  if (!blocks_) {
    stats_.sweep_cells += dense_->active_count();
    return dense_->Evaluate(x, EnergyMode::kFull, with_gradient);
  }
  const std::int64_t m = dense_->active_count();
  scratch_.resize(std::size_t(m));
  // The pending state is only read by Adopt, which follows a sweep of its own.
  return BlockSweep(x, with_gradient, false);
}

Evaluation<double> BandEnergy::Evaluate(const Eigen::VectorXd& x, EnergyMode mode, bool with_gradient) {
  const auto start = std::chrono::steady_clock::now();
  dense_->CheckX(x);
  const bool variable = mode == EnergyMode::kVariable;
  if (variable && !dense_->variable_ready())
    throw Error("energy: a V-pass evaluation needs BeginVariablePass first");
  const int r = dense_->root_count();
  std::vector<double> coeff(static_cast<std::size_t>(r));
  dense_->Coefficients(x, coeff.data());
  ++stats_.evaluations;
  auto finish = [&](Evaluation<double> ev) {
    ev.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return ev;
  };
  auto sweep = [&]() {
    const long long fallbacks = stats_.dense_fallbacks;
    Evaluation<double> ev = Sweep(x, variable, with_gradient);
    return std::make_pair(ev, stats_.dense_fallbacks == fallbacks);  // adoptable
  };
  if (!anchored_ || variable != anchor_variable_ || (variable && variable_version_ != dense_->variable_version())) {
    auto [ev, adoptable] = sweep();
    if (adoptable) {
      Adopt(x, variable, ev.energy);
      ++stats_.anchors;
    } else {
      anchored_ = false;
    }
    return finish(ev);
  }
  if (RoundingBound(x, coeff.data()) > 0.9 / dense_->alpha()) {
    ++stats_.dense_fallbacks;
    stats_.sweep_cells += dense_->active_count();
    return finish(dense_->Evaluate(x, mode, with_gradient));
  }
  // Cells of the list with r_c <= d(x) may have left saturation: evaluate them.
  const double d = Displacement(x, coeff.data());
  const std::int64_t k = std::upper_bound(list_r_.begin(), list_r_.end(), d) - list_r_.begin();
  const bool beyond = k == std::int64_t(list_r_.size()) && d >= list_cap_;
  const std::int64_t k_cells = list_cells_prefix_[std::size_t(k)];
  if (beyond || extra_ + k_cells > anchor_cost_) {
    auto [ev, adoptable] = sweep();
    const bool adopt =
        adoptable && (!beyond || anchor_weights_version_ != dense_->weights_version() || !(ev.energy > anchor_energy_));
    if (adopt) {
      Adopt(x, variable, ev.energy);
      ++stats_.anchors;
      ++(beyond ? stats_.anchors_reach : stats_.anchors_work);
    } else if (adoptable) {
      ++stats_.far;
    }
    return finish(ev);
  }
  extra_ += k_cells;
  if (weights_version_ != dense_->weights_version()) UpdateConstants();

  const LogLinearEnergy::BlockSums sums = dense_->SumBlocks(
      x, coeff.data(), variable, with_gradient, Blocks(candidates_, block_offsets_, std::int32_t(k)), nullptr, nullptr);
  // The saturated cells' terms: all of them less those of the list items just evaluated.
  const Fixed energy = const_total_ - prefix_[std::size_t(k)] + sums.energy;
  const long long exact = band_count_ + k_cells;
  stats_.exact_cells += exact;
  stats_.max_exact = std::max(stats_.max_exact, exact);
  return finish(dense_->Assemble(x, variable, with_gradient, energy, sums.total.data(), sums.nonfinite));
}

}  // namespace quijibo
