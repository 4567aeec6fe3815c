// Compiled with -fno-math-errno -fno-trapping-math -fno-builtin-sin -fno-builtin-cos
// (quijibo/CMakeLists.txt): calls may then be vectorized and if-converted, and sin and cos are not
// merged into a scalar sincos (libmvec has no plain vector sincos).
#include "quijibo/julia_batch.h"

#include <algorithm>
#include <cmath>

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
}
#endif

namespace quijibo {

JuliaKernel ParseJuliaKernel(const std::string& name) {
  if (name == "vector") return JuliaKernel::kVector;
  if (name == "fused") return JuliaKernel::kFused;
  if (name == "scalar") return JuliaKernel::kScalar;
  throw Error("kernel: expected vector, fused or scalar, found \"" + name + "\"");
}

const char* JuliaKernelName(JuliaKernel kernel) {
  return kernel == JuliaKernel::kVector ? "vector" : kernel == JuliaKernel::kFused ? "fused" : "scalar";
}

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
template <bool kZero, bool kFused>
[[gnu::always_inline]] inline void ApplyFactor(Lanes& s, double rw, double rx, double ry, double rz, double e) {
  alignas(64) double dw[C], dx[C], dy[C], dz[C], vn[C], ln[C], c[C], sn[C];
  if constexpr (kFused) {
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
template <bool kFused>
[[gnu::always_inline]] inline void ApplyBody(const Stream& f, Lanes& s) {
  for (int l = 0; l < C; ++l) s.L[l] = f.ln_C, s.uw[l] = 1, s.ux[l] = 0, s.uy[l] = 0, s.uz[l] = 0;
  double zero_coefficient = 0;
  for (std::size_t j = 0; j < f.n; ++j) {
    if (f.zero[j]) {
      ApplyFactor<true, kFused>(s, 0, 0, 0, 0, f.e[j]);
      zero_coefficient += f.e[j];
    } else {
      ApplyFactor<false, kFused>(s, f.w[j], f.x[j], f.y[j], f.z[j], f.e[j]);
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

// The same code for the x86-64 baseline (libmvec's _ZGVbN2 variants) and for AVX2 + FMA
// (_ZGVdN4), chosen at run time: the baseline never executes an instruction an old CPU lacks.
template <bool kFused>
void ApplySse2(const Stream& f, Lanes& s) { ApplyBody<kFused>(f, s); }
#if defined(__x86_64__)
template <bool kFused>
__attribute__((target("avx2,fma"))) void ApplyAvx2(const Stream& f, Lanes& s) { ApplyBody<kFused>(f, s); }

bool CpuHasAvx2() {
  __builtin_cpu_init();
  return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
}
#else
template <bool kFused>
void ApplyAvx2(const Stream& f, Lanes& s) { ApplyBody<kFused>(f, s); }
bool CpuHasAvx2() { return false; }
#endif

}  // namespace

JuliaBatch::JuliaBatch(const RationalMap& map, const JuliaOptions& options, bool allow_avx2, bool fused)
    : scalar_(map, options), fused_(fused) {
  for (const auto& f : scalar_.Factors()) {
    root_w_.push_back(f.root.w), root_x_.push_back(f.root.x), root_y_.push_back(f.root.y), root_z_.push_back(f.root.z);
    exponent_.push_back(f.exponent);
    zero_.push_back(f.zero);
  }
  ln_C_ = scalar_.ln_C();
  log_escape_ = scalar_.log_escape();
  log_capture_ = scalar_.log_capture();
  iterations_ = options.iterations;
  static const bool has_avx2 = CpuHasAvx2();
  avx2_ = allow_avx2 && has_avx2;
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
  void (*apply)(const Stream&, Lanes&) = fused_ ? (avx2_ ? ApplyAvx2<true> : ApplySse2<true>)
                                                : (avx2_ ? ApplyAvx2<false> : ApplySse2<false>);
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
