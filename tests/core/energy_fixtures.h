// The evaluators' tests' small problem (dense, cached and band): a sphere target on an n^3 grid and
// a seeded random map whose level set crosses the grid (ln C puts the median L at 0), so many cells
// sit on the steep part of tanh; large exponents make L steep, as after an optimization.
#pragma once

#include <cstdint>

#include "quijibo/energy.h"
#include "quijibo/grid.h"
#include "quijibo/rational_map.h"
#include "quijibo/target.h"

namespace quijibo::testing {

struct EnergyProblem {
  ScalarGrid sdf;
  EnergyGrid grid;
  RationalMap map;
};

// `top` and `bottom` roots in the ball of radius 1.2, exponents in [emin, emax], tau 0.9, beta 1.1;
// `weights` is the level grid's weight field; zero_roots puts a root at the origin first.
inline EnergyProblem MakeEnergyProblem(int n, int top, int bottom, double emin, double emax, std::uint64_t seed,
                                       WeightField weights = WeightField::kLayer, bool zero_roots = false) {
  EnergyProblem p;
  p.sdf = AnalyticTarget("sphere:radius=1", GridFrame::Cube(n, {0.01, -0.02, 0.03}, 3.0));
  p.grid = MakeEnergyGrid(p.sdf, weights);
  p.map = RandomMap({.top = top, .bottom = bottom, .root_radius = 1.2, .exponent_min = emin, .exponent_max = emax,
                     .leading_zero_roots = zero_roots, .seed = seed});
  p.map.tau = 0.9;
  p.map.beta = 1.1;
  p.map.ln_C = -MedianLogModulus(p.map, p.grid);
  return p;
}

}  // namespace quijibo::testing
