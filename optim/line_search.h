// The Moré–Thuente line search (Moré and Thuente 1994, "Line search algorithms with guaranteed
// sufficient decrease"; the MINPACK-2 dcsrch/dcstep that L-BFGS-B uses), templated on the scalar.
//
// Why not LBFGSpp's: Debian's LBFGSpp 0.1.0 updates its bracketing interval with
// `gt * (fI_lo - step) > 0` where the algorithm says `gt * (I_lo - step) > 0` (a function value
// where a step belongs). Once a trial step lies below the best step, the interval it keeps is on
// the wrong side of the minimizer; it then re-evaluates the same point every other trial until
// its 30 trials are spent and throws. Passes ended "line-search" with 0 iterations that way
// (docs/benchmarks.md, "Passes that ended at once").
//
// Here, as in MINPACK-2: the interval [stx, sty] always holds the best step stx, the next trial
// comes from safeguarded cubic/quadratic interpolation (dcstep's four cases), stage 1 works on
// the modified function f(t) - f(0) - t ftol g(0) until a step with sufficient decrease and
// non-negative slope is seen, and a bracket that does not shrink fast enough is bisected. The
// search stops at a step satisfying the strong Wolfe conditions. When that is impossible
// (rounding, the interval collapsed, the trials spent) it returns the best step that has
// sufficient decrease, and fails only when there is none.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace quijibo::optim {

template <class Scalar>
struct LineSearchOptions {
  Scalar ftol = Scalar(1e-4);   // sufficient decrease (LBFGSpp's and L-BFGS-B's default)
  Scalar gtol = Scalar(0.9);    // curvature (strong Wolfe)
  Scalar xtol = Scalar(0.1);    // relative width below which the bracket counts as collapsed (L-BFGS-B)
  Scalar min_step = Scalar(1e-20);
  int max_evaluations = 30;     // trials after the first (LBFGSpp's max_linesearch)
};

