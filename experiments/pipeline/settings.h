// The pipeline's part of the settings: the seeds every stage defaults to. The schema mechanism
// itself (Schema, Setting) is util/settings.h, below the libraries.
#pragma once

#include <cstdint>

#include "util/settings.h"

namespace quijibo::pipeline {

// The experiment's top-level seed when none is given, and so the default of every seed of a
// stage (monopole order and sampling, random map, generated versor).
inline constexpr std::uint64_t kDefaultSeed = 1;
inline constexpr long long kMaxSeed = 1ll << 53;

}  // namespace quijibo::pipeline
