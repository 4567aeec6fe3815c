// The per-cell arithmetic of the log-linear evaluator, shared by the dense evaluator
// (loglinear_energy.h) and the narrow band (band_energy.h).
//
// Both sum their cells with one loop, LogLinearEnergy::SumBlocks, which calls these out-of-line
// functions; the band's saturated cells' constant terms and LogModulus call them too, so a cell's
// L, tanh, gradient weight and energy term are bit for bit the same wherever they are computed.
// The energy is summed exactly (in a 128-bit fixed-point accumulator, see EnergyFixed), so the sum
// does not depend on the order of the cells; the gradient is summed per kEnergyBlock block in cell
// order. Together these make the band's energy and gradient identical to the dense ones, not
// merely close.
#pragma once

#include <cstdint>

namespace quijibo::loglinear {

using Fixed = __int128;

// sum_j coeff_j row_j.
double Dot(const double* coeff, const double* row, int r);
// G_j += g row_j.
void Axpy(double g, const double* row, double* G, int r);
// L of the V pass: ln C + tau S_T - beta S_B.
double VariableL(double lnC, double tau, double beta, double s_top, double s_bottom);
// th = tanh(alpha L); returns th and sets *g = dpsi/dL (before 1/eta) = -alpha W (1 - th^2).
double Tanh(double alpha, double L, double W, double* g);
// The cell's energy term -th W in units of 1/scale, truncated: exact to scale^-1 and order-free.
// A non-finite term gives 0 and sets *nonfinite.
Fixed EnergyFixed(double th, double W, double scale, bool* nonfinite);
// sums[0..2] += g, g S_T, g S_B (the V pass's gradient sums).
void AccumulateVariable(double g, double s_top, double s_bottom, double* sums);

// A power of two such that sum |W| * scale = 2^100: any partial sum fits in 127 bits and each
// term is kept to 2^-100 of sum |W|.
double EnergyScale(double sum_abs_weight);

}  // namespace quijibo::loglinear