namespace line_search_detail {

template <class Scalar>
Scalar Abs(const Scalar& v) { return v < Scalar(0) ? Scalar(-v) : v; }

template <class Scalar>
Scalar Max3(const Scalar& a, const Scalar& b, const Scalar& c) { return std::max(a, std::max(b, c)); }

// sqrt((theta/s)^2 - (a/s)(b/s)) * s, clamped at 0 against rounding.
template <class Scalar>
Scalar Gamma(const Scalar& theta, const Scalar& a, const Scalar& b) {
  using std::sqrt;
  const Scalar s = Max3(Abs(theta), Abs(a), Abs(b));
  if (s == Scalar(0)) return Scalar(0);
  const Scalar d = (theta / s) * (theta / s) - (a / s) * (b / s);
  return d > Scalar(0) ? Scalar(s * Scalar(sqrt(d))) : Scalar(0);
}

// dcstep: the next trial step from the best step (stx, fx, dx), the other end (sty, fy, dy) and the
// trial just evaluated (stp, fp, dp); updates the interval. d* are slopes along the direction.
template <class Scalar>
void Step(Scalar& stx, Scalar& fx, Scalar& dx, Scalar& sty, Scalar& fy, Scalar& dy, Scalar& stp, const Scalar& fp,
          const Scalar& dp, bool& brackt, const Scalar& stpmin, const Scalar& stpmax) {
  const Scalar sgnd = dx < Scalar(0) ? Scalar(-dp) : dp;  // dp * sign(dx)
  Scalar stpf;
  if (fp > fx) {
    // 1: a higher value: the minimizer is bracketed; the cubic step unless it is far from stx.
    const Scalar theta = Scalar(3) * (fx - fp) / (stp - stx) + dx + dp;
    Scalar gamma = Gamma(theta, dx, dp);
    if (stp < stx) gamma = -gamma;
    const Scalar p = (gamma - dx) + theta, q = ((gamma - dx) + gamma) + dp;
    const Scalar stpc = q != Scalar(0) ? Scalar(stx + p / q * (stp - stx)) : stx;
    const Scalar stpq = stx + dx / ((fx - fp) / (stp - stx) + dx) / Scalar(2) * (stp - stx);
    stpf = Abs(Scalar(stpc - stx)) < Abs(Scalar(stpq - stx)) ? stpc : Scalar(stpc + (stpq - stpc) / Scalar(2));
    brackt = true;
  } else if (sgnd < Scalar(0)) {
    // 2: lower, and the slopes have opposite signs: bracketed; the step farther from stp.
    const Scalar theta = Scalar(3) * (fx - fp) / (stp - stx) + dx + dp;
    Scalar gamma = Gamma(theta, dx, dp);
    if (stp > stx) gamma = -gamma;
    const Scalar p = (gamma - dp) + theta, q = ((gamma - dp) + gamma) + dx;
    const Scalar stpc = q != Scalar(0) ? Scalar(stp + p / q * (stx - stp)) : stp;
    const Scalar stpq = stp + dp / (dp - dx) * (stx - stp);
    stpf = Abs(Scalar(stpc - stp)) > Abs(Scalar(stpq - stp)) ? stpc : stpq;
    brackt = true;
  } else if (Abs(dp) < Abs(dx)) {
    // 3: lower, same slope sign, the slope shrinking: the cubic step if it heads the right way.
    const Scalar theta = Scalar(3) * (fx - fp) / (stp - stx) + dx + dp;
    Scalar gamma = Gamma(theta, dx, dp);
    if (stp > stx) gamma = -gamma;
    const Scalar p = (gamma - dp) + theta, q = (gamma + (dx - dp)) + gamma;
    const Scalar r = q != Scalar(0) ? Scalar(p / q) : Scalar(0);
    Scalar stpc;
    if (r < Scalar(0) && gamma != Scalar(0)) stpc = stp + r * (stx - stp);
    else stpc = stp > stx ? stpmax : stpmin;
    const Scalar stpq = stp + dp / (dp - dx) * (stx - stp);
    if (brackt) {
      stpf = Abs(Scalar(stpc - stp)) < Abs(Scalar(stpq - stp)) ? stpc : stpq;
      const Scalar limit = stp + Scalar(0.66) * (sty - stp);
      stpf = stp > stx ? std::min(limit, stpf) : std::max(limit, stpf);
    } else {
      stpf = Abs(Scalar(stpc - stp)) > Abs(Scalar(stpq - stp)) ? stpc : stpq;
      stpf = std::max(stpmin, std::min(stpmax, stpf));
    }
  } else {
    // 4: lower, same slope sign, the slope not shrinking: the cubic through stp and sty, or the
    // extrapolation limit.
    if (brackt) {
      const Scalar theta = Scalar(3) * (fp - fy) / (sty - stp) + dy + dp;
      Scalar gamma = Gamma(theta, dy, dp);
      if (stp > sty) gamma = -gamma;
      const Scalar p = (gamma - dp) + theta, q = ((gamma - dp) + gamma) + dy;
      stpf = q != Scalar(0) ? Scalar(stp + p / q * (sty - stp)) : Scalar((stp + sty) / Scalar(2));
    } else {
      stpf = stp > stx ? stpmax : stpmin;
    }
  }
  if (fp > fx) {
    sty = stp, fy = fp, dy = dp;
  } else {
    if (sgnd < Scalar(0)) sty = stx, fy = fx, dy = dx;
    stx = stp, fx = fp, dx = dp;
  }
  stp = stpf;
}

}  // namespace line_search_detail

