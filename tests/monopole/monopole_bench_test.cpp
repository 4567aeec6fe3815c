// Timing of the whole monopole stage on the shipped meshes (tooth, bunny) at the paper's 97^3
// grid. Skipped unless QUIJIBO_MONOPOLE_BENCH is set (they take tens of seconds):
//   QUIJIBO_MONOPOLE_BENCH=1 quijibo_tests --gtest_filter='MonopoleBench.*'
// Optional: QUIJIBO_BEM_ELEMENTS, QUIJIBO_CANDIDATES (counts), QUIJIBO_NORMALIZE_COLUMNS (set).
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

#if __has_include("mesh/sdf.h")
#include "mesh/normalize.h"
#include "mesh/sdf.h"
#include "mesh/triangle_mesh.h"
#include "monopole/fit_pipeline.h"
#include "quijibo/frame.h"

namespace quijibo {
namespace {

void RunBench(const std::string& name, MonopoleTarget target) {
  if (!std::getenv("QUIJIBO_MONOPOLE_BENCH")) GTEST_SKIP() << "set QUIJIBO_MONOPOLE_BENCH=1";
  const std::string path = std::string("/work/shared/data/") + name + ".obj";
  const TriangleMesh user = ReadMesh(path);
  const FractalFrame frame = NormalizationFor(user);
  const TriangleMesh mesh = ToFractalFrame(user, frame);
  const ScalarGrid sdf = SignedDistance(mesh, TargetGridFrame(97, frame));
  MonopoleOptions opt;
  opt.target = target;
  if (const char* e = std::getenv("QUIJIBO_BEM_ELEMENTS")) opt.bem.max_elements = std::atoi(e);
  if (const char* e = std::getenv("QUIJIBO_CANDIDATES")) opt.sampling.count = std::atoi(e);
  if (std::getenv("QUIJIBO_NORMALIZE_COLUMNS")) opt.fit.normalize_columns = true;
  const MonopoleResult r = FitMonopoles(mesh.vertices, mesh.triangles, sdf, opt);
  std::printf(
      "%s (%s): %d triangles -> %d BEM elements; system residual %.2g, surface |P-1| max %.3g "
      "rms %.3g\n  shell %d points, P in [%.4f, %.4f]; %d candidates\n"
      "  fit: %d monopoles (%d positive, %d negative), %d steps, relative residual %.4f (%s)\n"
      "  seconds: bem %.2f (assembly %.2f, solve %.2f), shell %.3f, potential %.2f, sampling "
      "%.2f, fit %.2f, total %.2f\n",
      name.c_str(), target == MonopoleTarget::kPotential ? "P" : "1-P", r.bem.input_triangles,
      r.bem.elements, r.bem.relative_residual, r.bem.surface_max_deviation,
      r.bem.surface_rms_deviation, r.shell_points, r.target_min, r.target_max, r.candidates,
      int(r.monopoles.size()), r.positive_count(), r.negative_count(), r.fit.steps,
      r.fit.final_relative_residual, ToString(r.fit.stop), r.seconds.bem, r.bem.assembly_seconds,
      r.bem.solve_seconds, r.seconds.shell, r.seconds.potential, r.seconds.sampling, r.seconds.fit,
      r.seconds.total);
}

TEST(MonopoleBench, Tooth) { RunBench("tooth", MonopoleTarget::kPotential); }
TEST(MonopoleBench, Bunny) { RunBench("bunny", MonopoleTarget::kPotential); }
TEST(MonopoleBench, ToothOneMinusP) { RunBench("tooth", MonopoleTarget::kOneMinusPotential); }
TEST(MonopoleBench, BunnyOneMinusP) { RunBench("bunny", MonopoleTarget::kOneMinusPotential); }

}  // namespace
}  // namespace quijibo
#endif

#if __has_include("mesh/sdf.h")
namespace quijibo {
namespace {

// How P on the tooth's offset shell converges with the number of BEM elements.
TEST(MonopoleBench, ToothBemConvergence) {
  if (!std::getenv("QUIJIBO_MONOPOLE_BENCH")) GTEST_SKIP() << "set QUIJIBO_MONOPOLE_BENCH=1";
  const TriangleMesh user = ReadMesh("/work/shared/data/tooth.obj");
  const FractalFrame frame = NormalizationFor(user);
  const TriangleMesh mesh = ToFractalFrame(user, frame);
  const ScalarGrid sdf = SignedDistance(mesh, TargetGridFrame(97, frame));
  const OffsetShell shell = ComputeOffsetShell(sdf);
  std::vector<double> reference;
  for (int e : {16000, 1000, 2000, 4000, 8000}) {
    BemOptions opt;
    opt.max_elements = e;
    BemSummary s;
    const ExteriorPotential pot = SolveExteriorPotential(mesh.vertices, mesh.triangles, opt, &s);
    const auto t0 = std::chrono::steady_clock::now();
    const std::vector<double> p = pot.Evaluate(shell.points);
    const double eval = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (reference.empty()) reference = p;
    double worst = 0.0;
    for (std::size_t i = 0; i < p.size(); ++i)
      worst = std::max(worst, std::abs(p[i] - reference[i]) / reference[i]);
    std::printf("%5d elements: assembly %.2f s, GMRES %d its %.2f s, shell eval %.2f s; surface "
                "|P-1| max %.4f; max rel. diff to 16000 on the shell %.4f %%\n",
                s.elements, s.assembly_seconds, s.solver_iterations, s.solve_seconds, eval,
                s.surface_max_deviation, 100 * worst);
  }
}

}  // namespace
}  // namespace quijibo
#endif
