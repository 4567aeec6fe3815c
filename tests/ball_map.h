// A map whose one-step set is a ball, for tests that need a set of known shape.
#pragma once
#include <cmath>

#include "quijibo/rational_map.h"

namespace quijibo::testing {

// One top root at the origin, exponent 1: L = ln C + log|q|, so the one-step set {L < 0} is the
// ball |q| < radius.
inline RationalMap BallMap(double radius) {
  RationalMap m;
  m.top_roots = {Vec4{0.0, 0.0, 0.0, 0.0}};
  m.top_exponents = {1.0};
  m.ln_C = -std::log(radius);
  return m;
}

}  // namespace quijibo::testing
