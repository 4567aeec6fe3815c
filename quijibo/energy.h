// The QUIJIBO energy (2015 paper Eqns 5-8 and 18) and what its evaluators share.
//
//   psi = (1/eta) sum_c -tanh(alpha L_c) W_c,   L_c = log|R(q_c)|,   eta = sum_c |W_c|
//
// over the samples c of an EnergyGrid. psi is in [-1, 1]; -1 is a perfect fit. With the
// reference code's normalized weights (sum |W| = 1 on the finest grid) psi equals the
// reference's E there; on coarse levels we divide by that level's eta as the paper says
// (§4.5 "Geometric Coarsening"), where the reference does not.
//
// Two evaluators compute psi and its gradient with respect to x = [ln C, tau, beta, T, B]:
//   cached_energy.h     the paper's O(R)-per-cell product caches, templated on the real type
//   loglinear_energy.h  design brief §3.1: L is linear in x given log|q_c - root|, double
//
// Samples that fall exactly on a root ("singular": log|q - root| = -inf) are left out of both
// the energy and the gradient, and counted.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <initializer_list>
#include <string>
#include <vector>

#include "quijibo/rational_map.h"
#include "util/settings.h"
#include "quijibo/target.h"

namespace quijibo {

struct EnergyOptions {
  double alpha = 10.0;  // sharpness of the tanh step (reference code: 10)
  static constexpr ValueRange kAlphaRange{0, 1e6, true};
  std::string Validate() const;
  // Also under this name: optim/, the energy evaluators and the Python module call it so.
};

// Which variables an evaluation differentiates.
enum class EnergyMode {
  kFull,      // all R + 3 variables
  kVariable,  // the V pass: ln C, tau, beta only (gradient has 3 entries)
};

struct CellCounts {
  std::int64_t cells = 0;       // samples on the grid
  std::int64_t singular = 0;    // samples exactly on a root (left out)
  std::int64_t overflowed = 0;  // samples whose map or gradient over/underflowed (left out)
};

template <class Real>
struct Evaluation {
  Real energy = 0;
  Eigen::Matrix<Real, Eigen::Dynamic, 1> gradient;  // empty when not requested
  CellCounts counts;
  double seconds = 0.0;
};

// Cells (by index into the grid) that lie exactly on a root of `map`. Both evaluators skip them.
std::vector<char> SingularCells(const RationalMap& map, const EnergyGrid& grid,
                                std::int64_t* count = nullptr);

// The median over the grid of log|T(q_c) B(q_c)^-1| (L with ln C = 0), by the identity of
// design brief §3.1. Setting ln C = -median centres the map's level set inside the grid; used to
// give random maps a sensible C.
double MedianLogModulus(const RationalMap& map, const EnergyGrid& grid);

// The energy of the better trivial set: min(psi(empty set), psi(full box)) = -|sum W| / sum eta
// over `grids` (one grid, or a grid and its corner twin: psi is then the sum over both, each term
// divided by both etas), 0 when |sum W| is rounding noise (the `layer` and `inverse` fields sum to
// 0). psi as every face reports it (the absolute energy, `quijibo energy`, EnergyOfField) is the
// evaluators' sum minus this constant, so that the empty set (L > 0 everywhere: psi = -sum W / eta)
// and the full box (L < 0: +sum W / eta) both score >= 0 in every weight mode, and psi < 0 means
// better than either trivial set. A pass minimizes the sum itself: a constant has no gradient, so
// the optimization is the same. Why not weights that sum to 0: docs/fidelity.md §12.
double TrivialSetEnergy(std::initializer_list<const EnergyGrid*> grids);

// psi = (1/eta) sum_c -tanh(alpha L_c) W_c - TrivialSetEnergy of any field L on the grid's cells (the 2015 energy of
// another method's log-modulus, for comparisons); non-finite L are left out.
double EnergyOfField(const EnergyGrid& grid, const std::vector<double>& L, double alpha);

// Cells per accumulation block. Partial sums are formed per block and added in block order, so
// results do not depend on the number of threads.
inline constexpr std::int64_t kEnergyBlock = 2048;

}  // namespace quijibo
