#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "optim/optimizer.h"
#include "optim/small_run.h"
#include "util/error.h"

namespace quijibo::optim {
namespace {

// The same schedule with the narrow band and with the dense evaluator: the band's energy and
// gradient equal the dense ones, so every pass ends at the same psi (the requirement: 1e-9). A
// third run keeps no matrix (on-the-fly storage, as beyond ~100^3): its band anchors on blocks and
// its absolute energies go through a band too; the same psi again. With between_nodes each grid's
// band checks its own share of the two-grid energy.
void BandAndDenseRunsEndAtTheSamePsi(AutoSwitch between_nodes) {
  const ScalarGrid sdf = AnalyticTarget("torus", GridFrame::Cube(24, {0, 0, 0}, 3.0));
  RandomMapOptions ro;
  ro.top = 12;
  ro.bottom = 9;
  ro.seed = 3;
  ro.exponent_min = 2.0;
  ro.exponent_max = 6.0;
  RationalMap start = RandomMap(ro);
  start.ln_C = -MedianLogModulus(start, MakeEnergyGrid(sdf, WeightField::kLayer));
  OptimizeSummary s[3];
  RationalMap result[3];
  const char* names[3] = {"band", "dense", "band"};
  std::string dirs[3];
  for (int k = 0; k < 3; ++k) {
    dirs[k] = TempDir(std::string("band_") + names[k] + std::to_string(k) + AutoSwitchName(between_nodes));
    OptimizeOptions o = ScheduleAsWritten("12(VFRF)24(VF)", 30, dirs[k]);
    o.between_nodes = between_nodes;
    // This random start scores worse than the empty set (absolute psi > 0) and its passes lower psi
    // with the IoU: the lowest psi is what the band and dense runs are compared on.
    o.keep = OptimizeOptions::Keep::kLowestPsi;
    o.evaluator = names[k];
    if (k == 2) o.storage = LogLinearOptions::Storage::kOnTheFly;
    result[k] = start;
    s[k] = Optimize(sdf, result[k], o);
    ASSERT_TRUE(s[k].complete);
  }
  ASSERT_EQ(s[0].passes.size(), s[1].passes.size());
  EXPECT_LT(s[0].absolute_end, s[0].absolute_start - 0.05);
  for (std::size_t p = 0; p < s[0].passes.size(); ++p) {
    const PassSummary &band = s[0].passes[p], &dense = s[1].passes[p];
    EXPECT_NEAR(band.absolute_end, dense.absolute_end, 1e-9 * std::fabs(dense.absolute_end)) << p;
    EXPECT_NEAR(band.energy_end, dense.energy_end, 1e-9 * std::fabs(dense.energy_end)) << p;
    EXPECT_EQ(band.iterations, dense.iterations) << p;
    // The band reports itself; the dense run does not.
    ASSERT_TRUE(band.band.is_object()) << p;
    EXPECT_EQ(band.band.contains("corners"), between_nodes == AutoSwitch::kOn) << p;
    EXPECT_TRUE(dense.band.is_null()) << p;
    EXPECT_LE(band.band["energy_error"].get<double>(), 1e-12) << p;
    EXPECT_GE(band.band["anchors"].get<long long>(), 1) << p;
    EXPECT_LE(band.band["mean_fraction"].get<double>(), 1.0) << p;
    const PassSummary& blocked = s[2].passes[p];
    EXPECT_EQ(blocked.absolute_end, dense.absolute_end) << p;
    EXPECT_EQ(blocked.energy_end, dense.energy_end) << p;
    EXPECT_EQ(blocked.iterations, dense.iterations) << p;
    EXPECT_EQ(blocked.band["energy_error"].get<double>(), 0.0) << p;
    EXPECT_EQ(band.band["block_sweeps"].get<long long>(), 0) << p;
    if (blocked.kind != 'V') {
      EXPECT_GE(blocked.band["block_sweeps"].get<long long>(), 1) << p;
    }
  }
  EXPECT_EQ(result[0].variables(), result[1].variables());
  EXPECT_EQ(result[2].variables(), result[1].variables());
  // The summary and the pass-end log lines carry the band's statistics; the table on stderr does not.
  const auto summary = nlohmann::json::parse(std::ifstream(dirs[0] + "/summary.json"));
  EXPECT_TRUE(summary["passes"][0]["band"].contains("energy_error"));
  std::ifstream log(dirs[0] + "/log.jsonl");
  bool pass_end_band = false;
  for (std::string line; std::getline(log, line);) {
    const auto j = nlohmann::json::parse(line);
    if (j["type"] == "pass_end") pass_end_band |= j.contains("band");
  }
  EXPECT_TRUE(pass_end_band);
  EXPECT_EQ(s[0].Report().find("band:"), std::string::npos) << s[0].Report();
  for (const std::string& d : dirs) std::filesystem::remove_all(d);
}

TEST(BandOptimizerTest, BandAndDenseRunsEndAtTheSamePsi) { BandAndDenseRunsEndAtTheSamePsi(AutoSwitch::kOff); }

TEST(BandOptimizerTest, BandAndDenseRunsEndAtTheSamePsiBetweenTheNodes) {
  BandAndDenseRunsEndAtTheSamePsi(AutoSwitch::kOn);
}

TEST(BandOptimizerTest, EvaluatorNamesResolve) {
  EXPECT_EQ(ResolveEvaluator("auto", Precision::kDouble), "band");
  EXPECT_EQ(ResolveEvaluator("auto", Precision::kLongDouble), "cached");
  EXPECT_EQ(ResolveEvaluator("loglinear", Precision::kDouble), "dense");
  EXPECT_THROW(ResolveEvaluator("fast", Precision::kDouble), Error);
  OptimizeOptions o;
  o.schedule = Schedule::Parse("8(V)");
  o.min_level_fidelity = 0;  // the schedule as written: the level rule is tested on its own
  o.out_dir = "x";
  o.evaluator = "band";
  o.precision = Precision::kLongDouble;
  EXPECT_NE(o.Validate().find("double only"), std::string::npos);
}

}  // namespace
}  // namespace quijibo::optim
