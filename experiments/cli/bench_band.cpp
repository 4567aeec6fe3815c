// `quijibo bench band`: seconds per energy+gradient evaluation of the dense log-linear evaluator and
// of its narrow band (quijibo/band_energy.h) on a map whose fit has formed, at the levels the
// issue asks for (97^3, 193^3, 257^3). The evaluations are those of an L-BFGS F pass (the same
// iterations for both: the band's energy and gradient equal the dense ones), so anchors count.
//
// Without --map the map is a seeded random one with the paper's root split, fitted to the target
// first (F passes at 25^3 and 50^3), as an optimization would have done before a fine level.
// Where the dense matrix exceeds --memory-budget it is not stored: the dense evaluator would
// recompute every log-distance at every evaluation, so it is timed on --dense-evaluations
// evaluations only, and the band (anchored on blocks, band_energy.h) is checked against it at the
// band's last point: the same energy, bit for bit.
#include <chrono>
#include <cstdio>

#include "experiments/cli/cli.h"
#include "mesh/frame_file.h"
#include "optim/lbfgsb.h"
#include "quijibo/band_energy.h"
#include "util/error.h"
#include "quijibo/frame.h"
#include "util/io.h"
#include "util/progress.h"

namespace quijibo::cli {

using nlohmann::json;

namespace {

struct BandArgs {
  std::string roots = "331,708", grids = "97,193,257", target = "sphere", map_path, out_json = "bench-band.json",
              out_md = "bench-band.md";
  int iterations = 30, form_iterations = 300, dense_evaluations = 2;
  double memory_budget_gb = LogLinearOptions{}.memory_budget_bytes / 1e9;
  std::uint64_t seed = 1;
};

std::vector<int> ParseList(const std::string& s) {
  std::vector<int> v;
  std::size_t pos = 0;
  while (pos < s.size()) {
    const std::size_t next = s.find(',', pos);
    const std::string item = s.substr(pos, next == std::string::npos ? std::string::npos : next - pos);
    try {
      v.push_back(std::stoi(item));
    } catch (const std::exception&) {
      throw Error("bench band: \"" + item + "\" is not a number");
    }
    if (v.back() < 4 || v.back() > 1024) throw Error("bench band: " + item + " is out of range [4, 1024]");
    pos = next == std::string::npos ? s.size() : next + 1;
  }
  if (v.empty()) throw Error("bench band: empty list");
  return v;
}

EnergyGrid LevelGrid(const std::string& target, int n) {
  if (target.ends_with(".qgrid")) {
    const ScalarGrid sdf = LoadTarget(target, n);
    return MakeEnergyGrid(sdf, WeightField::kBalanced, n, LevelWeights::kRecompute);
  }
  return MakeEnergyGrid(LoadTarget(target, n), WeightField::kBalanced);
}

// An F pass of `iterations` L-BFGS iterations with `eval`; returns seconds per evaluation etc.
template <class Eval>
json FPass(Eval&& eval, Eigen::VectorXd x, int iterations, Eigen::VectorXd* end = nullptr) {
  const int n = int(x.size());
  Eigen::VectorXd lb = Eigen::VectorXd::Zero(n), ub = Eigen::VectorXd::Constant(n, INFINITY);
  lb[0] = -INFINITY;
  int evaluations = 0;
  double first = 0, energy = 0;
  const auto t0 = std::chrono::steady_clock::now();
  auto f = [&](const Eigen::VectorXd& y, Eigen::VectorXd& g) {
    const Evaluation<double> ev = eval(y);
    if (evaluations++ == 0) first = ev.seconds;
    g = ev.gradient;
    energy = ev.energy;
    return ev.energy;
  };
  optim::LbfgsbOptions<double> lo;
  lo.max_iterations = iterations;
  lo.tolerance = 1e-12;
  const auto res = optim::MinimizeBounded<double>(f, x, lb, ub, lo, [](int, int, const double&, const double&) {
    return optim::IterationAction::kContinue;
  });
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (end) *end = x;
  return {{"iterations", res.iterations}, {"evaluations", evaluations}, {"seconds", seconds},
          {"seconds_per_evaluation", seconds / std::max(1, evaluations)}, {"first_evaluation_seconds", first},
          {"energy_end", energy}};
}

json RunBand(const BandArgs& a) {
  json cases = json::array();
  for (int roots : a.map_path.empty() ? ParseList(a.roots) : std::vector<int>{0}) {
    // The map: given, or random with the paper's split and fitted at 25^3 and 50^3.
    RationalMap map;
    if (!a.map_path.empty()) {
      map = ReadMap(a.map_path);
      mesh::CheckSameFrame(map.frame, a.map_path, a.target);
    } else {
      const int top = roots == 331 ? 178 : roots == 708 ? 352 : (roots + 1) / 2;
      RandomMapOptions o;
      o.top = top;
      o.bottom = roots - top;
      o.root_radius = 1.2;
      o.exponent_min = 1.0;
      o.exponent_max = 5.0;
      o.seed = a.seed + std::uint64_t(roots);
      map = RandomMap(o);
      for (int n : {25, 50}) {
        const EnergyGrid grid = LevelGrid(a.target, n);
        if (n == 25) map.ln_C = -MedianLogModulus(map, grid);
        const LogLinearEnergy e(map, grid);
        Eigen::VectorXd x;
        FPass([&](const Eigen::VectorXd& y) { return e.Evaluate(y); }, map.variables(),
              n == 25 ? a.form_iterations : a.form_iterations / 3, &x);
        map.set_variables(x);
      }
    }
    for (int n : ParseList(a.grids)) {
      std::fprintf(stderr, "bench band: %d roots, %d^3\n", map.root_count(), n);
      const EnergyGrid grid = LevelGrid(a.target, n);
      LogLinearOptions lo;
      lo.memory_budget_bytes = a.memory_budget_gb * 1e9;
      const LogLinearEnergy dense(map, grid, {}, lo);
      const bool stored = dense.storage() == LogLinearOptions::Storage::kDouble;
      json c = {{"roots", map.root_count()}, {"grid", n}, {"cells", dense.active_count()},
                {"storage", StorageName(dense.storage())}, {"matrix_bytes", dense.matrix_bytes()},
                {"setup_seconds", dense.setup_seconds()},
                {"dense_matrix_bytes", double(dense.active_count()) * map.root_count() * 8.0}};
      const Eigen::VectorXd x = map.variables();
      double dense_end = NAN;
      if (stored) {
        c["dense"] = FPass([&](const Eigen::VectorXd& y) { return dense.Evaluate(y); }, x, a.iterations);
        dense_end = c["dense"]["energy_end"];
      } else {
        // On the fly: a few evaluations at the start point give the seconds per evaluation.
        const auto t0 = std::chrono::steady_clock::now();
        for (int k = 0; k < a.dense_evaluations; ++k) dense.Evaluate(x);
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        c["dense"] = {{"evaluations", a.dense_evaluations}, {"seconds", seconds},
                      {"seconds_per_evaluation", seconds / a.dense_evaluations}, {"on_the_fly", true}};
      }
      const auto b0 = std::chrono::steady_clock::now();
      BandEnergy band(&dense);
      const double blocks_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - b0).count();
      Eigen::VectorXd band_end;
      c["band"] = FPass([&](const Eigen::VectorXd& y) { return band.Evaluate(y); }, x, a.iterations, &band_end);
      if (!stored) dense_end = dense.Evaluate(band_end).energy;  // the band's last point
      const BandStats& s = band.stats();
      c["band"]["anchors"] = s.anchors;
      c["band"]["anchors_reach"] = s.anchors_reach;
      c["band"]["anchors_work"] = s.anchors_work;
      c["band"]["far_sweeps"] = s.far;
      c["band"]["work_fraction"] = s.work_fraction();
      c["band"]["band_cells_last_anchor"] = s.band_cells;
      c["band"]["mean_fraction"] = s.mean_fraction();
      c["band"]["max_cells"] = s.max_exact;
      c["band"]["dense_fallbacks"] = s.dense_fallbacks;
      c["band"]["block_sweeps"] = s.block_sweeps;
      c["band"]["blocks"] = s.blocks;
      c["band"]["saturated_blocks_last_sweep"] = s.saturated_blocks;
      c["band"]["blocks_setup_seconds"] = blocks_seconds;
      c["band"]["blocks_bytes"] = band.blocks() ? band.blocks()->bytes() : 0;
      c["band"]["cached_row_bytes"] = dense.cached_row_bytes();
      c["identical"] = c["band"]["energy_end"].get<double>() == dense_end;
      c["speedup"] = c["dense"]["seconds_per_evaluation"].get<double>() / c["band"]["seconds_per_evaluation"].get<double>();
      cases.push_back(c);
    }
  }
  return cases;
}

std::string Fmt(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.3g", v);
  return b;
}

std::string Markdown(const json& cases) {
  std::string md =
      "| roots | grid | evaluations | dense s / eval | band s / eval | speed-up | anchors (+ other sweeps) | "
      "cells per band eval (mean, max) | work vs dense | first eval (anchor) s | storage | same final psi |\n"
      "|---:|---|---:|---:|---:|---:|---|---|---:|---:|---|---|\n";
  char line[512];
  for (const json& c : cases) {
    const json& b = c["band"];
    const std::string storage = c["storage"].get<std::string>() == "double" ? "stored" : "on the fly, blocks";
    std::snprintf(line, sizeof line, "| %d | %d³ | %d | %s | %.4g | %s | %lld (+%lld) | %.2f %%, %.2f %% | %.1f %% | %.3g | %s | %s |\n",
                  c["roots"].get<int>(), c["grid"].get<int>(), b["evaluations"].get<int>(),
                  Fmt(c["dense"]["seconds_per_evaluation"].get<double>()).c_str(),
                  b["seconds_per_evaluation"].get<double>(), (Fmt(c["speedup"].get<double>()) + "×").c_str(),
                  b["anchors"].get<long long>(), b["far_sweeps"].get<long long>() + b["dense_fallbacks"].get<long long>(),
                  100.0 * b["mean_fraction"].get<double>(), 100.0 * b["max_cells"].get<double>() / c["cells"].get<double>(),
                  100.0 * b["work_fraction"].get<double>(),
                  b["first_evaluation_seconds"].get<double>(), storage.c_str(),
                  c["identical"].get<bool>() ? "identical" : "DIFFERENT");
    md += line;
  }
  return md;
}

}  // namespace

