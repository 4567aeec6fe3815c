#include "monopole/monopole_fit.h"

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <random>

#include "util/error.h"

namespace quijibo::monopole {

namespace {

// Rows per block of the blocked inner products: fixed, so sums do not depend on thread count.
constexpr int kRowBlock = 4096;

}  // namespace

IncrementalLeastSquares::IncrementalLeastSquares(Eigen::VectorXd b) : b_(std::move(b)), r_(b_) {
  if (b_.size() == 0) throw Error("least squares: the target vector is empty");
  if (!b_.allFinite()) throw Error("least squares: the target vector is not finite");
}

Eigen::VectorXd IncrementalLeastSquares::ProjectOut(Eigen::VectorXd& a) const {
  const int n = rows();
  const int nb = (n + kRowBlock - 1) / kRowBlock;
  Eigen::MatrixXd partial(k_, nb);
#pragma omp parallel for schedule(static) if (nb > 1 && std::int64_t(n) * k_ > (1 << 18))
  for (int blk = 0; blk < nb; ++blk) {
    const int r0 = blk * kRowBlock, len = std::min(kRowBlock, n - r0);
    partial.col(blk).noalias() = Q_.block(r0, 0, len, k_).transpose() * a.segment(r0, len);
  }
  Eigen::VectorXd c = Eigen::VectorXd::Zero(k_);
  for (int blk = 0; blk < nb; ++blk) c += partial.col(blk);
#pragma omp parallel for schedule(static) if (nb > 1 && std::int64_t(n) * k_ > (1 << 18))
  for (int blk = 0; blk < nb; ++blk) {
    const int r0 = blk * kRowBlock, len = std::min(kRowBlock, n - r0);
    a.segment(r0, len).noalias() -= Q_.block(r0, 0, len, k_) * c;
  }
  return c;
}

bool IncrementalLeastSquares::AddColumn(const Eigen::VectorXd& a, double tolerance) {
  if (a.size() != b_.size())
    throw Error("least squares: column of length " + std::to_string(a.size()) + ", expected " +
                std::to_string(b_.size()));
  const double norm_a = a.norm();
  if (!std::isfinite(norm_a)) throw Error("least squares: column is not finite");
  if (norm_a == 0.0) return false;
  Eigen::VectorXd q = a;
  Eigen::VectorXd coeff = Eigen::VectorXd::Zero(k_);
  if (k_ > 0) {
    coeff = ProjectOut(q);
    coeff += ProjectOut(q);  // second pass: restores orthogonality lost to cancellation
  }
  const double rkk = q.norm();
  if (!(rkk > tolerance * norm_a)) return false;
  q /= rkk;
  if (k_ == Q_.cols()) {  // grow capacity geometrically
    const int cap = std::max(16, 2 * k_);
    Q_.conservativeResize(rows(), cap);
    R_.conservativeResize(cap, cap);
    z_.conservativeResize(cap);
  }
  Q_.col(k_) = q;
  R_.col(k_).head(k_) = coeff;
  R_(k_, k_) = rkk;
  z_(k_) = q.dot(b_);
  r_ -= z_(k_) * q;
  ++k_;
  return true;
}

Eigen::VectorXd IncrementalLeastSquares::Solution() const {
  if (k_ == 0) return Eigen::VectorXd();
  return R_.topLeftCorner(k_, k_).triangularView<Eigen::Upper>().solve(z_.head(k_));
}

std::string GreedyFitOptions::Validate() const {
  if (!(epsilon >= 0.0) || !(epsilon < 1.0))
    return "fit.epsilon (relative residual) must be in [0, 1), found " + std::to_string(epsilon);
  if (batch_size < 1) return "fit.batch_size must be positive, found " + std::to_string(batch_size);
  if (max_monopoles < 1)
    return "fit.max_monopoles must be positive, found " + std::to_string(max_monopoles);
  if (max_monopoles > 100000)
    return "fit.max_monopoles must be at most 100000, found " + std::to_string(max_monopoles);
  return {};
}

const char* ToString(FitStop stop) {
  switch (stop) {
    case FitStop::kConverged: return "converged";
    case FitStop::kCandidatesExhausted: return "candidates exhausted";
    case FitStop::kMaxMonopoles: return "max_monopoles reached";
  }
  return "?";
}

Eigen::VectorXd MonopoleColumn(const std::vector<Vec3>& points, const Vec3& m) {
  Eigen::VectorXd a(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    const double dx = points[i][0] - m[0], dy = points[i][1] - m[1], dz = points[i][2] - m[2];
    a[i] = 1.0 / std::sqrt(dx * dx + dy * dy + dz * dz);
  }
  return a;
}

std::vector<int> SeededPermutation(int n, std::uint64_t seed) {
  std::vector<int> perm(std::max(n, 0));
  for (int i = 0; i < n; ++i) perm[i] = i;
  std::mt19937_64 rng(seed);
  for (int i = n - 1; i > 0; --i) {
    // Unbiased integer in [0, i] (Lemire 2019).
    const std::uint64_t range = std::uint64_t(i) + 1;
    unsigned __int128 m = (unsigned __int128)rng() * range;
    if (std::uint64_t(m) < range) {
      const std::uint64_t threshold = (0 - range) % range;
      while (std::uint64_t(m) < threshold) m = (unsigned __int128)rng() * range;
    }
    std::swap(perm[i], perm[int(m >> 64)]);
  }
  return perm;
}

std::vector<Monopole> GreedyMonopoleFit(const std::vector<Vec3>& points,
                                        const std::vector<double>& targets,
                                        const std::vector<Vec3>& candidates,
                                        const GreedyFitOptions& options, GreedyFitSummary* summary,
                                        const GreedyFitCallback& on_step) {
  if (const std::string why = options.Validate(); !why.empty()) throw Error(why);
  if (points.empty()) throw Error("monopole fit: no collocation points");
  if (targets.size() != points.size())
    throw Error("monopole fit: " + std::to_string(targets.size()) + " target values for " +
                std::to_string(points.size()) + " points");
  const auto t0 = std::chrono::steady_clock::now();
  const int n = int(points.size());
  const int m = int(candidates.size());

  IncrementalLeastSquares ls(Eigen::Map<const Eigen::VectorXd>(targets.data(), n));
  const double norm_b = ls.target_norm();
  GreedyFitSummary s;
  double relative = norm_b > 0.0 ? 1.0 : 0.0;
  std::vector<int> chosen;
  const std::vector<int> perm = SeededPermutation(m, options.seed);
  int next = 0;
  std::vector<double> score;
  while (relative > options.epsilon) {
    if (int(chosen.size()) >= options.max_monopoles) {
      s.stop = FitStop::kMaxMonopoles;
      break;
    }
    if (next >= m) {
      s.stop = FitStop::kCandidatesExhausted;
      break;
    }
    const int batch = std::min(options.batch_size, m - next);
    score.assign(batch, 0.0);
    const Eigen::VectorXd& r = ls.residual();
    // One column per candidate, each summed in row order (deterministic).
#pragma omp parallel for schedule(dynamic, 1)
    for (int c = 0; c < batch; ++c) {
      const Vec3& p = candidates[perm[next + c]];
      double dot = 0.0, nn = 0.0;
      for (int i = 0; i < n; ++i) {
        const double dx = points[i][0] - p[0], dy = points[i][1] - p[1], dz = points[i][2] - p[2];
        const double a = 1.0 / std::sqrt(dx * dx + dy * dy + dz * dz);
        dot += a * r[i];
        nn += a * a;
      }
      score[c] = options.normalize_columns ? std::abs(dot) / std::sqrt(nn) : std::abs(dot);
    }
    int best = 0;  // first maximum: a fixed tie rule
    for (int c = 1; c < batch; ++c)
      if (score[c] > score[best]) best = c;
    const int pick = perm[next + best];
    next += batch;
    s.candidates_examined += batch;
    ++s.steps;
    if (!std::isfinite(score[best]))
      throw Error("monopole fit: candidate " + std::to_string(pick) +
                  " coincides with a collocation point");
    if (ls.AddColumn(MonopoleColumn(points, candidates[pick])))
      chosen.push_back(pick);
    else
      ++s.dependent_rejected;
    relative = ls.residual_norm() / norm_b;
    s.relative_residual.push_back(relative);
    if (on_step) on_step(s.steps, relative);
  }
  const Eigen::VectorXd w = ls.Solution();
  std::vector<Monopole> out(chosen.size());
  for (std::size_t i = 0; i < chosen.size(); ++i) out[i] = {candidates[chosen[i]], w[i]};
  s.monopoles = int(out.size());
  s.final_relative_residual = relative;
  s.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (summary) *summary = std::move(s);
  return out;
}

}  // namespace quijibo::monopole
