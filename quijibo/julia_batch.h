// The vectorized Julia kernel (issue 28): JuliaMap<double>::Iterate for many starting points at
// once, in structure-of-arrays form.
//
// Meshing costs nodes x iterations x roots x one factor (log, atan2, sin, cos, a quaternion
// product); the scalar kernel (JuliaMap::Iterate) does one node at a time. This one runs the same
// log-polar arithmetic, in the same order, on chunks of kLanes nodes, with glibc's vector math
// library (libmvec: _ZGVbN2 SSE variants on any x86-64, _ZGVdN4 AVX2 variants when the CPU has AVX2
// and FMA, _ZGVeN8 AVX-512 variants when it has AVX-512 F/DQ/VL/BW, chosen at run time; glibc
// documents at most 4 ulp for these functions). The roots
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
// and sincos, vector_math.h, their error bounds stated there), float (libmvec's float log, atan2,
// sin and cos per factor, everything else in double; its error below) or scalar (the reference).
enum class JuliaKernel { kVector, kScalar, kFused, kFloat };
inline const std::vector<std::string> kJuliaKernelNames = {"vector", "fused", "float", "scalar"};
// The default: fused gave the same meshes as vector, byte for byte, and took 20-22 % less CPU on
// intricate sets with AVX-512 (the same time with AVX2; docs/benchmarks.md §27).
inline constexpr JuliaKernel kDefaultJuliaKernel = JuliaKernel::kFused;
// "vector", "fused", "float" or "scalar"; throws quijibo::Error otherwise.
JuliaKernel ParseJuliaKernel(const std::string& name);
const char* JuliaKernelName(JuliaKernel kernel);

// The instruction sets the vector kernels are compiled for, chosen at run time: the x86-64 baseline
// (libmvec's SSE variants, which pick SSE4.1 code themselves when the CPU has it), AVX2 + FMA,
// AVX-512 (F, DQ, VL, BW; 512-bit vectors).
enum class VectorIsa { kSse2, kAvx2, kAvx512 };
inline const std::vector<std::string> kVectorIsaNames = {"sse2", "avx2", "avx512"};
VectorIsa ParseVectorIsa(const std::string& name);  // throws quijibo::Error on an unknown name
const char* VectorIsaName(VectorIsa isa);
// The best instruction set this CPU supports, capped by the environment variable QUIJIBO_VECTOR_ISA
// (sse2, avx2 or avx512) when it is set: A/B measurements (bench mesh's `KERNEL:ISA`) and tests.
VectorIsa BestVectorIsa();
// The instruction sets this CPU supports (kSse2 first): the tests run every one.
std::vector<VectorIsa> SupportedVectorIsas();

class JuliaBatch {
 public:
  static constexpr int kLanes = 16;  // nodes per chunk (a multiple of every vector width used)

  // Throws quijibo::Error when the map, the options or the kernel (kScalar) are invalid. The
  // instruction set is BestVectorIsa() capped by `max_isa` (tests run each).
  //
  // kFloat: each factor's log|d|, atan2(|v|, w), sin and cos in float (libmvec's float variants: 16
  // lanes in one AVX-512 vector), the differences d = q - r, the sums of e log|d|, the versor
  // products and exp in double. log|d|^2 is split into its binary exponent (exact, in double) and
  // the log of its mantissa in [1, 2) in float, and atan2's arguments are scaled by a power of two,
  // so no value overflows or underflows float. Error per factor: log|d| within ~2^-23 absolute, the
  // angle e atan2 within ~|e| 2^-22 + |e atan2| 2^-24 (float rounding of the angle), sin and cos
  // within a few float ulp of the rounded angle; after n applications the differences are amplified
  // as in double. Measured in tests/core/julia_batch_test.cpp and on meshes (docs/meshing.md).
  JuliaBatch(const RationalMap& map, const JuliaOptions& options, JuliaKernel kernel = kDefaultJuliaKernel,
             VectorIsa max_isa = VectorIsa::kAvx512);

  // out[i] = JuliaMap<double>::Iterate(q0[i]) up to the vector math library's rounding.
  void Iterate(const Quaternion<double>* q0, std::size_t n, JuliaResult<double>* out) const;
  // out[i] = JuliaMap<double>::At(points[i]), likewise.
  void At(const Vec3* points, std::size_t n, JuliaResult<double>* out) const;

  const JuliaMap<double>& scalar() const { return scalar_; }
  std::size_t factor_count() const { return exponent_.size(); }
  // The instruction set this kernel runs with ("sse2", "avx2" or "avx512").
  const char* isa() const { return VectorIsaName(isa_); }
  VectorIsa vector_isa() const { return isa_; }
  JuliaKernel kernel() const { return kernel_; }

 private:
  JuliaMap<double> scalar_;
  // The factors in Apply's order, one array per component (roots at the origin: 0).
  std::vector<double> root_w_, root_x_, root_y_, root_z_, exponent_;
  std::vector<char> zero_;
  double ln_C_ = 0, log_escape_ = 0, log_capture_ = 0;
  int iterations_ = 0;
  VectorIsa isa_ = VectorIsa::kSse2;
  JuliaKernel kernel_ = kDefaultJuliaKernel;
};

}  // namespace quijibo
