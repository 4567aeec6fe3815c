#include <gtest/gtest.h>

#include <cmath>

#include "tests/core/energy_fixtures.h"
#include "quijibo/band_energy.h"
#include "util/error.h"
#include "quijibo/loglinear_energy.h"

namespace quijibo {
namespace {

using testing::EnergyProblem;
using testing::MakeEnergyProblem;

// The band's problems: the optimizer's weight field.
EnergyProblem MakeBandProblem(int n, int top, int bottom, double emin, double emax, std::uint64_t seed) {
  return MakeEnergyProblem(n, top, bottom, emin, emax, seed, WeightField::kBalanced);
}

double Relative(double a, double b) { return std::fabs(a - b) / std::max(1e-300, std::fabs(b)); }

// Band and dense agree (the design makes them bit-identical; the requirement is 1e-12).
void ExpectSame(const Evaluation<double>& band, const Evaluation<double>& dense, const std::string& what) {
  EXPECT_LE(Relative(band.energy, dense.energy), 1e-12) << what;
  EXPECT_EQ(band.energy, dense.energy) << what;
  ASSERT_EQ(band.gradient.size(), dense.gradient.size()) << what;
  const double scale = dense.gradient.cwiseAbs().maxCoeff();
  for (Eigen::Index k = 0; k < dense.gradient.size(); ++k) {
    EXPECT_LE(std::fabs(band.gradient[k] - dense.gradient[k]), 1e-12 * scale) << what << " component " << k;
    EXPECT_EQ(band.gradient[k], dense.gradient[k]) << what << " component " << k;
  }
}

TEST(BandEnergyTest, SaturatedTanhIsExactlyOne) {
  // The band's premise: beyond |alpha L| = 19.07 tanh is +-1 in double; kBandSaturation leaves room.
  EXPECT_EQ(std::tanh(19.1), 1.0);
  EXPECT_EQ(std::tanh(-19.1), -1.0);
  EXPECT_LT(std::tanh(18.0), 1.0);
  EXPECT_GE(kBandSaturation, 19.1);
}

TEST(BandEnergyTest, MatchesDenseOnRandomMaps) {
  for (auto storage : {LogLinearOptions::Storage::kDouble, LogLinearOptions::Storage::kOnTheFly}) {
    for (std::uint64_t seed : {1, 2}) {
      const EnergyProblem p = MakeBandProblem(18, 9, 7, 0.5, 3.0, seed);
      LogLinearOptions lo;
      lo.storage = storage;
      const LogLinearEnergy dense(p.map, p.grid, {}, lo);
      BandEnergy band(&dense);
      const Eigen::VectorXd x = p.map.variables();
      ExpectSame(band.Evaluate(x), dense.Evaluate(x), "random map");
      EXPECT_EQ(band.Evaluate(x, EnergyMode::kFull, false).energy, dense.Evaluate(x, EnergyMode::kFull, false).energy);
    }
  }
}

// Seeded moves of every variable, then far moves and new weights: band and dense stay identical.
BandStats CheckAlongMoves(int n, const LogLinearOptions& lo) {
  const EnergyProblem p = MakeBandProblem(n, 12, 10, 4.0, 12.0, 7);
  LogLinearEnergy dense(p.map, p.grid, {}, lo);
  BandEnergy band(&dense);
  Eigen::VectorXd x = p.map.variables();
  ExpectSame(band.Evaluate(x), dense.Evaluate(x), "start");
  const BandStats first = band.stats();
  EXPECT_EQ(first.anchors, 1);
  // Steep L: a minority of the cells is unsaturated (27 % here).
  EXPECT_LT(first.band_cells, first.cells / 2);
  EXPECT_GT(first.band_cells, 0);
  // Small seeded moves of every variable: the list covers them without a new anchor at first.
  std::uint64_t state = 12345;
  auto uniform = [&] {
    state = state * 6364136223846793005ULL + 1442695040888963407ULL;
    return double(state >> 11) * 0x1p-53 - 0.5;
  };
  for (int step = 0; step < 40; ++step) {
    Eigen::VectorXd y = x;
    for (Eigen::Index k = 0; k < y.size(); ++k) y[k] = std::max(0.0, y[k] + 0.002 * (step + 1) * uniform());
    y[0] = x[0] + 0.01 * step * uniform();
    ExpectSame(band.Evaluate(y), dense.Evaluate(y), "step " + std::to_string(step));
  }
  EXPECT_GT(band.stats().max_exact, first.band_cells);  // cells beyond the band were evaluated
  EXPECT_LT(band.stats().max_exact, first.cells);
  EXPECT_LT(band.stats().work_fraction(), 1.0);
  // ln C moves by 3: the level set moves through cells that were deep in saturation. A refresh
  // must notice, else the energies would differ.
  const long long sweeps = band.stats().sweeps();
  Eigen::VectorXd far = x;
  far[0] += 3.0;
  const auto dense_far = dense.Evaluate(far);
  ExpectSame(band.Evaluate(far), dense_far, "ln C + 3");
  ExpectSame(band.EvaluateOnce(far, true), dense_far, "ln C + 3, once");
  EXPECT_EQ(band.EvaluateOnce(x).energy, dense.Evaluate(x).energy);
  EXPECT_GT(band.stats().sweeps(), sweeps);
  EXPECT_GT(std::fabs(dense_far.energy - dense.Evaluate(x).energy), 1e-3);  // the move mattered
  // Exponents doubled, then back: more sweeps, still identical.
  Eigen::VectorXd twice = x;
  twice.tail(twice.size() - 3) *= 2.0;
  ExpectSame(band.Evaluate(twice), dense.Evaluate(twice), "exponents x2");
  ExpectSame(band.Evaluate(x), dense.Evaluate(x), "back");
  // New weights (an R pass) keep the anchor but change the constants.
  std::vector<double> w = p.grid.weight;
  for (std::size_t c = 0; c < w.size(); ++c) w[c] *= 1.0 + 0.5 * std::sin(double(c));
  double eta = 0;
  for (double v : w) eta += std::fabs(v);
  dense.SetWeights(w, eta);
  ExpectSame(band.Evaluate(x), dense.Evaluate(x), "reweighted");
  EXPECT_EQ(band.stats().dense_fallbacks, 0);
  // L on the grid: exact where the band computes it, the exact sign (and |L| > L_sat) in blocks.
  const std::vector<double> Lb = band.LogModulus(x), Ld = dense.LogModulus(x);
  EXPECT_EQ(Lb.size(), Ld.size());
  long long infinite = 0;
  for (std::size_t c = 0; c < std::min(Lb.size(), Ld.size()); ++c) {
    if (std::isnan(Ld[c])) {
      EXPECT_TRUE(std::isnan(Lb[c])) << c;
    } else if (std::isinf(Lb[c])) {
      ++infinite;
      EXPECT_GT(Lb[c] * Ld[c], 0) << c;
      EXPECT_GT(std::fabs(Ld[c]) * dense.alpha(), kBandSaturation) << c;
    } else {
      EXPECT_EQ(Lb[c], Ld[c]) << c;
    }
  }
  EXPECT_EQ(infinite > 0, dense.storage() == LogLinearOptions::Storage::kOnTheFly);
  if (dense.storage() == LogLinearOptions::Storage::kOnTheFly) {
    // Anchored on blocks, never by a dense sweep, and some blocks were proven saturated.
    EXPECT_EQ(band.stats().block_sweeps, band.stats().sweeps());
    EXPECT_GT(band.stats().saturated_blocks, 0);
  } else {
    EXPECT_EQ(band.stats().block_sweeps, 0);
  }
  return band.stats();
}

TEST(BandEnergyTest, MatchesDenseAlongMovesThatForceRefreshes) { CheckAlongMoves(24, {}); }

TEST(BandEnergyTest, BlocksMatchDenseAlongMoves) {
  LogLinearOptions lo;
  lo.storage = LogLinearOptions::Storage::kOnTheFly;
  const BandStats s = CheckAlongMoves(30, lo);  // 30 = 7 x 4 + 2: partial blocks at the far faces
  EXPECT_LT(s.sweep_cells, s.sweeps() * s.cells);  // block sweeps did less than dense ones
  lo.memory_budget_bytes = 1000;  // no row fits the cache: rows recomputed, same results
  CheckAlongMoves(26, lo);
}

TEST(BandEnergyTest, RowCacheFollowsTheRequests) {
  // CacheRows keeps the rows asked for, with the values Row computes, and drops the others once
  // they would make up a quarter of the cache: it follows the band rather than accumulating.
  const EnergyProblem p = MakeBandProblem(16, 6, 5, 1.0, 2.0, 3);
  LogLinearOptions lo;
  lo.storage = LogLinearOptions::Storage::kOnTheFly;
  const LogLinearEnergy dense(p.map, p.grid, {}, lo);
  lo.storage = LogLinearOptions::Storage::kDouble;
  const LogLinearEnergy stored(p.map, p.grid, {}, lo);
  const int r = dense.root_count();
  const std::size_t row_bytes = std::size_t(r) * sizeof(double);
  const std::int64_t m = dense.active_count(), quarter = m / 4, shift = m / 40;
  auto range = [](std::int64_t from, std::int64_t count) {
    std::vector<std::int64_t> v;
    for (std::int64_t a = from; a < from + count; ++a) v.push_back(a);
    return v;
  };
  std::vector<double> buffer(static_cast<std::size_t>(r)), reference(static_cast<std::size_t>(r));
  auto expect_cached = [&](const std::vector<std::int64_t>& actives) {
    for (std::int64_t a : actives) {
      const double* row = dense.RowOf(a, buffer.data());
      ASSERT_NE(row, buffer.data()) << a;
      const double* want = stored.RowOf(a, reference.data());
      for (int j = 0; j < r; ++j) ASSERT_EQ(row[j], want[j]) << a << " root " << j;
    }
  };
  std::vector<std::int64_t> first = range(0, quarter);
  first.push_back(0);  // duplicates get one row
  dense.CacheRows(first);
  EXPECT_EQ(dense.cached_row_bytes(), std::size_t(quarter) * row_bytes);
  expect_cached(first);
  // A shifted request: few rows go stale, so they stay.
  dense.CacheRows(range(shift, quarter));
  EXPECT_EQ(dense.cached_row_bytes(), std::size_t(quarter + shift) * row_bytes);
  // A request elsewhere: the old rows are dropped, the kept ones moved and still right.
  const std::vector<std::int64_t> elsewhere = range(quarter, quarter);
  dense.CacheRows(elsewhere);
  EXPECT_EQ(dense.cached_row_bytes(), std::size_t(quarter) * row_bytes);
  expect_cached(elsewhere);
  EXPECT_EQ(dense.RowOf(0, buffer.data()), buffer.data());  // dropped: computed
  // Half the budget holds 10 rows: the first 10 asked for.
  lo.storage = LogLinearOptions::Storage::kOnTheFly;
  lo.memory_budget_bytes = double(20 * row_bytes);
  const LogLinearEnergy small(p.map, p.grid, {}, lo);
  small.CacheRows(range(5, 30));
  EXPECT_EQ(small.cached_row_bytes(), 10 * row_bytes);
  EXPECT_NE(small.RowOf(14, buffer.data()), buffer.data());
  EXPECT_EQ(small.RowOf(15, buffer.data()), buffer.data());
}

TEST(BandEnergyTest, IsolatedEvaluationsKeepRowsOnlyWhereNoBandAnchors) {
  // The absolute energy's band (EvaluateOnce) keeps the rows it evaluates, so that the next
  // absolute energy reads them; once a band that anchors keeps the evaluator's rows (a pass at the
  // finest level shares the evaluator), isolated evaluations leave that cache alone.
  const EnergyProblem p = MakeBandProblem(20, 10, 8, 3.0, 9.0, 11);
  LogLinearOptions lo;
  lo.storage = LogLinearOptions::Storage::kOnTheFly;
  const LogLinearEnergy dense(p.map, p.grid, {}, lo);
  BandEnergy once(&dense);
  const Eigen::VectorXd x = p.map.variables();
  const auto reference = dense.Evaluate(x);
  EXPECT_EQ(dense.row_owner(), nullptr);
  ExpectSame(once.EvaluateOnce(x, true), reference, "first isolated");
  EXPECT_EQ(dense.row_owner(), &once);
  const std::size_t kept = dense.cached_row_bytes();
  EXPECT_GT(kept, 0u);
  ExpectSame(once.EvaluateOnce(x, true), reference, "isolated, rows cached");
  EXPECT_EQ(dense.cached_row_bytes(), kept);
  BandEnergy pass(&dense, once.blocks());
  ExpectSame(pass.Evaluate(x), reference, "anchoring band");
  EXPECT_EQ(dense.row_owner(), &pass);
  const std::size_t pass_rows = dense.cached_row_bytes();
  Eigen::VectorXd y = x;
  y[0] += 0.7;
  ExpectSame(once.EvaluateOnce(y, true), dense.Evaluate(y), "isolated beside a band");
  EXPECT_EQ(dense.row_owner(), &pass);
  EXPECT_EQ(dense.cached_row_bytes(), pass_rows);
  ExpectSame(pass.Evaluate(x), reference, "band after the isolated point");
}

TEST(BandEnergyTest, AutoStorageKeepsOnlyTheBandsRowsOfLargeMatrices) {
  // Read through a band, kAuto stores the matrix only up to an eighth of the budget.
  const EnergyProblem p = MakeBandProblem(12, 6, 5, 1.0, 2.0, 3);
  LogLinearOptions lo;
  lo.storage = LogLinearOptions::Storage::kDouble;
  const double bytes = double(LogLinearEnergy(p.map, p.grid, {}, lo).matrix_bytes());
  ASSERT_GT(bytes, 0);
  lo.storage = LogLinearOptions::Storage::kAuto;
  for (double budget : {bytes * 4, bytes * 8}) {
    lo.memory_budget_bytes = budget;
    lo.band = false;
    EXPECT_EQ(LogLinearEnergy(p.map, p.grid, {}, lo).storage(), LogLinearOptions::Storage::kDouble);
    lo.band = true;
    const LogLinearEnergy banded(p.map, p.grid, {}, lo);
    EXPECT_EQ(banded.storage(), budget < bytes * 8 ? LogLinearOptions::Storage::kOnTheFly
                                                   : LogLinearOptions::Storage::kDouble);
    EXPECT_EQ(banded.matrix_bytes(), budget < bytes * 8 ? 0 : std::size_t(bytes));
  }
  lo.memory_budget_bytes = bytes / 2;  // does not fit at all
  lo.band = false;
  EXPECT_EQ(LogLinearEnergy(p.map, p.grid, {}, lo).storage(), LogLinearOptions::Storage::kOnTheFly);
}

TEST(BandEnergyTest, BlockBoundsHoldForEveryCell) {
  // The premise of a block anchor: every cell's D is within e_j of the block centre's, within q_j
  // of its first-order Taylor expansion about the centre, and its row norm within N_B.
  const EnergyProblem p = MakeBandProblem(21, 6, 5, 1.0, 2.0, 3);
  LogLinearOptions lo;
  lo.storage = LogLinearOptions::Storage::kOnTheFly;
  const LogLinearEnergy dense(p.map, p.grid, {}, lo);
  const auto blocks = BandBlocks::Build(dense, 4);
  ASSERT_EQ(blocks->count(), 6 * 6 * 6);
  const int r = dense.root_count();
  std::vector<double> row(static_cast<std::size_t>(r));
  std::int64_t finite = 0, checked = 0;
  for (std::int64_t b = 0; b < blocks->count(); ++b) {
    const double N = blocks->norm[std::size_t(b)];
    finite += std::isfinite(N);
    for (std::int64_t i = blocks->offsets[std::size_t(b)]; i < blocks->offsets[std::size_t(b + 1)]; ++i) {
      const std::int64_t a = blocks->actives[std::size_t(i)];
      const double* D = dense.RowOf(a, row.data());
      const Vec3 c = dense.frame().cell_center(dense.cell_of(a));
      const double* centre = blocks->centre.data() + 3 * b;
      double n2 = 1;
      for (int j = 0; j < r; ++j) {
        n2 += D[j] * D[j];
        const std::size_t k = std::size_t(b * r + j);
        EXPECT_LE(std::fabs(D[j] - blocks->log_distance[k]), blocks->reach[k]);
        const Vec4& t = dense.roots()[std::size_t(j)];
        double d2 = (dense.slice() - t[3]) * (dense.slice() - t[3]), slope = 0;
        for (int e = 0; e < 3; ++e) d2 += (centre[e] - t[e]) * (centre[e] - t[e]);
        for (int e = 0; e < 3; ++e) slope += (centre[e] - t[e]) / d2 * (c[e] - centre[e]);
        EXPECT_LE(std::fabs(D[j] - blocks->log_distance[k] - slope), blocks->curvature[k]);
      }
      EXPECT_LE(std::sqrt(n2), N);
      ++checked;
    }
  }
  EXPECT_EQ(checked, dense.active_count());
  EXPECT_GT(finite, blocks->count() / 2);
  // Blocks belong to their evaluator.
  const EnergyProblem q = MakeBandProblem(21, 7, 5, 1.0, 2.0, 3);
  const LogLinearEnergy other(q.map, q.grid, {}, lo);
  EXPECT_THROW(BandEnergy(&other, blocks), Error);
}

TEST(BandEnergyTest, VariablePassMatchesDense) {
  const EnergyProblem p = MakeBandProblem(20, 10, 8, 3.0, 9.0, 11);
  LogLinearEnergy dense(p.map, p.grid);
  BandEnergy band(&dense);
  const Eigen::VectorXd x = p.map.variables();
  EXPECT_THROW(band.Evaluate(x, EnergyMode::kVariable), Error);
  dense.BeginVariablePass(x);
  for (int step = 0; step < 12; ++step) {
    Eigen::VectorXd y = x;
    y[0] += 0.05 * step * (step % 2 ? -1 : 1);
    y[1] *= 1.0 + 0.02 * step;
    y[2] *= 1.0 - 0.01 * step;
    ExpectSame(band.Evaluate(y, EnergyMode::kVariable), dense.Evaluate(y, EnergyMode::kVariable),
               "V step " + std::to_string(step));
  }
  Eigen::VectorXd far = x;
  far[0] -= 2.5;
  ExpectSame(band.Evaluate(far, EnergyMode::kVariable), dense.Evaluate(far, EnergyMode::kVariable), "V far");
  // A new V pass (other exponents) re-anchors; then a full evaluation switches mode.
  Eigen::VectorXd z = x;
  z.tail(z.size() - 3) *= 1.3;
  dense.BeginVariablePass(z);
  ExpectSame(band.Evaluate(z, EnergyMode::kVariable), dense.Evaluate(z, EnergyMode::kVariable), "new V pass");
  ExpectSame(band.Evaluate(z), dense.Evaluate(z), "full after V");
}

}  // namespace
}  // namespace quijibo
