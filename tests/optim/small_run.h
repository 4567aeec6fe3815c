// A small optimization problem for the optimizer's tests: an analytic torus on 20^3 and a seeded
// random map (12 top, 9 bottom roots) scaled so that half the cells are inside; and an empty
// output folder for a test's run.
#pragma once

#include <filesystem>
#include <string>

#include "quijibo/energy.h"
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
};

// <temp>/quijibo_optim_<name>, removed if it exists (the optimizer creates it).
inline std::string TempDir(const std::string& name) {
  const auto d = std::filesystem::temp_directory_path() / ("quijibo_optim_" + name);
  std::filesystem::remove_all(d);
  return d.string();
}

}  // namespace quijibo
