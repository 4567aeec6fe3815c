// Compiled with -fno-math-errno -fno-trapping-math -fno-builtin-sin -fno-builtin-cos and the same for
// sinf and cosf (quijibo/CMakeLists.txt): calls may then be vectorized and if-converted, and sin and
// cos are not merged into a scalar sincos (libmvec has no plain vector sincos).
#include "quijibo/julia_batch.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdlib>

#include "quijibo/vector_math.h"
#include "util/error.h"

// glibc's math-vector.h declares libmvec's variants only under -ffast-math (which would also drop
// NaN and signed-zero semantics); these declarations give GCC the same variants without it. Clang
// (the fuzz build) has no such attribute: there the loops call the scalar functions.
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__)
extern "C" {
__attribute__((simd("notinbranch"))) double log(double) noexcept;
__attribute__((simd("notinbranch"))) double exp(double) noexcept;
__attribute__((simd("notinbranch"))) double sin(double) noexcept;
__attribute__((simd("notinbranch"))) double cos(double) noexcept;
__attribute__((simd("notinbranch"))) double atan2(double, double) noexcept;
__attribute__((simd("notinbranch"))) float logf(float) noexcept;
__attribute__((simd("notinbranch"))) float sinf(float) noexcept;
__attribute__((simd("notinbranch"))) float cosf(float) noexcept;
__attribute__((simd("notinbranch"))) float atan2f(float, float) noexcept;
}
#endif

