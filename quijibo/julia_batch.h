// The vectorized Julia kernel (issue 28): JuliaMap<double>::Iterate for many starting points at
// once, in structure-of-arrays form.
//
// Meshing costs nodes x iterations x roots x one factor (log, atan2, sin, cos, a quaternion
// product); the scalar kernel (JuliaMap::Iterate) does one node at a time. This one runs the same
// log-polar arithmetic, in the same order, on chunks of kLanes nodes, with glibc's vector math
// library (libmvec: _ZGVbN2 SSE variants on any x86-64, _ZGVdN4 AVX2 variants chosen at run time
// when the CPU has AVX2 and FMA; glibc documents at most 4 ulp for these functions). The roots
// stream through as one array per component. Nodes that escaped (or became NaN) leave the chunks
// before the next application, so every lane does useful work.
//
// Semantics are exactly those of JuliaMap<double>::Iterate: root translation, root scale, slice,
// placement (StartingPoint), roots at the origin using the iterate's own log|q| and versor, the
// escape test before each application, NaN stops the iteration and stays NaN. Values differ from
// the scalar kernel's by the math library's rounding only (tests/core/julia_batch_test.cpp measures it).
// A node's value does not depend on its position in the batch or on the batch (chunks are padded
// to full width, so no lane runs a scalar remainder loop), hence neither on tiles nor threads.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "quijibo/julia.h"

namespace quijibo {

// Which kernel evaluates the field (double precision; other precisions are always scalar):
// vector (libmvec's functions), fused (the same arithmetic with quijibo's own branch-free log, atan2
// and sincos, vector_math.h, their error bounds stated there) or scalar (the reference).
enum class JuliaKernel { kVector, kScalar, kFused };
inline const std::vector<std::string> kJuliaKernelNames = {"vector", "fused", "scalar"};
// "vector", "fused" or "scalar"; throws quijibo::Error otherwise.
JuliaKernel ParseJuliaKernel(const std::string& name);
const char* JuliaKernelName(JuliaKernel kernel);

class JuliaBatch {
 public:
  static constexpr int kLanes = 16;  // nodes per chunk (a multiple of every vector width used)

  // Throws quijibo::Error when the map or the options are invalid. `allow_avx2` false keeps the
  // SSE variants on a CPU with AVX2 (tests run both). `fused`: vector_math.h's functions instead of
  // libmvec's (JuliaKernel::kFused).
  JuliaBatch(const RationalMap& map, const JuliaOptions& options, bool allow_avx2 = true, bool fused = false);

  // out[i] = JuliaMap<double>::Iterate(q0[i]) up to the vector math library's rounding.
  void Iterate(const Quaternion<double>* q0, std::size_t n, JuliaResult<double>* out) const;
  // out[i] = JuliaMap<double>::At(points[i]), likewise.
  void At(const Vec3* points, std::size_t n, JuliaResult<double>* out) const;

  const JuliaMap<double>& scalar() const { return scalar_; }
  std::size_t factor_count() const { return exponent_.size(); }
  // The instruction set this kernel runs with: "avx2" (AVX2 and FMA) or "sse2" (libmvec's SSE
  // variants pick SSE4.1 code themselves when the CPU has it).
  const char* isa() const { return avx2_ ? "avx2" : "sse2"; }
  bool fused() const { return fused_; }

 private:
  JuliaMap<double> scalar_;
  // The factors in Apply's order, one array per component (roots at the origin: 0).
  std::vector<double> root_w_, root_x_, root_y_, root_z_, exponent_;
  std::vector<char> zero_;
  double ln_C_ = 0, log_escape_ = 0, log_capture_ = 0;
  int iterations_ = 0;
  bool avx2_ = false;
  bool fused_ = false;
};

}  // namespace quijibo
