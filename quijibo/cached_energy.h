// The paper's evaluator (2015 Appendix A), faithful and templated on the real type, so the
// precision problem the paper met can be reproduced: it forms T(q), B(q) and R(q) as quaternion
// products, which overflow when the exponents grow (double already for tens of roots with
// realistic exponents; 80-bit above ~350 roots in the paper).
//
// Per cell and per polynomial it keeps the forward and reverse product caches
//   f_i = P_1 ... P_i,   r_i = P_i ... P_n,   P_i = (q - t_i)^(tau T_i)     (paper Eqns 9-10)
// so the whole gradient of a cell costs O(R):
//   dL/dT_i = tau <R, e^C f_{i-1} log(q - t_i) P_i r_{i+1} B^-1> / <R, R>
//   dL/dB_i = beta <R, -e^C T r'_{i+1}^-1 log(q - b_i) Q_i^-1 f'_{i-1}^-1> / <R, R>
// the bottom form being Eqn 27's, which never forms B^2 nor divides by beta or B_i.
// dL/dtau and dL/dbeta are the sums of the per-root terms weighted by T_i and B_i.
//
// The caches live per thread (O(R) memory per thread; the reference keeps them per cell and
// needs 49 GB for the bunny at 97^3). A cell whose T, B, R, |R|^2 or gradient terms are not
// finite, or whose |R|^2 underflows to 0, is counted as overflowed and left out of the energy
// and the gradient, never propagated.
#pragma once

#include "quijibo/energy.h"

namespace quijibo {

template <class Real>
class CachedEnergy {
 public:
  using Vector = Eigen::Matrix<Real, Eigen::Dynamic, 1>;

  // Keeps copies of the roots and the sample points; `map`'s exponents are not used (they come
  // with each evaluation's x).
  CachedEnergy(const RationalMap& map, const EnergyGrid& grid, const EnergyOptions& options = {});

  // psi and, if asked, its gradient at x = [ln C, tau, beta, T..., B...] (R + 3 entries, also
  // in kVariable mode, where only the first three entries of the gradient are formed).
  // Throws quijibo::Error if x has the wrong size or a non-finite entry.
  Evaluation<Real> Evaluate(const Vector& x, EnergyMode mode = EnergyMode::kFull,
                            bool with_gradient = true) const;
  // (A template so that clang, which mangles a constrained non-template member like its sibling
  // when Real = double, can compile the explicit instantiations.)
  template <class D = double>
    requires(std::is_same_v<D, double> && !std::is_same_v<Real, double>)
  Evaluation<Real> Evaluate(const Eigen::Matrix<D, Eigen::Dynamic, 1>& x, EnergyMode mode = EnergyMode::kFull,
                            bool with_gradient = true) const {
    return Evaluate(Vector(x.template cast<Real>()), mode, with_gradient);
  }

  // Replaces the weights (one per grid cell) and eta, e.g. for the reweighted pass.
  void SetWeights(const std::vector<double>& grid_weight, double eta);

  int top_count() const { return int(top_.size()); }
  int bottom_count() const { return int(bottom_.size()); }
  std::int64_t cell_count() const { return std::int64_t(weight_.size()); }

 private:
  std::vector<Quaternion<Real>> top_, bottom_;
  GridFrame frame_;
  double slice_ = 0;
  std::vector<double> weight_;
  double eta_ = 1;
  std::vector<char> singular_;
  std::int64_t singular_count_ = 0;
  EnergyOptions options_;
};

extern template class CachedEnergy<float>;
extern template class CachedEnergy<double>;
extern template class CachedEnergy<long double>;
extern template class CachedEnergy<float128>;

}  // namespace quijibo
