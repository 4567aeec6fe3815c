// Intersection over union, the one definition every fidelity figure uses (level fidelity, the start
// check, `quijibo fidelity`, the run's Quality section, `quijibo compare`).
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

namespace quijibo {

// |A ∩ B| / |A ∪ B| from the two counts. Two empty sets are the same set: 1.
inline double IntersectionOverUnion(std::int64_t intersection, std::int64_t union_count) {
  return union_count > 0 ? double(intersection) / double(union_count) : 1.0;
}

// The IoU of the insides {a < 0} and {b < 0} of two fields sampled at the same cells (a NaN
// sample is outside). The fields must have the same size.
inline double InsideIntersectionOverUnion(std::span<const double> a, std::span<const double> b) {
  std::int64_t both = 0, either = 0;
  for (std::size_t c = 0; c < a.size(); ++c) {
    const bool in_a = a[c] < 0, in_b = b[c] < 0;
    both += in_a && in_b;
    either += in_a || in_b;
  }
  return IntersectionOverUnion(both, either);
}

}  // namespace quijibo
