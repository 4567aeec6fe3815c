#include "experiments/pipeline/energy.h"

#include <algorithm>
#include <chrono>
#include <limits>
#include <sstream>
#include <vector>

#include "optim/optimizer.h"
#include "quijibo/cached_energy.h"
#include "util/error.h"

namespace quijibo::pipeline {

using nlohmann::json;

const Schema<EnergyStageOptions>& EnergyStageOptions::Settings() {
  using O = EnergyStageOptions;
  static const Schema<O> s =
      Schema<O>()
          .With(optim::AlphaSetting([](auto& o) -> double& { return o.energy.alpha; }))
          .Choice("evaluator", "-e,--evaluator", "loglinear (exact, double; also: dense) or cached (the paper's)",
                  [](auto& o) -> std::string& { return o.evaluator; }, {"loglinear", "dense", "cached"})
          .With(optim::PrecisionSetting([](auto& o) -> Precision& { return o.precision; }))
          .With(optim::StorageSetting([](auto& o) -> LogLinearOptions::Storage& { return o.storage; }))
          .With(optim::WeightsSetting([](auto& o) -> WeightField& { return o.weights; }))
          .Integer(
              "resolution", "-r,--resolution",
              "Level resolution N (cells along the longest axis); 0 = the target's own grid",
              [](auto& o) -> int& { return o.resolution; }, 0, 4096)
          .With(optim::LevelWeightsSetting([](auto& o) -> LevelWeights& { return o.level_weights; }))
          .Number(
              "slice", "--slice", "k component S of the sample quaternions [x, y, z, S]",
              [](auto& o) -> double& { return o.slice; }, -std::numeric_limits<double>::infinity(),
              std::numeric_limits<double>::infinity())
          .Enum(
              "mode", "--mode", "full (all R+3 variables) or variable (V pass: ln C, tau, beta)", {"full", "variable"},
              [](const O& o) { return std::string(o.mode == EnergyMode::kFull ? "full" : "variable"); },
              [](O& o, const std::string& v) { o.mode = v == "full" ? EnergyMode::kFull : EnergyMode::kVariable; })
          .Boolean("gradient", "--no-gradient", "Energy only", [](auto& o) -> bool& { return o.gradient; })
          .Integer(
              "repeats", "--repeats", "Evaluate this many times (timings of each reported)",
              [](auto& o) -> int& { return o.repeats; }, 1, 1000);
  return s;
}

EnergyStageOptions EnergyStageOptions::FromJson(const JsonReader& r, const std::string& p,
                                                const std::filesystem::path& base) {
  return Settings().FromJson(r, p, base);
}

namespace {

template <class Real>
std::string Exact(const Real& x) {
  std::ostringstream s;
  s.precision(std::numeric_limits<Real>::max_digits10);
  s << x;
  return s.str();
}

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n == 0 ? 0.0 : (n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]));
}

template <class Real>
json Report(const RationalMap& map, const Evaluation<Real>& ev, const std::vector<double>& seconds, double trivial) {
  json r;
  // psi counted from the better trivial set (TrivialSetEnergy, quijibo/energy.h); 0 for layer and inverse.
  const Real psi = trivial == 0 ? ev.energy : Real(ev.energy - Real(trivial));
  r["energy"] = ToDouble(psi);
  r["energy_exact"] = Exact(psi);
  r["trivial_set_energy"] = trivial;
  if (ev.gradient.size() > 0) {
    json g, exact = json::array();
    g["ln_C"] = ToDouble(ev.gradient[0]);
    g["tau"] = ToDouble(ev.gradient[1]);
    g["beta"] = ToDouble(ev.gradient[2]);
    if (ev.gradient.size() > 3) {
      json top = json::array(), bottom = json::array();
      for (int i = 0; i < map.top_count(); ++i) top.push_back(ToDouble(ev.gradient[VariableIndex::top(i)]));
      for (int i = 0; i < map.bottom_count(); ++i)
        bottom.push_back(ToDouble(ev.gradient[VariableIndex::bottom(map, i)]));
      g["top"] = top;
      g["bottom"] = bottom;
    }
    for (Eigen::Index k = 0; k < ev.gradient.size(); ++k) exact.push_back(Exact(ev.gradient[k]));
    r["gradient"] = g;
    r["gradient_exact"] = exact;
  }
  r["cells"] = ev.counts.cells;
  r["singular_cells"] = ev.counts.singular;
  r["overflowed_cells"] = ev.counts.overflowed;
  r["seconds"] = seconds;
  r["median_seconds"] = Median(seconds);
  return r;
}

