// Intersection over union, the one definition every fidelity figure uses (level fidelity, the start
// check, `quijibo fidelity`, the run's Quality section, `quijibo compare`).
#pragma once

#include <cstdint>

namespace quijibo {

// |A ∩ B| / |A ∪ B| from the two counts. Two empty sets are the same set: 1.
inline double IntersectionOverUnion(std::int64_t intersection, std::int64_t union_count) {
  return union_count > 0 ? double(intersection) / double(union_count) : 1.0;
}

}  // namespace quijibo
