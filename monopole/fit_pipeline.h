// The whole monopole stage of the 2015 paper (section 4.4): BEM potential -> offset shell ->
// potential on the shell -> blue-noise candidates -> greedy monopole fit, with a timing per stage.
//
// Everything is in the caller's frame; the toolkit passes the mesh and the signed distance field
// in fractal coordinates. P = 1 on the surface in any units, so the targets do not depend on the
// frame, while the weights scale with length (a monopole w / |x - m|).
#pragma once

#include <array>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "monopole/bem.h"
#include "monopole/monopole_fit.h"
#include "monopole/sampling.h"
#include "monopole/shell.h"
#include "quijibo/grid.h"

namespace quijibo::monopole {

// What the monopoles fit on the shell.
enum class MonopoleTarget {
  kPotential,           // P itself (paper, Eqn 15)
  kOneMinusPotential,   // 1 - P (what the reference code fits: its BEM field file stores 1 - u)
};

struct MonopoleOptions {
  BemOptions bem;
  ShellOptions shell;
  SamplingOptions sampling;  // the candidates
  GreedyFitOptions fit;
  // P, as the paper's text (a few positive monopoles). The reference code's 1 - P needs hundreds of
  // charges of both signs and converges only on the reference's tight box, which cuts the shell:
  // on the toolkit's unit-cube box it stops above epsilon and gives the bunny an inverted start and
  // the tooth one the optimizer collapses from (issue 29, docs/benchmarks.md §2).
  MonopoleTarget target = MonopoleTarget::kPotential;

  // Empty string when valid, else what is wrong (the first problem found).
  std::string Validate() const;
};

struct MonopoleTimings {
  double bem = 0.0;        // patches, assembly and LU solve
  double shell = 0.0;      // offset shell extraction
  double potential = 0.0;  // P at the shell points
  double sampling = 0.0;   // candidates
  double fit = 0.0;        // greedy fit
  double total = 0.0;
};

struct MonopoleResult {
  std::vector<Monopole> monopoles;
  BemSummary bem;
  GreedyFitSummary fit;
  int shell_points = 0;
  int candidates = 0;
  double target_min = 0.0, target_max = 0.0;  // range of the fitted values on the shell
  MonopoleTimings seconds;
  // The BEM solution, kept so callers can draw or sample P without solving again.
  std::shared_ptr<const ExteriorPotential> potential;

  int positive_count() const;  // future top roots
  int negative_count() const;  // future bottom roots
};

// One progress report: the stage that just finished ("bem", "shell", "potential", "sampling") or
// "fit" after each greedy step (with step and relative residual).
struct MonopoleProgress {
  std::string stage;
  int step = 0;
  double relative_residual = 0.0;
  double elapsed_seconds = 0.0;  // since FitMonopoles started
};
using MonopoleProgressFn = std::function<void(const MonopoleProgress&)>;

// Runs the monopole stage.
// Inputs:
//   vertices, triangles  the closed target mesh (fractal frame)
//   sdf                  its signed distance field, negative inside, cell-centred (same frame)
//   options              see MonopoleOptions; validated (throws quijibo::Error when invalid)
//   progress             optional callback
// Output: the monopoles (positions on the surface, least-squares weights) and the stage reports.
MonopoleResult FitMonopoles(const std::vector<Vec3>& vertices,
                            const std::vector<std::array<int, 3>>& triangles,
                            const ScalarGrid& sdf, const MonopoleOptions& options = {},
                            const MonopoleProgressFn& progress = {});

}  // namespace quijibo::monopole
