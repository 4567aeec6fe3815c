#include "monopole/monopole_fit.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <omp.h>
#include <random>

#include "monopole/fit_pipeline.h"
#include "monopole/sampling.h"
#include "util/error.h"
#include "test_meshes.h"
#include "thrown_message.h"

namespace quijibo::monopole {
namespace {

using testing::ThrownMessage;

// Points on the sphere of radius r about c (icosphere vertices, level 3: 642 points).
std::vector<Vec3> SpherePoints(const Vec3& c, double r) {
  return testing::MakeIcosphere(3, c, r).vertices;
}

TEST(Monopole, IncrementalLeastSquaresEqualsBatch) {
  // Monopole columns of nearby surface points: strongly correlated, as in the real fit.
  const std::vector<Vec3> x = SpherePoints({0, 0, 0}, 1.3);
  const auto mesh = testing::MakeIcosphere(2);
  std::vector<Vec3> sources(mesh.vertices.begin(), mesh.vertices.begin() + 60);
  Eigen::VectorXd b(x.size());
  for (std::size_t i = 0; i < x.size(); ++i) b[i] = std::sin(3 * x[i][0]) + x[i][1] * x[i][2];
  IncrementalLeastSquares ls(b);
  Eigen::MatrixXd A(x.size(), 0);
  for (const Vec3& s : sources) {
    const Eigen::VectorXd a = MonopoleColumn(x, s);
    ASSERT_TRUE(ls.AddColumn(a));
    A.conservativeResize(Eigen::NoChange, A.cols() + 1);
    A.col(A.cols() - 1) = a;
    if (A.cols() % 15 != 0) continue;
    const Eigen::VectorXd w_batch = A.colPivHouseholderQr().solve(b);
    const Eigen::VectorXd w = ls.Solution();
    const Eigen::VectorXd r_batch = b - A * w_batch;
    EXPECT_NEAR(ls.residual_norm(), r_batch.norm(), 1e-10 * b.norm()) << A.cols();
    EXPECT_LT((ls.residual() - r_batch).norm(), 1e-9 * b.norm()) << A.cols();
    EXPECT_LT((b - A * w - ls.residual()).norm(), 1e-9 * b.norm()) << A.cols();
    if (A.cols() <= 30) {  // beyond, A is too ill-conditioned for the weights themselves to agree
      EXPECT_LT((w - w_batch).norm(), 1e-6 * w_batch.norm()) << A.cols();
    }
  }
  // A column already in the span is refused and changes nothing.
  const double before = ls.residual_norm();
  EXPECT_FALSE(ls.AddColumn(A.col(3) * 2.0 - A.col(7)));
  EXPECT_EQ(ls.columns(), 60);
  EXPECT_EQ(ls.residual_norm(), before);
}

TEST(Monopole, SeededPermutationIsAPermutation) {
  const std::vector<int> p = SeededPermutation(1000, 1);
  std::vector<int> s = p;
  std::sort(s.begin(), s.end());
  for (int i = 0; i < 1000; ++i) ASSERT_EQ(s[i], i);
  EXPECT_EQ(p, SeededPermutation(1000, 1));
  EXPECT_NE(p, SeededPermutation(1000, 2));
}

struct SphereProblem {
  std::vector<Vec3> points, candidates;
  std::vector<double> targets;
};

// P = a / r on a shell of radius 1.2 a, candidates on the sphere.
SphereProblem MakeSphereProblem(int candidates) {
  const double a = 1.0;
  SphereProblem p;
  p.points = SpherePoints({0, 0, 0}, 1.2 * a);
  p.targets.assign(p.points.size(), a / (1.2 * a));
  const auto mesh = testing::MakeIcosphere(3, {0, 0, 0}, a);
  SamplingOptions so;
  so.count = candidates;
  p.candidates = PoissonDiskSample(mesh.vertices, mesh.triangles, so);
  return p;
}

TEST(Monopole, GreedyFitOnTheSphereReachesEpsilon) {
  const SphereProblem p = MakeSphereProblem(5000);
  GreedyFitOptions opt;
  opt.epsilon = 0.04;  // the paper's
  GreedyFitSummary s;
  int calls = 0;
  const auto m = GreedyMonopoleFit(p.points, p.targets, p.candidates, opt, &s,
                                   [&](int, double) { ++calls; });
  std::printf("sphere: %d monopoles, relative residual %.4f after %d steps\n", s.monopoles,
              s.final_relative_residual, s.steps);
  EXPECT_EQ(s.stop, FitStop::kConverged);
  EXPECT_LE(s.final_relative_residual, 0.04);
  EXPECT_GT(s.monopoles, 1);  // one surface monopole cannot make a constant on the shell
  EXPECT_EQ(int(m.size()), s.monopoles);
  EXPECT_EQ(calls, s.steps);
  ASSERT_EQ(int(s.relative_residual.size()), s.steps);
  for (int i = 1; i < s.steps; ++i) EXPECT_LE(s.relative_residual[i], s.relative_residual[i - 1]);
  // Stops at the first step below epsilon.
  for (int i = 0; i + 1 < s.steps; ++i) EXPECT_GT(s.relative_residual[i], 0.04);
  EXPECT_EQ(s.candidates_examined, 100 * s.steps);
  // The weights reproduce the residual.
  double rr = 0.0, bb = 0.0;
  for (std::size_t i = 0; i < p.points.size(); ++i) {
    double v = 0.0;
    for (const Monopole& q : m) {
      const double dx = p.points[i][0] - q.position[0], dy = p.points[i][1] - q.position[1],
                   dz = p.points[i][2] - q.position[2];
      v += q.weight / std::sqrt(dx * dx + dy * dy + dz * dz);
    }
    rr += (v - p.targets[i]) * (v - p.targets[i]);
    bb += p.targets[i] * p.targets[i];
  }
  EXPECT_NEAR(std::sqrt(rr / bb), s.final_relative_residual, 1e-9);
}

TEST(Monopole, GreedyFitReportsRunningOutOfCandidates) {
  const SphereProblem p = MakeSphereProblem(250);
  GreedyFitOptions opt;
  opt.epsilon = 1e-9;
  GreedyFitSummary s;
  GreedyMonopoleFit(p.points, p.targets, p.candidates, opt, &s);
  EXPECT_EQ(s.stop, FitStop::kCandidatesExhausted);
  EXPECT_EQ(s.steps, 3);  // 100 + 100 + 50
  EXPECT_EQ(s.candidates_examined, 250);
  opt.max_monopoles = 2;
  GreedyMonopoleFit(p.points, p.targets, p.candidates, opt, &s);
  EXPECT_EQ(s.stop, FitStop::kMaxMonopoles);
  EXPECT_EQ(s.monopoles, 2);
}

TEST(Monopole, PipelineOnTheSphereIsDeterministic) {
  const Vec3 c{0.1, 0.0, -0.1};
  const double a = 1.0;
  const auto mesh = testing::MakeIcosphere(3, c, a);
  const ScalarGrid sdf = testing::SphereSdf(40, c, 3.0, a);
  MonopoleOptions opt;
  opt.target = MonopoleTarget::kPotential;
  opt.sampling.count = 5000;
  opt.fit.epsilon = 0.01;
  std::vector<std::string> stages;
  const MonopoleResult r1 = FitMonopoles(mesh.vertices, mesh.triangles, sdf, opt,
                                         [&](const MonopoleProgress& p) {
                                           if (stages.empty() || stages.back() != p.stage)
                                             stages.push_back(p.stage);
                                         });
  EXPECT_EQ(stages, (std::vector<std::string>{"bem", "shell", "potential", "sampling", "fit"}));
  EXPECT_EQ(r1.fit.stop, FitStop::kConverged);
  EXPECT_GT(r1.shell_points, 1000);
  // The shell lies 5 cells (0.375) out: P = a / r there, within 1 %.
  EXPECT_NEAR(r1.target_max, a / (a + 5 * 3.0 / 40), 0.01 * a / (a + 5 * 3.0 / 40) + 0.02);
  const MonopoleResult r2 = FitMonopoles(mesh.vertices, mesh.triangles, sdf, opt);
  ASSERT_EQ(r1.monopoles.size(), r2.monopoles.size());
  for (std::size_t i = 0; i < r1.monopoles.size(); ++i) {
    EXPECT_EQ(r1.monopoles[i].position, r2.monopoles[i].position);
    EXPECT_EQ(r1.monopoles[i].weight, r2.monopoles[i].weight);
  }
  EXPECT_EQ(r1.fit.relative_residual, r2.fit.relative_residual);
  opt.fit.seed = 7;
  const MonopoleResult r3 = FitMonopoles(mesh.vertices, mesh.triangles, sdf, opt);
  EXPECT_NE(r1.monopoles.front().position, r3.monopoles.front().position);
}

TEST(Monopole, PipelineDoesNotDependOnTheThreadCount) {
  const auto mesh = testing::MakeIcosphere(3);
  const ScalarGrid sdf = testing::SphereSdf(32, {0, 0, 0}, 3.0, 1.0);
  MonopoleOptions opt;
  opt.target = MonopoleTarget::kPotential;
  opt.bem.max_elements = 600;
  opt.sampling.count = 3000;
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  const MonopoleResult one = FitMonopoles(mesh.vertices, mesh.triangles, sdf, opt);
  omp_set_num_threads(std::max(2, threads));
  const MonopoleResult many = FitMonopoles(mesh.vertices, mesh.triangles, sdf, opt);
  omp_set_num_threads(threads);
  ASSERT_EQ(one.monopoles.size(), many.monopoles.size());
  for (std::size_t i = 0; i < one.monopoles.size(); ++i) {
    EXPECT_EQ(one.monopoles[i].position, many.monopoles[i].position);
    EXPECT_EQ(one.monopoles[i].weight, many.monopoles[i].weight);
  }
}

TEST(Monopole, BadOptionsAreRejected) {
  const SphereProblem p = MakeSphereProblem(300);
  GreedyFitOptions opt;
  opt.epsilon = 1.5;
  EXPECT_EQ(ThrownMessage([&] { GreedyMonopoleFit(p.points, p.targets, p.candidates, opt); }),
            "fit.epsilon (relative residual) must be in [0, 1), found 1.500000");
  opt = {};
  opt.batch_size = 0;
  EXPECT_NE(opt.Validate().find("fit.batch_size"), std::string::npos);
  std::vector<double> short_targets(3, 1.0);
  EXPECT_THROW(GreedyMonopoleFit(p.points, short_targets, p.candidates, {}), Error);
  MonopoleOptions mo;
  mo.shell.offset_cells = -1;
  EXPECT_NE(mo.Validate().find("shell.offset_cells"), std::string::npos);
  mo = {};
  mo.bem.max_elements = 0;
  EXPECT_NE(mo.Validate().find("bem.max_elements"), std::string::npos);
}

TEST(Monopole, ZeroTargetGivesNoMonopoles) {
  const SphereProblem p = MakeSphereProblem(300);
  GreedyFitSummary s;
  const auto m = GreedyMonopoleFit(p.points, std::vector<double>(p.points.size(), 0.0),
                                   p.candidates, {}, &s);
  EXPECT_TRUE(m.empty());
  EXPECT_EQ(s.final_relative_residual, 0.0);
}

}  // namespace
}  // namespace quijibo::monopole
