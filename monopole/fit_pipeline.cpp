#include "monopole/fit_pipeline.h"

#include <algorithm>
#include <chrono>

#include "util/error.h"

namespace quijibo::monopole {

std::string MonopoleOptions::Validate() const {
  for (const std::string& why :
       {bem.Validate(), shell.Validate(), sampling.Validate(), fit.Validate()})
    if (!why.empty()) return why;
  return {};
}

int MonopoleResult::positive_count() const {
  return int(std::count_if(monopoles.begin(), monopoles.end(),
                           [](const Monopole& m) { return m.weight > 0.0; }));
}

int MonopoleResult::negative_count() const {
  return int(monopoles.size()) - positive_count();
}

MonopoleResult FitMonopoles(const std::vector<Vec3>& vertices,
                            const std::vector<std::array<int, 3>>& triangles,
                            const ScalarGrid& sdf, const MonopoleOptions& options,
                            const MonopoleProgressFn& progress) {
  if (const std::string why = options.Validate(); !why.empty()) throw Error(why);
  using Clock = std::chrono::steady_clock;
  const auto start = Clock::now();
  auto since = [](Clock::time_point t) {
    return std::chrono::duration<double>(Clock::now() - t).count();
  };
  auto report = [&](const std::string& stage, int step = 0, double rel = 0.0) {
    if (progress) progress({stage, step, rel, since(start)});
  };
  MonopoleResult result;

  auto t = Clock::now();
  result.potential = std::make_shared<const ExteriorPotential>(
      SolveExteriorPotential(vertices, triangles, options.bem, &result.bem));
  const ExteriorPotential& potential = *result.potential;
  result.seconds.bem = since(t);
  report("bem");

  t = Clock::now();
  const OffsetShell shell = ComputeOffsetShell(sdf, options.shell);
  result.shell_points = int(shell.points.size());
  result.seconds.shell = since(t);
  report("shell");

  // P directly at the shell points: no closest-point extension needed (see shell.h).
  t = Clock::now();
  std::vector<double> targets = potential.Evaluate(shell.points);
  if (options.target == MonopoleTarget::kOneMinusPotential)
    for (double& v : targets) v = 1.0 - v;
  const auto [lo, hi] = std::minmax_element(targets.begin(), targets.end());
  result.target_min = *lo;
  result.target_max = *hi;
  result.seconds.potential = since(t);
  report("potential");

  t = Clock::now();
  const std::vector<Vec3> candidates = PoissonDiskSample(vertices, triangles, options.sampling);
  result.candidates = int(candidates.size());
  result.seconds.sampling = since(t);
  report("sampling");

  t = Clock::now();
  result.monopoles = GreedyMonopoleFit(
      shell.points, targets, candidates, options.fit, &result.fit,
      [&](int step, double rel) { report("fit", step, rel); });
  result.seconds.fit = since(t);
  result.seconds.total = since(start);
  return result;
}

}  // namespace quijibo::monopole
