#include "mesh/julia_field.h"

namespace quijibo {

BatchField MakeJuliaField(const RationalMap& map, const JuliaOptions& options, double iso, Precision precision,
                          JuliaFieldStats* stats) {
  BatchField field;
  field.iso = iso;
  field.value_margin = kLogModulusValueMargin;
  DispatchPrecision(precision, [&]<class Real>() {
    auto jm = std::make_shared<const JuliaMap<Real>>(map, options);
    field.evaluate = [jm, stats](const Vec3* points, std::size_t n, double* values) {
      std::int64_t escaped = 0, bad = 0;
      for (std::size_t i = 0; i < n; ++i) {
        const JuliaResult<Real> r = jm->At(points[i]);
        values[i] = ToDouble(r.log_modulus);
        escaped += r.escaped;
        bad += !std::isfinite(values[i]);
      }
      if (stats) {
        stats->evaluations += std::int64_t(n);
        stats->escaped += escaped;
        stats->non_finite += bad;
      }
    };
    return 0;
  });
  return field;
}

}  // namespace quijibo
