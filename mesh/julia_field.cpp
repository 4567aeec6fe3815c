#include "mesh/julia_field.h"

#include <vector>

namespace quijibo::mesh {

namespace {

// Writes the field values of a batch and adds its counts to `stats` (may be null): the one
// bookkeeping of both kernels.
template <class Real>
void RecordBatch(const JuliaResult<Real>* r, std::size_t n, double* values, JuliaFieldStats* stats) {
  std::int64_t escaped = 0, bad = 0, applications = 0;
  for (std::size_t i = 0; i < n; ++i) {
    values[i] = ToDouble(r[i].log_modulus);
    escaped += r[i].escaped;
    applications += r[i].iterations;
    bad += !std::isfinite(values[i]);
  }
  if (!stats) return;
  stats->evaluations += std::int64_t(n);
  stats->escaped += escaped;
  stats->non_finite += bad;
  stats->applications += applications;
}

}  // namespace

BatchField MakeJuliaField(const RationalMap& map, const JuliaOptions& options, double iso, Precision precision,
                          JuliaFieldStats* stats, JuliaKernel kernel, VectorIsa max_isa) {
  BatchField field;
  field.iso = iso;
  field.value_margin = kLogModulusValueMargin;
  field.log_modulus = true;
  if (precision == Precision::kDouble && kernel != JuliaKernel::kScalar) {
    auto jb = std::make_shared<const JuliaBatch>(map, options, kernel, max_isa);
    field.evaluate = [jb, stats](const Vec3* points, std::size_t n, double* values) {
      std::vector<JuliaResult<double>> r(n);
      jb->At(points, n, r.data());
      RecordBatch(r.data(), n, values, stats);
    };
    return field;
  }
  DispatchPrecision(precision, [&]<class Real>() {
    auto jm = std::make_shared<const JuliaMap<Real>>(map, options);
    field.evaluate = [jm, stats](const Vec3* points, std::size_t n, double* values) {
      std::vector<JuliaResult<Real>> r(n);
      for (std::size_t i = 0; i < n; ++i) r[i] = jm->At(points[i]);
      RecordBatch(r.data(), n, values, stats);
    };
    return 0;
  });
  return field;
}

BatchField MakeQuaternionMapField(std::shared_ptr<const QuaternionMap> map, const IterationOptions& o,
                                  double point_scale) {
  BatchField f;
  f.iso = 0.0;
  f.value_margin = kLogModulusValueMargin;
  f.log_modulus = true;
  f.evaluate = [map, o, point_scale](const Vec3* p, std::size_t n, double* out) {
    for (std::size_t i = 0; i < n; ++i)
      out[i] = IterateField(*map, {point_scale * p[i][0], point_scale * p[i][1], point_scale * p[i][2], 0.0}, o);
  };
  return f;
}

}  // namespace quijibo::mesh
