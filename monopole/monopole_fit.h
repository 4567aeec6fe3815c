// The greedy monopole fit of the 2015 paper (section 4.4, Eqns 14-17, Alg. 1): approximate the
// potential P on the offset shell by monopoles on the surface,
//     P(x) ~ sum_i w_i / |x - m_i|,
// adding one monopole per step: among the next `batch_size` fresh candidates (a seeded, proper
// permutation of the candidate list), the one whose column a_m(x) = 1 / |x - m| has the largest
// |a_m . r|, r the current residual; then the least-squares weights over all chosen monopoles.
// It stops when ||r|| / ||b|| <= epsilon (relative, as the reference code; Alg. 1 writes ||r||),
// when the candidates run out, or at max_monopoles.
//
// The least squares is updated, not re-solved: each new column is orthogonalized against the
// previous ones (a growing thin QR), so a step costs O(N k) instead of the reference code's SVD of
// the whole N x k system (O(N k^2) per step).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "quijibo/grid.h"

namespace quijibo::monopole {

struct Monopole {
  Vec3 position{0.0, 0.0, 0.0};
  double weight = 0.0;  // > 0: a top root (T_i = w), < 0: a bottom root (B_i = |w|)
};

// min_w ||A w - b|| with the columns of A arriving one at a time. Keeps A = Q R (Q with
// orthonormal columns, R upper triangular), built by classical Gram-Schmidt with one full
// reorthogonalization ("twice is enough", Giraud et al. 2005), which keeps Q orthonormal to
// working precision even for the nearly parallel columns of neighbouring monopoles. The residual
// r = b - A w = b - Q Q^T b is updated in O(N) per column. Inner products over the rows are summed
// in fixed blocks in a fixed order, so results do not depend on the number of threads.
class IncrementalLeastSquares {
 public:
  explicit IncrementalLeastSquares(Eigen::VectorXd b);

  // Appends column a (length rows()). Returns false, and leaves the problem unchanged, when a is
  // numerically in the span of the columns already in: ||a - Q Q^T a|| <= tolerance * ||a||.
  bool AddColumn(const Eigen::VectorXd& a, double tolerance = 1e-10);

  int rows() const { return int(b_.size()); }
  int columns() const { return k_; }
  const Eigen::VectorXd& residual() const { return r_; }  // b - A w
  double residual_norm() const { return r_.norm(); }
  double target_norm() const { return b_.norm(); }
  // The least-squares weights w (back substitution R w = Q^T b).
  Eigen::VectorXd Solution() const;

 private:
  Eigen::VectorXd ProjectOut(Eigen::VectorXd& a) const;  // a -= Q c, returns c = Q^T a

  Eigen::VectorXd b_, r_;
  Eigen::MatrixXd Q_;  // rows() x capacity; the first k_ columns are in use
  Eigen::MatrixXd R_;  // capacity x capacity, upper triangle of the first k_ x k_ in use
  Eigen::VectorXd z_;  // Q^T b, first k_ entries
  int k_ = 0;
};

struct GreedyFitOptions {
  // Stop at relative residual ||r|| / ||b|| <= epsilon. The paper's 4 % counts the residual of its
  // 1 - P fit, which takes hundreds of charges (its bunny: 331 roots); our P fit meets 4 % with 19-27
  // monopoles, too few roots for the optimizer to shape (docs/benchmarks.md §22). 0.25 % gives the
  // bunny 165, 331 roots with their twins (InitialGuessOptions::both_signs).
  double epsilon = 0.0025;
  int batch_size = 100;         // fresh candidates examined per step (paper: 100)
  int max_monopoles = 5000;     // hard cap on the number of monopoles
  std::uint64_t seed = 123456;  // std::mt19937_64 seed of the candidate shuffle
  // Rank candidates by |a . r| / ||a|| (orthogonal matching pursuit) instead of the paper's and
  // reference code's raw |a . r|, which favours candidates near many shell points.
  bool normalize_columns = false;

  // Empty string when valid, else what is wrong.
  std::string Validate() const;
};

enum class FitStop {
  kConverged,            // relative residual <= epsilon
  kCandidatesExhausted,  // every candidate was examined first
  kMaxMonopoles,         // max_monopoles reached first
};
const char* ToString(FitStop stop);

struct GreedyFitSummary {
  int steps = 0;                       // batches examined
  int monopoles = 0;
  int candidates_examined = 0;
  int dependent_rejected = 0;          // best candidates whose column was already in the span
  std::vector<double> relative_residual;  // after each step (entry 0: after step 1)
  double final_relative_residual = 1.0;
  FitStop stop = FitStop::kConverged;
  double seconds = 0.0;
};

// Called after every step with (step, relative residual); may be empty.
using GreedyFitCallback = std::function<void(int step, double relative_residual)>;

// The greedy fit (Alg. 1).
// Inputs:
//   points      N collocation points (the offset shell), away from every candidate
//   targets     N values to fit (P at the points)
//   candidates  M candidate monopole positions (blue noise on the surface)
//   options     see GreedyFitOptions; validated (throws quijibo::Error when invalid)
// Output: the chosen monopoles in the order chosen, with their least-squares weights; optionally
// a summary. A zero target gives no monopoles (relative residual 0).
std::vector<Monopole> GreedyMonopoleFit(const std::vector<Vec3>& points,
                                        const std::vector<double>& targets,
                                        const std::vector<Vec3>& candidates,
                                        const GreedyFitOptions& options = {},
                                        GreedyFitSummary* summary = nullptr,
                                        const GreedyFitCallback& on_step = {});

// The column of Eqn 16: a_m(x_i) = 1 / |x_i - m|.
Eigen::VectorXd MonopoleColumn(const std::vector<Vec3>& points, const Vec3& m);

// A proper Fisher-Yates permutation of 0..n-1 from std::mt19937_64(seed), with unbiased bounded
// integers (Lemire's method), the same on every standard library.
std::vector<int> SeededPermutation(int n, std::uint64_t seed);

}  // namespace quijibo::monopole
