#include "quijibo/cached_energy.h"

#include <omp.h>

#include <chrono>

#include "util/error.h"

namespace quijibo {

namespace {

template <class Real>
bool Finite(const Quaternion<Real>& q) {
  return IsFinite(q.w) && IsFinite(q.x) && IsFinite(q.y) && IsFinite(q.z);
}

// Per-thread workspace: the product caches of one cell, O(R).
template <class Real>
struct Caches {
  using Q = Quaternion<Real>;
  std::vector<Q> log_t, p, fwd, rev;   // top: log(q - t_i), P_i, prefix, suffix
  std::vector<Q> log_b, qb, fwdb, revb;  // bottom: log(q - b_i), Q_i, prefix, suffix
  std::vector<Real> grad;
  Caches(int nt, int nb, int ng)
      : log_t(nt), p(nt), fwd(nt), rev(nt), log_b(nb), qb(nb), fwdb(nb), revb(nb), grad(ng) {}
};

// Builds the factors, prefix and suffix products of one polynomial; returns the product.
template <class Real>
Quaternion<Real> Factor(const Quaternion<Real>& q, const std::vector<Quaternion<Real>>& roots,
                        const Real* exponents, const Real& bulk, std::vector<Quaternion<Real>>& lg,
                        std::vector<Quaternion<Real>>& factor, std::vector<Quaternion<Real>>& fwd,
                        std::vector<Quaternion<Real>>& rev) {
  using Q = Quaternion<Real>;
  const Q one(Real(1), Real(0), Real(0), Real(0));
  const int n = int(roots.size());
  for (int i = 0; i < n; ++i) {
    LogAndPower(q - roots[i], bulk * exponents[i], lg[i], factor[i]);
    fwd[i] = i == 0 ? factor[i] : fwd[i - 1] * factor[i];
  }
  for (int i = n - 1; i >= 0; --i) rev[i] = i == n - 1 ? factor[i] : factor[i] * rev[i + 1];
  return n == 0 ? one : fwd[n - 1];
}

}  // namespace

template <class Real>
CachedEnergy<Real>::CachedEnergy(const RationalMap& map, const EnergyGrid& grid,
                                 const EnergyOptions& options)
    : frame_(grid.frame), slice_(grid.slice), weight_(grid.weight), eta_(grid.eta), options_(options) {
  if (auto why = options.Validate(); !why.empty()) throw Error("energy options: " + why);
  if (auto why = map.Validate(); !why.empty()) throw Error("map: " + why);
  if (std::int64_t(weight_.size()) != frame_.cell_count())
    throw Error("energy grid: weight count does not match the grid");
  for (int i = 0; i < map.top_count(); ++i) top_.push_back(map.top_root<Real>(i));
  for (int i = 0; i < map.bottom_count(); ++i) bottom_.push_back(map.bottom_root<Real>(i));
  singular_ = SingularCells(map, grid, &singular_count_);
}

template <class Real>
void CachedEnergy<Real>::SetWeights(const std::vector<double>& grid_weight, double eta) {
  if (grid_weight.size() != weight_.size()) throw Error("weights do not match the energy grid");
  if (!(eta > 0) || !std::isfinite(eta)) throw Error("eta must be positive and finite");
  weight_ = grid_weight;
  eta_ = eta;
}

template <class Real>
Evaluation<Real> CachedEnergy<Real>::Evaluate(const Vector& x, EnergyMode mode,
                                              bool with_gradient) const {
  using std::exp;
  using std::log;
  using std::tanh;
  using Q = Quaternion<Real>;
  const auto start = std::chrono::steady_clock::now();
  const int nt = top_count(), nb = bottom_count();
  if (x.size() != 3 + nt + nb)
    throw Error("energy: variable vector has " + std::to_string(x.size()) + " entries, expected " +
                std::to_string(3 + nt + nb));
  for (Eigen::Index i = 0; i < x.size(); ++i)
    if (!IsFinite(x[i])) throw Error("energy: variable " + std::to_string(i) + " is not finite");

  const Real eC = exp(x[0]), tau = x[1], beta = x[2], alpha = Real(options_.alpha);
  const Real* t_exp = x.data() + 3;
  const Real* b_exp = x.data() + 3 + nt;
  const int ng = with_gradient ? (mode == EnergyMode::kFull ? 3 + nt + nb : 3) : 0;
  const std::int64_t cells = cell_count();
  const std::int64_t nblocks = (cells + kEnergyBlock - 1) / kEnergyBlock;
  std::vector<Real> block_energy(std::size_t(nblocks), Real(0));
  std::vector<Real> block_grad(std::size_t(nblocks * ng), Real(0));
  std::vector<std::int64_t> block_overflow(std::size_t(nblocks), 0);
  const Q one(Real(1), Real(0), Real(0), Real(0));

#pragma omp parallel if (nblocks > 1)
  {
    Caches<Real> w(nt, nb, ng);
#pragma omp for schedule(dynamic, 1)
    for (std::int64_t blk = 0; blk < nblocks; ++blk) {
      Real energy(0);
      Real* g_block = block_grad.data() + blk * ng;
      std::int64_t overflow = 0;
      const std::int64_t end = std::min(cells, (blk + 1) * kEnergyBlock);
      for (std::int64_t c = blk * kEnergyBlock; c < end; ++c) {
        if (singular_[c]) continue;
        const Vec3 p = frame_.cell_center(c);
        const Q q{Real(p[0]), Real(p[1]), Real(p[2]), Real(slice_)};
        const Q T = Factor(q, top_, t_exp, tau, w.log_t, w.p, w.fwd, w.rev);
        const Q B = Factor(q, bottom_, b_exp, beta, w.log_b, w.qb, w.fwdb, w.revb);
        const Q Binv = B.inverse();
        const Q R = (T * Binv) * eC;
        const Real RR = R.norm2();
        if (!Finite(T) || !Finite(Binv) || !IsFinite(RR) || !(RR > Real(0))) {
          ++overflow;
          continue;
        }
        const Real L = Real(0.5) * log(RR);
        const Real th = tanh(alpha * L);
        const Real W = Real(weight_[c]);
        if (ng == 0) {
          energy += -th * W;
          continue;
        }
        // d(-tanh(alpha L) W)/dL; 1/eta is applied once at the end.
        const Real gL = -alpha * W * (Real(1) - th * th);
        std::fill(w.grad.begin(), w.grad.end(), Real(0));
        w.grad[0] = gL;
        if (gL != Real(0)) {
          const Real inv_RR = Real(1) / RR;
          Real d_tau(0), d_beta(0);
          for (int i = 0; i < nt; ++i) {
            const Q left = i > 0 ? w.fwd[i - 1] : one;
            const Q right = i + 1 < nt ? w.rev[i + 1] : one;
            const Q dR = (((left * (w.log_t[i] * w.p[i])) * right) * Binv) * eC;
            const Real d = R.dot(dR) * inv_RR;  // dL/dT_i divided by tau
            d_tau += t_exp[i] * d;
            if (ng > 3) w.grad[3 + i] = gL * tau * d;
          }
          const Q eCT = T * eC;
          for (int i = 0; i < nb; ++i) {
            const Q right_inv = i + 1 < nb ? w.revb[i + 1].inverse() : one;
            const Q left_inv = i > 0 ? w.fwdb[i - 1].inverse() : one;
            const Q dR = -((((eCT * right_inv) * w.log_b[i]) * w.qb[i].inverse()) * left_inv);
            const Real d = R.dot(dR) * inv_RR;  // dL/dB_i divided by beta
            d_beta += b_exp[i] * d;
            if (ng > 3) w.grad[3 + nt + i] = gL * beta * d;
          }
          w.grad[1] = gL * d_tau;
          w.grad[2] = gL * d_beta;
        }
        bool finite = IsFinite(th);
        for (int k = 0; k < ng && finite; ++k) finite = IsFinite(w.grad[k]);
        if (!finite) {
          ++overflow;
          continue;
        }
        energy += -th * W;
        for (int k = 0; k < ng; ++k) g_block[k] += w.grad[k];
      }
      block_energy[blk] = energy;
      block_overflow[blk] = overflow;
    }
  }

  Evaluation<Real> out;
  const Real inv_eta = Real(1) / Real(eta_);
  Real energy(0);
  for (std::int64_t b = 0; b < nblocks; ++b) {
    energy += block_energy[b];
    out.counts.overflowed += block_overflow[b];
  }
  out.energy = energy * inv_eta;
  if (ng > 0) {
    out.gradient = Vector::Zero(ng);
    for (std::int64_t b = 0; b < nblocks; ++b)
      for (int k = 0; k < ng; ++k) out.gradient[k] += block_grad[b * ng + k];
    out.gradient *= inv_eta;
  }
  out.counts.cells = cells;
  out.counts.singular = singular_count_;
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

template class CachedEnergy<float>;
template class CachedEnergy<double>;
template class CachedEnergy<long double>;
template class CachedEnergy<float128>;

}  // namespace quijibo
