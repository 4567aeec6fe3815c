// Fixtures shared by the shape modulus tests (modulus_test.cpp, modulus_features_test.cpp).
#pragma once

#include <cstdint>

#include "methods/mask.h"
#include "methods/modulus.h"

namespace quijibo::testing {

// The versor of the generator's default polynomial drawn with `seed`.
inline Versor PolynomialVersor(std::uint64_t seed) {
  VersorGeneratorOptions o;
  o.seed = seed;
  Versor v;
  v.polynomial = GenerateVersorPolynomial(o);
  return v;
}

// The varying parameter of the tests (2023 Figs. 7, 13): 300 for x > 0 and 10 for x < 0 (the
// half-space x < 0 as the region), blended by a cubic ramp of width 0.2 across x = 0.
inline ParameterField HalfspaceStep() {
  ParameterField field(300.0);
  ParameterField::Region r;
  r.mask.type = Mask::Type::kHalfspace;
  r.mask.normal = {1, 0, 0};
  r.mask.offset = 0.0;
  r.value = 10.0;
  r.feather = 0.2;
  field.regions.push_back(r);
  return field;
}

}  // namespace quijibo::testing