// Searches along drt from xp, where fx and grad hold f and its gradient. On return x, fx and grad
// are at the accepted step `step` (in: the first trial). Throws std::runtime_error when no step
// in (0, step_max] with sufficient decrease was found, std::logic_error when drt does not descend.
template <class Scalar, class Function>
void MoreThuente(Function& f, Scalar& fx, Eigen::Matrix<Scalar, -1, 1>& x, Eigen::Matrix<Scalar, -1, 1>& grad,
                 Scalar& step, const Scalar& step_max, const Eigen::Matrix<Scalar, -1, 1>& drt,
                 const Eigen::Matrix<Scalar, -1, 1>& xp, const LineSearchOptions<Scalar>& o = {}) {
  using line_search_detail::Abs;
  using Vector = Eigen::Matrix<Scalar, -1, 1>;
  if (!(step > Scalar(0)) || step > step_max)
    throw std::invalid_argument("line search: the first step is not in (0, step_max]");
  const Scalar finit = fx, ginit = grad.dot(drt);
  if (!(ginit < Scalar(0)))
    throw std::logic_error("the moving direction does not decrease the objective function value");
  const Scalar gtest = o.ftol * ginit;
  const Scalar stpmin = o.min_step, stpmax = step_max;
  bool brackt = false;
  int stage = 1;
  Scalar width = stpmax - stpmin, width1 = Scalar(2) * width;
  Scalar stx = 0, fxb = finit, gx = ginit, sty = 0, fy = finit, gy = ginit;
  Scalar stmin = 0, stmax = step + Scalar(4) * step;
  // The lowest evaluated point with sufficient decrease, returned when no Wolfe point is found.
  Vector best_x, best_grad;
  Scalar best_f = finit, best_step = 0;
  bool have_best = false;
  auto accept_best = [&](const char* why) {
    if (!have_best) throw std::runtime_error(why);
    x = best_x, grad = best_grad, fx = best_f, step = best_step;
  };
  for (int trial = 0;; ++trial) {
    x.noalias() = xp + step * drt;
    const Scalar f_now = f(x, grad);
    const Scalar g_now = grad.dot(drt);
    fx = f_now;
    const Scalar ftest = finit + step * gtest;
    const bool decrease = f_now <= ftest;
    if (decrease && (!have_best || f_now < best_f)) {
      best_x = x, best_grad = grad, best_f = f_now, best_step = step;
      have_best = true;
    }
    if (decrease && Abs(g_now) <= -o.gtol * ginit) return;          // strong Wolfe
    if (step == stpmax && decrease && g_now <= gtest) return;      // the bound stops a descent
    if (step == stpmin && (f_now > ftest || g_now >= gtest))
      return accept_best("the line search step became smaller than the minimum value allowed");
    if (trial >= o.max_evaluations)
      return accept_best("the line search routine reached the maximum number of iterations");
    if (stage == 1 && decrease && g_now >= Scalar(0)) stage = 2;
    if (stage == 1 && f_now <= fxb && f_now > ftest) {
      // Stage 1 on the modified function psi(t) = f(t) - f(0) - t ftol g(0).
      Scalar fm = f_now - step * gtest, fxm = fxb - stx * gtest, fym = fy - sty * gtest;
      Scalar gm = g_now - gtest, gxm = gx - gtest, gym = gy - gtest;
      line_search_detail::Step(stx, fxm, gxm, sty, fym, gym, step, fm, gm, brackt, stmin, stmax);
      fxb = fxm + stx * gtest, fy = fym + sty * gtest, gx = gxm + gtest, gy = gym + gtest;
    } else {
      line_search_detail::Step(stx, fxb, gx, sty, fy, gy, step, f_now, g_now, brackt, stmin, stmax);
    }
    if (brackt) {
      // Bisect when two trials did not shrink the bracket by a third.
      if (Abs(Scalar(sty - stx)) >= Scalar(0.66) * width1) step = stx + (sty - stx) / Scalar(2);
      width1 = width;
      width = Abs(Scalar(sty - stx));
      stmin = std::min(stx, sty), stmax = std::max(stx, sty);
    } else {
      stmin = step + Scalar(1.1) * (step - stx);
      stmax = step + Scalar(4) * (step - stx);
    }
    step = std::max(stpmin, std::min(stpmax, step));
    // Where MINPACK would evaluate stx once more and stop: the best point is as good as it gets.
    if (brackt && (step <= stmin || step >= stmax))
      return accept_best("the line search cannot progress: rounding errors");
    if (brackt && stmax - stmin <= o.xtol * stmax)
      return accept_best("the line search interval collapsed without sufficient decrease");
  }
}

}  // namespace quijibo::optim
