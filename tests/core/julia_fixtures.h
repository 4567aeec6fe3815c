// The seeded small map the Julia iteration's tests (scalar and vector kernels) iterate: roots in a
// ball of radius 1.2, exponents in [0.3, 1.2], tau 1.1, beta 0.9, ln C -0.4.
#pragma once

#include <cstdint>

#include "quijibo/rational_map.h"

namespace quijibo::testing {

inline RationalMap JuliaTestMap(std::uint64_t seed, int top = 12, int bottom = 9, bool zero_roots = false) {
  RationalMap m = RandomMap({.top = top, .bottom = bottom, .root_radius = 1.2, .exponent_min = 0.3, .exponent_max = 1.2,
                             .leading_zero_roots = zero_roots, .seed = seed});
  m.tau = 1.1;
  m.beta = 0.9;
  m.ln_C = -0.4;
  return m;
}

}  // namespace quijibo::testing
