// The Julia set of a rational map as a BatchField for the mesher: f(p) = log|q_m| (julia.h), the
// surface f = iso (default 0), in the precision asked for.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>

#include "mesh/marching_cubes.h"
#include "quijibo/julia.h"
#include "quijibo/julia_batch.h"
#include "quijibo/quaternion_map.h"
#include "quijibo/real.h"

namespace quijibo::mesh {

// BatchField::value_margin of log-modulus fields (this one, the shape modulus, portals): sub-cell
// specks of the set sit next to outside nodes with log|q_m| up to ~0.2 (docs/meshing.md); few
// same-side blocks have a corner within 2, so the margin costs little.
inline constexpr double kLogModulusValueMargin = 2.0;

// What the field saw, counted across threads.
struct JuliaFieldStats {
  std::atomic<std::int64_t> evaluations{0};
  std::atomic<std::int64_t> escaped{0};     // stopped at the escape radius
  std::atomic<std::int64_t> non_finite{0};  // NaN or -inf log-modulus (a sample on a root)
  std::atomic<std::int64_t> applications{0};  // map applications done (the sum of m)
};

// Throws quijibo::Error when the map or the options are invalid. `stats` may be null; it must
// outlive the field. In double precision `kernel` picks a vectorized kernel (JuliaBatch: vector,
// the default, fused or float; its instruction set capped by `max_isa`) or the scalar reference
// (JuliaMap); other precisions are always scalar.
BatchField MakeJuliaField(const RationalMap& map, const JuliaOptions& options, double iso = 0.0,
                          Precision precision = Precision::kDouble, JuliaFieldStats* stats = nullptr,
                          JuliaKernel kernel = kDefaultJuliaKernel, VectorIsa max_isa = VectorIsa::kAvx512);

// Any quaternion map's field log|q_n| (quijibo/quaternion_map.h) as a BatchField on points p:
// q = [s p, 0] with s = `point_scale`; iso 0. `map` is shared by the field.
BatchField MakeQuaternionMapField(std::shared_ptr<const QuaternionMap> map, const IterationOptions& options,
                                  double point_scale = 1.0);

}  // namespace quijibo::mesh