// EnergyStage's evaluations on a level grid already made: the report but its weights (`weights`
// is not read; the grid's are the caller's).
json EvaluateEnergy(const RationalMap& map, const EnergyGrid& grid, const EnergyStageOptions& choice) {
  if (auto why = EnergyStageOptions::Settings().Check(choice); !why.empty()) throw Error("energy: " + why);
  const EnergyOptions& options = choice.energy;
  const std::string evaluator = choice.evaluator == "dense" ? "loglinear" : choice.evaluator;
  json out;
  const double trivial = TrivialSetEnergy({&grid});
  const Eigen::VectorXd x = map.variables();
  std::vector<double> seconds;
  if (evaluator == "loglinear") {
    if (choice.precision != Precision::kDouble)
      throw Error("the loglinear evaluator runs in double only (it needs no more); use "
                  "--evaluator cached for the other precisions");
    LogLinearOptions lo;
    lo.storage = choice.storage;
    LogLinearEnergy energy(map, grid, options, lo);
    const auto setup = std::chrono::steady_clock::now();
    if (choice.mode == EnergyMode::kVariable) energy.BeginVariablePass(x);
    const double pass_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - setup).count();
    Evaluation<double> ev;
    for (int k = 0; k < choice.repeats; ++k) {
      ev = energy.Evaluate(x, choice.mode, choice.gradient);
      seconds.push_back(ev.seconds);
    }
    out = Report(map, ev, seconds, trivial);
    out["setup_seconds"] = energy.setup_seconds() + pass_seconds;
    out["storage"] = StorageName(energy.storage());
    out["matrix_bytes"] = energy.matrix_bytes();
  } else {
    out = DispatchPrecision(choice.precision, [&]<class Real>() {
      const CachedEnergy<Real> energy(map, grid, options);
      const Eigen::Matrix<Real, -1, 1> xr = x.cast<Real>();
      Evaluation<Real> ev;
      for (int k = 0; k < choice.repeats; ++k) {
        ev = energy.Evaluate(xr, choice.mode, choice.gradient);
        seconds.push_back(ev.seconds);
      }
      return Report(map, ev, seconds, trivial);
    });
    out["setup_seconds"] = 0.0;
  }
  out["evaluator"] = evaluator;
  out["precision"] = PrecisionName(choice.precision);
  out["mode"] = choice.mode == EnergyMode::kFull ? "full" : "variable";
  out["alpha"] = options.alpha;
  out["grid"] = {{"dims", grid.frame.dims}, {"spacing", grid.frame.spacing},
                 {"min_corner", grid.frame.min_corner}, {"slice", grid.slice}, {"eta", grid.eta}};
  out["roots"] = {{"top", map.top_count()}, {"bottom", map.bottom_count()}};
  return out;
}

}  // namespace

json EnergyStage(const RationalMap& map, const ScalarGrid& target, const EnergyStageOptions& options) {
  const EnergyGrid grid = MakeEnergyGrid(target, options.weights, options.resolution, options.level_weights,
                                         options.slice);
  json report = EvaluateEnergy(map, grid, options);
  report["weights"] = WeightFieldName(options.weights);
  return report;
}

}  // namespace quijibo::pipeline