void AddBenchBandCommand(CLI::App& bench) {
  auto a = std::make_shared<BandArgs>();
  CLI::App* b = bench.add_subcommand(
      "band", "Dense log-linear evaluator against its narrow band: seconds per evaluation during an F pass on a "
              "fitted map, at fine levels");
  b->add_option("--roots", a->roots, "Root counts of the random maps (paper splits for 331, 708)")->capture_default_str();
  b->add_option("--grids", a->grids, "Levels N (N^3 cells)")->capture_default_str();
  b->add_option("--iterations", a->iterations, "L-BFGS iterations timed per case")->capture_default_str()
      ->check(CLI::Range(1, 100000));
  b->add_option("--form-iterations", a->form_iterations, "F iterations at 25^3 that fit the random map first (a third at 50^3)")
      ->capture_default_str()->check(CLI::Range(0, 100000));
  b->add_option("--dense-evaluations", a->dense_evaluations,
                "Evaluations that time the dense evaluator where its matrix is not stored")
      ->capture_default_str()->check(CLI::Range(1, 1000));
  b->add_option("--target", a->target, "Target: analytic shape or .qgrid")->capture_default_str();
  b->add_option("--map", a->map_path, "A fitted map (map.json) instead of the random ones (--roots is then ignored)");
  b->add_option("--memory-budget", a->memory_budget_gb, "GB the dense matrix may take")->capture_default_str()
      ->check(CLI::Range(0.0, 1.0e6));
  b->add_option("--seed", a->seed, "Seed of the random maps")->capture_default_str();
  b->add_option("--json", a->out_json, "Write the results as JSON here")->capture_default_str();
  b->add_option("--markdown", a->out_md, "Write the Markdown table here")->capture_default_str();
  b->callback([a] {
    const json cases = RunBand(*a);
    const std::string md = Markdown(cases);
    if (!a->out_json.empty()) WriteOutput(a->out_json, json{{"cases", cases}}.dump(1) + "\n");
    if (!a->out_md.empty()) WriteOutput(a->out_md, md);
    std::fputs(md.c_str(), stdout);
  });
}

}  // namespace quijibo::cli
