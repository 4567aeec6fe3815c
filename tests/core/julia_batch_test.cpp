// The vectorized Julia kernel (quijibo/julia_batch.h) against the scalar reference
// (JuliaMap<double>::Iterate): field values, versors, iteration counts, escape and non-finite
// values under every option, on every instruction set the CPU has (SSE2, AVX2, AVX-512), for the
// vector, fused and float kernels; a node's value is independent of the batch.
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <random>

#include "util/error.h"
#include "quijibo/julia.h"
#include "quijibo/julia_batch.h"
#include "quijibo/rational_map.h"
#include "tests/core/julia_fixtures.h"

namespace quijibo {
namespace {

// Measured largest difference |L_vector - L_scalar| / max(1, |L_scalar|) over these cases: see
// docs/meshing.md (kernel section). libmvec is within 4 ulp per call; differences grow with n as
// the iteration amplifies them.
constexpr double kRelativeTolerance = 1e-11;
// The float kernel (float log, atan2, sin, cos per factor; julia_batch.h): values within this of the
// scalar kernel's (relative as above), measured largest 2.4e-5 at n = 6 on these cases (docs/meshing.md);
// a point whose escape or iteration count differs (its value within this of log_escape, or
// log_capture) is allowed in at most kFloatFlipFraction of the points.
constexpr double kFloatRelativeTolerance = 1e-3;
constexpr double kFloatFlipFraction = 0.002;

RationalMap BatchTestMap(std::uint64_t seed, int top, int bottom, bool zero_roots) {
  return testing::JuliaTestMap(seed, top, bottom, zero_roots);
}

std::vector<Vec3> BatchPoints(int n, std::uint64_t seed, double half = 2.0) {
  std::mt19937_64 rng(seed);
  std::vector<Vec3> p(n);
  for (auto& x : p)
    for (double& c : x) c = -half + 2 * half * double(rng() >> 11) / double(1ull << 53);
  return p;
}

struct BatchCase {
  const char* name;
  int top, bottom;
  bool zero_roots;
  JuliaOptions options;
};

JuliaOptions BatchOptions(int iterations, auto&& change) {
  JuliaOptions o;
  o.iterations = iterations;
  change(o);
  return o;
}

std::vector<BatchCase> BatchCases() {
  auto none = [](JuliaOptions&) {};
  return {
      {"n1", 12, 9, false, BatchOptions(1, none)},
      {"n4", 12, 9, false, BatchOptions(4, none)},
      {"n6", 12, 9, false, BatchOptions(6, none)},
      {"zero_roots_n4", 12, 9, true, BatchOptions(4, none)},
      {"translation_n3", 12, 9, false, BatchOptions(3, [](JuliaOptions& o) { o.root_translation = {0.1, -0.2, 0.05, 0.3}; })},
      {"scale_n3", 12, 9, false, BatchOptions(3, [](JuliaOptions& o) { o.root_scale = 0.7; })},
      {"slice_n4", 12, 9, false, BatchOptions(4, [](JuliaOptions& o) { o.slice = 0.35; })},
      {"placement_n4", 12, 9, false,
       BatchOptions(4, [](JuliaOptions& o) { o.placement = SampleTransform::AxisAngle({1, 2, 3}, 37, {0.1, 0.2, -0.3}); })},
      {"escape_5_n6", 12, 9, false, BatchOptions(6, [](JuliaOptions& o) { o.escape_radius = 5; })},
      {"capture_translation_n4", 12, 9, false, BatchOptions(4, [](JuliaOptions& o) {
         o.root_translation = {0, 0, 0.6, 0};
         o.capture_radius = 0.3;
       })},
      {"many_roots_n4", 300, 200, true, BatchOptions(4, none)},
  };
}

const std::vector<JuliaKernel> kVectorKernels = {JuliaKernel::kVector, JuliaKernel::kFused, JuliaKernel::kFloat};

// Parameters: the case, the instruction set (every one this CPU has), the kernel.
class JuliaBatchMatchesScalar : public ::testing::TestWithParam<std::tuple<int, VectorIsa, JuliaKernel>> {};

TEST_P(JuliaBatchMatchesScalar, ValuesVersorsIterationsAndEscape) {
  const auto [index, isa, kernel] = GetParam();
  const BatchCase c = BatchCases()[std::size_t(index)];
  SCOPED_TRACE(c.name);
  const RationalMap map = BatchTestMap(7 + std::uint64_t(index), c.top, c.bottom, c.zero_roots);
  const JuliaMap<double> scalar(map, c.options);
  const JuliaBatch batch(map, c.options, kernel, isa);
  ASSERT_EQ(batch.vector_isa(), isa);
  const bool single = kernel == JuliaKernel::kFloat;
  const double tolerance = single ? kFloatRelativeTolerance : kRelativeTolerance;
  std::vector<Vec3> p = BatchPoints(c.top > 100 ? 600 : 3000, 11 + std::uint64_t(index));
  p.push_back({0, 0, 0});  // the zero roots' own point
  std::vector<JuliaResult<double>> v(p.size());
  batch.At(p.data(), p.size(), v.data());
  int escaped = 0, finite = 0, flipped = 0;
  double worst = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    const JuliaResult<double> s = scalar.At(p[i]);
    ASSERT_EQ(std::isfinite(v[i].log_modulus), std::isfinite(s.log_modulus)) << i;
    if (v[i].iterations != s.iterations || v[i].escaped != s.escaped) {
      ASSERT_TRUE(single) << i << ": iterations " << v[i].iterations << " vs " << s.iterations;
      ++flipped;  // float: an iterate on the other side of the escape or capture radius
      continue;
    }
    escaped += s.escaped;
    if (!std::isfinite(s.log_modulus)) continue;
    ++finite;
    const double scale = std::max(1.0, std::abs(s.log_modulus));
    worst = std::max(worst, std::abs(v[i].log_modulus - s.log_modulus) / scale);
    ASSERT_NEAR(v[i].log_modulus, s.log_modulus, tolerance * scale) << i;
    if (!s.escaped) {  // escaped versors are those of a number e^2000-times larger: compare the value only
      const double vt = single ? 1e-2 : 1e-6;
      EXPECT_NEAR(v[i].versor.w, s.versor.w, vt) << i;
      EXPECT_NEAR(v[i].versor.x, s.versor.x, vt) << i;
      EXPECT_NEAR(v[i].versor.y, s.versor.y, vt) << i;
      EXPECT_NEAR(v[i].versor.z, s.versor.z, vt) << i;
    }
  }
  RecordProperty("max_relative_difference", std::to_string(worst));
  std::printf("%s %s %s: max |L_vector - L_scalar| / max(1, |L|) = %.3g over %d finite values, %d escaped, %d flipped\n",
              c.name, batch.isa(), JuliaKernelName(kernel), worst, finite, escaped, flipped);
  EXPECT_LE(flipped, kFloatFlipFraction * double(p.size()));
  EXPECT_GT(finite, int(p.size()) / 2);
  if (c.options.iterations > 1) {
    EXPECT_GT(escaped, 0);
  }
}

INSTANTIATE_TEST_SUITE_P(Cases, JuliaBatchMatchesScalar,
                         ::testing::Combine(::testing::Range(0, int(BatchCases().size())),
                                            ::testing::ValuesIn(SupportedVectorIsas()),
                                            ::testing::ValuesIn(kVectorKernels)));

// The instruction set: the CPU's best unless capped (by the constructor or QUIJIBO_VECTOR_ISA).
TEST(JuliaBatch, InstructionSets) {
  const RationalMap map = BatchTestMap(3, 4, 3, false);
  const std::vector<VectorIsa> all = SupportedVectorIsas();
  ASSERT_FALSE(all.empty());
  EXPECT_EQ(all.front(), VectorIsa::kSse2);
  EXPECT_EQ(JuliaBatch(map, JuliaOptions{}).vector_isa(), all.back());
  EXPECT_EQ(JuliaBatch(map, JuliaOptions{}, JuliaKernel::kVector, VectorIsa::kSse2).vector_isa(), VectorIsa::kSse2);
  EXPECT_EQ(ParseVectorIsa("avx512"), VectorIsa::kAvx512);
  EXPECT_STREQ(VectorIsaName(VectorIsa::kAvx2), "avx2");
  EXPECT_THROW(ParseVectorIsa("avx"), Error);
  EXPECT_THROW(JuliaBatch(map, JuliaOptions{}, JuliaKernel::kScalar), Error);
}

// Samples on a root and NaN samples: non-finite exactly where the scalar kernel is, and NaN stays
// NaN (counted by the field, not hidden).
TEST(JuliaBatch, NonFiniteLikeTheScalarKernel) {
  const RationalMap map = BatchTestMap(5, 12, 9, false);
  JuliaOptions o;
  o.iterations = 1;
  const JuliaMap<double> scalar(map, o);
  for (JuliaKernel kernel : kVectorKernels) {
  SCOPED_TRACE(JuliaKernelName(kernel));
  const JuliaBatch batch(map, o, kernel);
  std::vector<Quaternion<double>> q0;
  for (const auto& f : scalar.Factors()) q0.push_back(f.root);  // log|q - r| = -inf
  const double nan = std::numeric_limits<double>::quiet_NaN();
  q0.push_back({nan, 0, 0, 0});
  q0.push_back({0.3, 0.2, 0.1, 0});
  std::vector<JuliaResult<double>> v(q0.size());
  batch.Iterate(q0.data(), q0.size(), v.data());
  int non_finite = 0;
  for (std::size_t i = 0; i < q0.size(); ++i) {
    const JuliaResult<double> s = scalar.Iterate(q0[i]);
    EXPECT_EQ(std::isnan(v[i].log_modulus), std::isnan(s.log_modulus)) << i;
    EXPECT_EQ(std::isinf(v[i].log_modulus), std::isinf(s.log_modulus)) << i;
    if (std::isinf(s.log_modulus)) {
      EXPECT_EQ(v[i].log_modulus, s.log_modulus) << i;
    }
    EXPECT_EQ(v[i].iterations, s.iterations) << i;
    non_finite += !std::isfinite(v[i].log_modulus);
  }
  EXPECT_GE(non_finite, int(scalar.Factors().size()));  // every root, and the NaN sample
  EXPECT_TRUE(std::isnan(v[q0.size() - 2].log_modulus));
  EXPECT_EQ(v[q0.size() - 2].iterations, 0);
  EXPECT_TRUE(std::isfinite(v.back().log_modulus));
  }
}

// A node's value does not depend on the batch it comes in, nor on its place there (partial chunks
// and nodes that leave early included), bit for bit: so meshes cannot depend on tiles or threads.
TEST(JuliaBatch, ValueIndependentOfTheBatch) {
  const RationalMap map = BatchTestMap(9, 12, 9, true);
  JuliaOptions o;
  o.iterations = 4;
  for (VectorIsa isa : SupportedVectorIsas())
  for (JuliaKernel kernel : kVectorKernels) {
  SCOPED_TRACE(std::string(JuliaKernelName(kernel)) + " " + VectorIsaName(isa));
  const JuliaBatch batch(map, o, kernel, isa);
  const std::vector<Vec3> p = BatchPoints(203, 21);
  std::vector<JuliaResult<double>> all(p.size());
  batch.At(p.data(), p.size(), all.data());
  std::vector<std::size_t> order(p.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::shuffle(order.begin(), order.end(), std::mt19937_64(3));
  std::vector<Vec3> shuffled;
  for (std::size_t i : order) shuffled.push_back(p[i]);
  std::vector<JuliaResult<double>> other(p.size());
  batch.At(shuffled.data(), shuffled.size(), other.data());
  for (std::size_t k = 0; k < order.size(); ++k) {
    EXPECT_EQ(std::bit_cast<std::uint64_t>(other[k].log_modulus), std::bit_cast<std::uint64_t>(all[order[k]].log_modulus));
    EXPECT_EQ(other[k].iterations, all[order[k]].iterations);
  }
  for (std::size_t i = 0; i < p.size(); i += 17) {
    JuliaResult<double> one;
    batch.At(&p[i], 1, &one);
    EXPECT_EQ(std::bit_cast<std::uint64_t>(one.log_modulus), std::bit_cast<std::uint64_t>(all[i].log_modulus)) << i;
  }
  }
}

TEST(JuliaBatch, KernelNames) {
  EXPECT_EQ(ParseJuliaKernel("vector"), JuliaKernel::kVector);
  EXPECT_EQ(ParseJuliaKernel("scalar"), JuliaKernel::kScalar);
  EXPECT_EQ(ParseJuliaKernel("fused"), JuliaKernel::kFused);
  EXPECT_EQ(ParseJuliaKernel("float"), JuliaKernel::kFloat);
  EXPECT_STREQ(JuliaKernelName(JuliaKernel::kFloat), "float");
  EXPECT_STREQ(JuliaKernelName(JuliaKernel::kFused), "fused");
  EXPECT_STREQ(JuliaKernelName(JuliaKernel::kVector), "vector");
  EXPECT_THROW(ParseJuliaKernel("simd"), Error);
  EXPECT_THROW(JuliaBatch(BatchTestMap(1, 3, 2, false), BatchOptions(0, [](JuliaOptions&) {})), Error);
}

}  // namespace
}  // namespace quijibo