namespace quijibo {

JuliaKernel ParseJuliaKernel(const std::string& name) {
  if (name == "vector") return JuliaKernel::kVector;
  if (name == "fused") return JuliaKernel::kFused;
  if (name == "float") return JuliaKernel::kFloat;
  if (name == "scalar") return JuliaKernel::kScalar;
  throw Error("kernel: expected vector, fused, float or scalar, found \"" + name + "\"");
}

const char* JuliaKernelName(JuliaKernel kernel) {
  switch (kernel) {
    case JuliaKernel::kVector: return "vector";
    case JuliaKernel::kFused: return "fused";
    case JuliaKernel::kFloat: return "float";
    case JuliaKernel::kScalar: break;
  }
  return "scalar";
}

VectorIsa ParseVectorIsa(const std::string& name) {
  for (std::size_t i = 0; i < kVectorIsaNames.size(); ++i)
    if (name == kVectorIsaNames[i]) return VectorIsa(i);
  throw Error("vector instruction set: expected sse2, avx2 or avx512, found \"" + name + "\"");
}

const char* VectorIsaName(VectorIsa isa) { return kVectorIsaNames[std::size_t(isa)].c_str(); }

namespace {

constexpr int C = JuliaBatch::kLanes;

// One chunk: the iterate (q, log|q|, versor of q) in, log|R(q)|, versor of R(q) and R(q) out.
struct Lanes {
  alignas(64) double qw[C], qx[C], qy[C], qz[C], lq[C], vw[C], vx[C], vy[C], vz[C];
  alignas(64) double L[C], uw[C], ux[C], uy[C], uz[C], nw[C], nx[C], ny[C], nz[C];
};

// The factors, one array per component (JuliaBatch's members).
struct Stream {
  const double *w, *x, *y, *z, *e;
  const char* zero;
  std::size_t n;
  double ln_C;
};

// One factor on every lane, as JuliaMap::Apply with LogAndVersor: u <- u u(d)^e with
// d = q - r (kZero: the iterate's versor) and, unless kZero, L <- L + e log|d|. Two loops: one of
// calls, one of selects (GCC vectorizes neither kind inside the other).
// kFused: quijibo's own log, atan2 and sincos (vector_math.h) instead of libmvec's, one loop and
// one range reduction for sin and cos; a lane whose angle is beyond vm::kSinCosMax (or NaN) takes
// libmvec's sin and cos (computed for the chunk only when a lane needs them).
// kFloat: libmvec's float log, atan2, sin and cos (JuliaBatch's constructor states the error).
enum class Functions { kLibmvec, kFused, kFloat };

template <bool kZero, Functions kF>
[[gnu::always_inline]] inline void ApplyFactor(Lanes& s, double rw, double rx, double ry, double rz, double e) {
  alignas(64) double dw[C], dx[C], dy[C], dz[C], vn[C], ln[C], c[C], sn[C];
  if constexpr (kF == Functions::kFloat) {
    // A loop of selects, then one of calls (GCC 12 if-converts neither inside the other).
    alignas(64) float m[C], ys[C], xs[C];
    alignas(64) double k_ln2[C];
#pragma omp simd
    for (int l = 0; l < C; ++l) {
      dw[l] = kZero ? s.vw[l] : s.qw[l] - rw;
      dx[l] = kZero ? s.vx[l] : s.qx[l] - rx;
      dy[l] = kZero ? s.vy[l] : s.qy[l] - ry;
      dz[l] = kZero ? s.vz[l] : s.qz[l] - rz;
      const double v2 = dx[l] * dx[l] + dy[l] * dy[l] + dz[l] * dz[l];
      vn[l] = std::sqrt(v2);
      const double r2 = dw[l] * dw[l] + v2;
      // r2 = m 2^k with m in [1, 2): k ln 2 in double, log m in float below. Tiny r2 (subnormal
      // included) is scaled up first, so that its exponent field is that of a normal number.
      const bool tiny = r2 < 0x1p-900;
      const std::uint64_t bits = std::bit_cast<std::uint64_t>(tiny ? r2 * 0x1p1000 : r2);
      const std::uint64_t biased = bits >> 52;  // k + 1023 (+ 1000 when tiny); r2 >= 0: no sign bit
      const double k = std::bit_cast<double>(biased | 0x4330000000000000ull) - (0x1p52 + 1023.0) - (tiny ? 1000.0 : 0.0);
      m[l] = float(std::bit_cast<double>((bits & 0x000fffffffffffffull) | 0x3ff0000000000000ull));
      // 0, inf and NaN give log's -inf, inf and NaN (their m is 1 or NaN).
      k_ln2[l] = r2 == 0 ? -HUGE_VAL : !(r2 < HUGE_VAL) ? r2 : k * 0.69314718055994530942;
      // atan2 is scale-free: w and |v| scaled by 2^-h, h about k / 2, are within float's range.
      const std::uint64_t t = biased + 1024 - (tiny ? 1000 : 0);  // k + 2047, in [24, 3071]
      const double scale = std::bit_cast<double>((2046 - (t >> 1)) << 52);
      ys[l] = float(vn[l] * scale);
      xs[l] = float(dw[l] * scale);
    }
#pragma omp simd
    for (int l = 0; l < C; ++l) {
      ln[l] = 0.5 * (k_ln2[l] + double(logf(m[l])));
      const float phi = float(e * double(atan2f(ys[l], xs[l])));
      c[l] = double(cosf(phi));
      sn[l] = double(sinf(phi));
    }
  } else if constexpr (kF == Functions::kFused) {
    alignas(64) double phi[C];
    int far = 0;
#pragma omp simd reduction(| : far)
    for (int l = 0; l < C; ++l) {
      dw[l] = kZero ? s.vw[l] : s.qw[l] - rw;
      dx[l] = kZero ? s.vx[l] : s.qx[l] - rx;
      dy[l] = kZero ? s.vy[l] : s.qy[l] - ry;
      dz[l] = kZero ? s.vz[l] : s.qz[l] - rz;
      const double v2 = dx[l] * dx[l] + dy[l] * dy[l] + dz[l] * dz[l];
      vn[l] = std::sqrt(v2);
      ln[l] = 0.5 * vm::VmLog(dw[l] * dw[l] + v2);
      phi[l] = e * vm::VmAtan2(vn[l], dw[l]);
      far |= !(std::fabs(phi[l]) < vm::kSinCosMax);
      vm::VmSinCos(phi[l], sn[l], c[l]);
    }
    if (far) {  // per lane, so that a node's value does not depend on the other lanes
#pragma omp simd
      for (int l = 0; l < C; ++l) {
        const double cl = std::cos(phi[l]), sl = std::sin(phi[l]);
        const bool lane_far = !(std::fabs(phi[l]) < vm::kSinCosMax);
        c[l] = lane_far ? cl : c[l];
        sn[l] = lane_far ? sl : sn[l];
      }
    }
  } else {
#pragma omp simd
    for (int l = 0; l < C; ++l) {
      dw[l] = kZero ? s.vw[l] : s.qw[l] - rw;
      dx[l] = kZero ? s.vx[l] : s.qx[l] - rx;
      dy[l] = kZero ? s.vy[l] : s.qy[l] - ry;
      dz[l] = kZero ? s.vz[l] : s.qz[l] - rz;
      const double v2 = dx[l] * dx[l] + dy[l] * dy[l] + dz[l] * dz[l];
      vn[l] = std::sqrt(v2);
      ln[l] = 0.5 * std::log(dw[l] * dw[l] + v2);
      const double phi = e * std::atan2(vn[l], dw[l]);
      c[l] = std::cos(phi);
      sn[l] = std::sin(phi);
    }
  }
#pragma omp simd
  for (int l = 0; l < C; ++l) {
    // Axis i for reals, as LogAndVersor.
    const bool axis = vn[l] > 0;
    const double k = sn[l] / vn[l];
    const double fw = c[l], fx = axis ? dx[l] * k : sn[l], fy = axis ? dy[l] * k : 0.0, fz = axis ? dz[l] * k : 0.0;
    if (!kZero) s.L[l] += e * ln[l];
    const double w = s.uw[l], x = s.ux[l], y = s.uy[l], z = s.uz[l];
    s.uw[l] = w * fw - x * fx - y * fy - z * fz;
    s.ux[l] = w * fx + x * fw + y * fz - z * fy;
    s.uy[l] = w * fy - x * fz + y * fw + z * fx;
    s.uz[l] = w * fz + x * fy - y * fx + z * fw;
  }
}

// One application of the map on every lane (JuliaMap::Apply), then R(q) = versor e^L.
template <Functions kF>
[[gnu::always_inline]] inline void ApplyBody(const Stream& f, Lanes& s) {
  for (int l = 0; l < C; ++l) s.L[l] = f.ln_C, s.uw[l] = 1, s.ux[l] = 0, s.uy[l] = 0, s.uz[l] = 0;
  double zero_coefficient = 0;
  for (std::size_t j = 0; j < f.n; ++j) {
    if (f.zero[j]) {
      ApplyFactor<true, kF>(s, 0, 0, 0, 0, f.e[j]);
      zero_coefficient += f.e[j];
    } else {
      ApplyFactor<false, kF>(s, f.w[j], f.x[j], f.y[j], f.z[j], f.e[j]);
    }
  }
  if (zero_coefficient != 0) {
#pragma omp simd
    for (int l = 0; l < C; ++l) s.L[l] += zero_coefficient * s.lq[l];
  }
  alignas(64) double m[C];
#pragma omp simd
  for (int l = 0; l < C; ++l) {
    const double inv = 1.0 / std::sqrt(s.uw[l] * s.uw[l] + s.ux[l] * s.ux[l] + s.uy[l] * s.uy[l] + s.uz[l] * s.uz[l]);
    s.uw[l] *= inv, s.ux[l] *= inv, s.uy[l] *= inv, s.uz[l] *= inv;
    m[l] = std::exp(s.L[l]);
  }
#pragma omp simd
  for (int l = 0; l < C; ++l) s.nw[l] = s.uw[l] * m[l], s.nx[l] = s.ux[l] * m[l], s.ny[l] = s.uy[l] * m[l], s.nz[l] = s.uz[l] * m[l];
}

// The same code for the x86-64 baseline (libmvec's _ZGVbN2 / _ZGVbN4 variants), for AVX2 + FMA
// (_ZGVdN4 / _ZGVdN8) and for AVX-512 (_ZGVeN8 / _ZGVeN16), chosen at run time: the baseline never
// executes an instruction an old CPU lacks.
template <Functions kF>
void ApplySse2(const Stream& f, Lanes& s) { ApplyBody<kF>(f, s); }
#if defined(__x86_64__) && defined(__GNUC__)
template <Functions kF>
__attribute__((target("avx2,fma"))) void ApplyAvx2(const Stream& f, Lanes& s) { ApplyBody<kF>(f, s); }
template <Functions kF>
__attribute__((target("avx2,fma,avx512f,avx512dq,avx512vl,avx512bw,prefer-vector-width=512"))) void ApplyAvx512(
    const Stream& f, Lanes& s) {
  ApplyBody<kF>(f, s);
}

VectorIsa CpuVectorIsa() {
  __builtin_cpu_init();
  if (!__builtin_cpu_supports("avx2") || !__builtin_cpu_supports("fma")) return VectorIsa::kSse2;
  if (__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512dq") && __builtin_cpu_supports("avx512vl") &&
      __builtin_cpu_supports("avx512bw"))
    return VectorIsa::kAvx512;
  return VectorIsa::kAvx2;
}
#else
template <Functions kF>
void ApplyAvx2(const Stream& f, Lanes& s) { ApplyBody<kF>(f, s); }
template <Functions kF>
void ApplyAvx512(const Stream& f, Lanes& s) { ApplyBody<kF>(f, s); }
VectorIsa CpuVectorIsa() { return VectorIsa::kSse2; }
#endif

template <Functions kF>
auto ApplyFor(VectorIsa isa) -> void (*)(const Stream&, Lanes&) {
  return isa == VectorIsa::kAvx512 ? ApplyAvx512<kF> : isa == VectorIsa::kAvx2 ? ApplyAvx2<kF> : ApplySse2<kF>;
}

}  // namespace

VectorIsa BestVectorIsa() {
  static const VectorIsa cpu = CpuVectorIsa();
  const char* cap = std::getenv("QUIJIBO_VECTOR_ISA");
  if (!cap || !*cap) return cpu;
  return std::min(cpu, ParseVectorIsa(cap));
}

std::vector<VectorIsa> SupportedVectorIsas() {
  static const VectorIsa cpu = CpuVectorIsa();
  std::vector<VectorIsa> all;
  for (int i = 0; i <= int(cpu); ++i) all.push_back(VectorIsa(i));
  return all;
}

JuliaBatch::JuliaBatch(const RationalMap& map, const JuliaOptions& options, JuliaKernel kernel, VectorIsa max_isa)
    : scalar_(map, options), kernel_(kernel) {
  if (kernel == JuliaKernel::kScalar) throw Error("JuliaBatch: the scalar kernel is JuliaMap, not a vector kernel");
  for (const auto& f : scalar_.Factors()) {
    root_w_.push_back(f.root.w), root_x_.push_back(f.root.x), root_y_.push_back(f.root.y), root_z_.push_back(f.root.z);
    exponent_.push_back(f.exponent);
    zero_.push_back(f.zero);
  }
  ln_C_ = scalar_.ln_C();
  log_escape_ = scalar_.log_escape();
  log_capture_ = scalar_.log_capture();
  iterations_ = options.iterations;
  isa_ = std::min(BestVectorIsa(), max_isa);
}

void JuliaBatch::Iterate(const Quaternion<double>* q0, std::size_t n, JuliaResult<double>* out) const {
  std::vector<Quaternion<double>> q(q0, q0 + n);
  for (std::size_t i = 0; i < n; ++i) {  // as JuliaMap::Iterate
    JuliaResult<double>& r = out[i];
    const double n0 = std::sqrt(q0[i].norm2());
    r = JuliaResult<double>();
    r.log_modulus = std::log(n0);
    r.versor = n0 > 0 ? q0[i] * (1.0 / n0) : Quaternion<double>(1, 0, 0, 0);
  }
  const Stream f{root_w_.data(), root_x_.data(), root_y_.data(), root_z_.data(), exponent_.data(), zero_.data(),
                 exponent_.size(), ln_C_};
  void (*apply)(const Stream&, Lanes&) = kernel_ == JuliaKernel::kFused   ? ApplyFor<Functions::kFused>(isa_)
                                         : kernel_ == JuliaKernel::kFloat ? ApplyFor<Functions::kFloat>(isa_)
                                                                          : ApplyFor<Functions::kLibmvec>(isa_);
  std::vector<std::size_t> active;
  active.reserve(n);
  Lanes s;
  for (int k = 0; k < iterations_; ++k) {
    active.clear();
    for (std::size_t i = 0; i < n; ++i)
      if (out[i].log_modulus < log_escape_ && (k == 0 || !(out[i].log_modulus < log_capture_)))
        active.push_back(i);  // not escaped, not captured (the start itself is not), not NaN
    for (std::size_t b = 0; b < active.size(); b += C) {
      const std::size_t lanes = std::min<std::size_t>(C, active.size() - b);
      for (int l = 0; l < C; ++l) {  // a partial chunk repeats its last node
        const std::size_t i = active[b + std::min<std::size_t>(l, lanes - 1)];
        s.qw[l] = q[i].w, s.qx[l] = q[i].x, s.qy[l] = q[i].y, s.qz[l] = q[i].z;
        s.lq[l] = out[i].log_modulus;
        s.vw[l] = out[i].versor.w, s.vx[l] = out[i].versor.x, s.vy[l] = out[i].versor.y, s.vz[l] = out[i].versor.z;
      }
      apply(f, s);
      for (std::size_t l = 0; l < lanes; ++l) {
        const std::size_t i = active[b + l];
        JuliaResult<double>& r = out[i];
        r.log_modulus = s.L[l];
        r.versor = {s.uw[l], s.ux[l], s.uy[l], s.uz[l]};
        ++r.iterations;
        if (r.log_modulus < log_escape_) q[i] = {s.nw[l], s.nx[l], s.ny[l], s.nz[l]};
      }
    }
  }
  for (std::size_t i = 0; i < n; ++i) out[i].escaped = out[i].log_modulus >= log_escape_;
}

void JuliaBatch::At(const Vec3* points, std::size_t n, JuliaResult<double>* out) const {
  std::vector<Quaternion<double>> q0(n);
  for (std::size_t i = 0; i < n; ++i) q0[i] = scalar_.StartingPoint(points[i]);
  Iterate(q0.data(), n, out);
}

}  // namespace quijibo
