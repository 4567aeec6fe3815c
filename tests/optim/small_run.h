// A small optimization problem for the optimizer's tests: an analytic torus on 20^3 and a seeded
// random map (12 top, 9 bottom roots) scaled so that half the cells are inside; empty output
// folders for a test's runs; and the options of a run of a schedule as written.
#pragma once

#include <gtest/gtest.h>

#include <filesystem>
#include <optional>
#include <string>

#include "optim/optimizer.h"
#include "quijibo/energy.h"
#include "quijibo/loglinear_energy.h"
#include "quijibo/rational_map.h"
#include "quijibo/target.h"

namespace quijibo {

struct SmallRun {
  ScalarGrid sdf;
  RationalMap map;
  explicit SmallRun(int top = 12, int bottom = 9, double exponent_max = 3.0) {
    sdf = AnalyticTarget("torus", GridFrame::Cube(20, {0, 0, 0}, 3.0));
    RandomMapOptions o;
    o.top = top;
    o.bottom = bottom;
    o.exponent_max = exponent_max;
    o.seed = 3;
    map = RandomMap(o);
    map.ln_C = -MedianLogModulus(map, MakeEnergyGrid(sdf, WeightField::kLayer));
  }
  // The exact (log-linear) energy of `m` on the target's own grid with `weights`: what a run
  // reports as its absolute energy (counted from the better trivial set).
  double AbsoluteEnergy(const RationalMap& m, WeightField weights) const {
    const EnergyGrid grid = MakeEnergyGrid(sdf, weights);
    return LogLinearEnergy(m, grid).Evaluate(m.variables(), EnergyMode::kFull, false).energy - TrivialSetEnergy({&grid});
  }
};

// <temp>/quijibo_optim_<name>, removed if it exists (the optimizer creates it).
inline std::string TempDir(const std::string& name) {
  const auto d = std::filesystem::temp_directory_path() / ("quijibo_optim_" + name);
  std::filesystem::remove_all(d);
  return d.string();
}

// <temp>/quijibo_<prefix>_<the running test case>_<name>, removed if it exists: a folder of the test
// case's own (ctest runs test cases in parallel).
inline std::string TestCaseDir(const std::string& prefix, const std::string& name) {
  const std::string test = ::testing::UnitTest::GetInstance()->current_test_info()->name();
  const auto d = std::filesystem::temp_directory_path() / ("quijibo_" + prefix + "_" + test + "_" + name);
  std::filesystem::remove_all(d);
  return d.string();
}

namespace optim {

// A run of the schedule `notation` as written (min_level_fidelity 0: the level rule has tests of
// its own) on the grid's nodes (between_nodes off: the small grids here are thin-walled in cells, and
// the corners have tests of their own), every pass capped at `max_iterations` (none: the notation's
// caps), into `out_dir`.
inline OptimizeOptions ScheduleAsWritten(const std::string& notation, std::optional<int> max_iterations,
                                         const std::string& out_dir) {
  OptimizeOptions o;
  o.schedule = Schedule::Parse(notation);
  o.min_level_fidelity = 0;
  o.between_nodes = AutoSwitch::kOff;
  if (max_iterations)
    for (auto& l : o.schedule.levels)
      for (auto& p : l.passes) p.max_iterations = *max_iterations;
  o.out_dir = out_dir;
  return o;
}

}  // namespace optim
}  // namespace quijibo
