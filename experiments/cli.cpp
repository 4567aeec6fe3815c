#include "experiments/cli.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <sstream>

#include "mesh/sdf_command.h"
#include "quijibo/cached_energy.h"
#include "quijibo/error.h"
#include "quijibo/frame.h"
#include "quijibo/io.h"
#include "quijibo/target.h"

namespace quijibo::cli {

using nlohmann::json;

ScalarGrid LoadTarget(const std::string& spec, int resolution) {
  const bool looks_like_file = spec.find('/') != std::string::npos ||
                               spec.ends_with(".qgrid") || std::filesystem::exists(spec);
  if (looks_like_file) return ReadGrid(spec);
  if (resolution < 2 || resolution > 2048)
    throw Error("--target-resolution must be in [2, 2048], found " + std::to_string(resolution));
  return AnalyticTarget(spec, TargetGridFrame(resolution, FractalFrame{}));
}

void WriteOutput(const std::string& path, const std::string& text) {
  if (path.empty() || path == "-") {
    std::fwrite(text.data(), 1, text.size(), stdout);
    std::fflush(stdout);
  } else {
    CreateParentFolder(path);
    WriteFileAtomically(path, text);
  }
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
json Report(const RationalMap& map, const Evaluation<Real>& ev, const std::vector<double>& seconds) {
  json r;
  r["energy"] = ToDouble(ev.energy);
  r["energy_exact"] = Exact(ev.energy);
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

}  // namespace

json EvaluateEnergy(const RationalMap& map, const EnergyGrid& grid, const EnergyOptions& options,
                    const EvaluatorChoice& choice) {
  if (choice.repeats < 1) throw Error("--repeats must be >= 1");
  json out;
  const Eigen::VectorXd x = map.variables();
  std::vector<double> seconds;
  if (choice.evaluator == "loglinear") {
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
    out = Report(map, ev, seconds);
    out["setup_seconds"] = energy.setup_seconds() + pass_seconds;
    out["storage"] = StorageName(energy.storage());
    out["matrix_bytes"] = energy.matrix_bytes();
  } else if (choice.evaluator == "cached") {
    out = DispatchPrecision(choice.precision, [&]<class Real>() {
      const CachedEnergy<Real> energy(map, grid, options);
      const Eigen::Matrix<Real, -1, 1> xr = x.cast<Real>();
      Evaluation<Real> ev;
      for (int k = 0; k < choice.repeats; ++k) {
        ev = energy.Evaluate(xr, choice.mode, choice.gradient);
        seconds.push_back(ev.seconds);
      }
      return Report(map, ev, seconds);
    });
    out["setup_seconds"] = 0.0;
  } else {
    throw Error("unknown evaluator \"" + choice.evaluator + "\": expected loglinear or cached");
  }
  out["evaluator"] = choice.evaluator;
  out["precision"] = PrecisionName(choice.precision);
  out["mode"] = choice.mode == EnergyMode::kFull ? "full" : "variable";
  out["alpha"] = options.alpha;
  out["grid"] = {{"dims", grid.frame.dims}, {"spacing", grid.frame.spacing},
                 {"min_corner", grid.frame.min_corner}, {"slice", grid.slice}, {"eta", grid.eta}};
  out["roots"] = {{"top", map.top_count()}, {"bottom", map.bottom_count()}};
  return out;
}

void AddEnergyCommand(CLI::App& app) {
  struct Args {
    std::string target, map_path, out, weights = WeightFieldName(kDefaultWeightField), level_weights = "sample",
        evaluator = EvaluatorChoice{}.evaluator, precision = "double", storage = "auto", mode = "full";
    int resolution = 0, target_resolution = 97, repeats = 1;
    double alpha = 10.0, slice = 0.0;
    bool no_gradient = false;
  };
  auto a = std::make_shared<Args>();
  CLI::App* c = app.add_subcommand(
      "energy",
      "Evaluate the QUIJIBO energy psi (2015 paper Eqns 5-8) of a map on a target, with its gradient "
      "and diagnostics, as JSON");
  c->add_option("-t,--target", a->target,
                "Target: a .qgrid signed distance file, or sphere[:radius=R] / torus[:major=R,minor=r]")
      ->required();
  c->add_option("-m,--map", a->map_path, "The map (map.json)")->required()->check(CLI::ExistingFile);
  c->add_option("-e,--evaluator", a->evaluator, "loglinear (exact, double) or cached (the paper's)")
      ->capture_default_str()
      ->check(CLI::IsMember({"loglinear", "cached"}));
  c->add_option("-p,--precision", a->precision, "float, double, long-double or float128 (cached only)")
      ->capture_default_str()
      ->check(CLI::IsMember({"float", "double", "long-double", "float128"}));
  c->add_option("-w,--weights", a->weights,
                "Weight field: balanced (the optimizer's), layer (reference code) or inverse (paper, 1/phi)")
      ->capture_default_str()
      ->check(CLI::IsMember({"layer", "inverse", "balanced"}));
  c->add_option("-r,--resolution", a->resolution,
                "Level resolution N (cells along the longest axis); 0 = the target's own grid")
      ->capture_default_str()
      ->check(CLI::Range(0, 4096));
  c->add_option("--level-weights", a->level_weights,
                "Coarse-level weights: sample (the finest W, as the reference) or recompute")
      ->capture_default_str()
      ->check(CLI::IsMember({"sample", "recompute"}));
  c->add_option("--target-resolution", a->target_resolution, "Grid of an analytic target")
      ->capture_default_str();
  c->add_option("--alpha", a->alpha, "Sharpness of tanh")->capture_default_str();
  c->add_option("--slice", a->slice, "k component S of the sample quaternions [x, y, z, S]")
      ->capture_default_str();
  c->add_option("--storage", a->storage, "loglinear log-distance storage: auto, double, float, on-the-fly")
      ->capture_default_str()
      ->check(CLI::IsMember({"auto", "double", "float", "on-the-fly"}));
  c->add_option("--mode", a->mode, "full (all R+3 variables) or variable (V pass: ln C, tau, beta)")
      ->capture_default_str()
      ->check(CLI::IsMember({"full", "variable"}));
  c->add_flag("--no-gradient", a->no_gradient, "Energy only");
  c->add_option("--repeats", a->repeats, "Evaluate this many times (timings of each reported)")
      ->capture_default_str()
      ->check(CLI::Range(1, 1000));
  c->add_option("-o,--out", a->out, "Write the JSON report here (default: stdout)");
  c->callback([a] {
    const RationalMap map = ReadMap(a->map_path);
    mesh::CheckSameFrame(map.frame, a->map_path, a->target);
    const ScalarGrid sdf = LoadTarget(a->target, a->target_resolution);
    EnergyOptions options;
    options.alpha = a->alpha;
    const EnergyGrid grid =
        MakeEnergyGrid(sdf, ParseWeightField(a->weights), a->resolution,
                       a->level_weights == "sample" ? LevelWeights::kSampleFinest : LevelWeights::kRecompute,
                       a->slice);
    EvaluatorChoice choice;
    choice.evaluator = a->evaluator;
    choice.precision = ParsePrecision(a->precision);
    choice.storage = ParseStorage(a->storage);
    choice.mode = a->mode == "full" ? EnergyMode::kFull : EnergyMode::kVariable;
    choice.gradient = !a->no_gradient;
    choice.repeats = a->repeats;
    json report = EvaluateEnergy(map, grid, options, choice);
    report["target"] = a->target;
    report["map"] = a->map_path;
    report["weights"] = a->weights;
    if (report["overflowed_cells"].get<long long>() > 0)
      std::fprintf(stderr, "quijibo: warning: %lld cells overflowed in %s and were left out\n",
                   report["overflowed_cells"].get<long long>(), a->precision.c_str());
    WriteOutput(a->out, report.dump(1) + "\n");
  });
}

void AddMapCommand(CLI::App& app) {
  CLI::App* m = app.add_subcommand("map", "Make or inspect rational maps (map.json)");
  m->require_subcommand(1);
  auto o = std::make_shared<RandomMapOptions>();
  auto out = std::make_shared<std::string>();
  auto target = std::make_shared<std::string>();
  auto target_res = std::make_shared<int>(25);
  CLI::App* r = m->add_subcommand("random", "A seeded random map (roots uniform in a ball, k = 0)");
  r->add_option("--top", o->top, "Number of top roots")->capture_default_str()->check(CLI::Range(0, 100000));
  r->add_option("--bottom", o->bottom, "Number of bottom roots")->capture_default_str()->check(CLI::Range(0, 100000));
  r->add_option("--root-radius", o->root_radius, "Radius of the ball holding the roots")->capture_default_str();
  r->add_option("--exponent-min", o->exponent_min, "Smallest exponent")->capture_default_str();
  r->add_option("--exponent-max", o->exponent_max, "Largest exponent")->capture_default_str();
  r->add_option("--ln-C", o->ln_C, "ln C (unless --center-on is given)")->capture_default_str();
  r->add_flag("--leading-zero-roots", o->leading_zero_roots,
              "Prepend the reference code's zero roots (exponent 1) to top and bottom");
  r->add_option("--seed", o->seed, "Random seed")->capture_default_str();
  r->add_option("--center-on", *target,
                "Set ln C so that the median of L on this target's grid is 0 (a target as in `energy`)");
  r->add_option("--target-resolution", *target_res, "Grid of an analytic --center-on target")->capture_default_str();
  r->add_option("-o,--out", *out, "Output map.json")->required();
  r->callback([o, out, target, target_res] {
    RationalMap map = RandomMap(*o);
    if (!target->empty()) {
      const EnergyGrid grid = MakeEnergyGrid(LoadTarget(*target, *target_res), WeightField::kLayer);
      map.ln_C = -MedianLogModulus(map, grid);
    }
    CreateParentFolder(*out);
    WriteMap(*out, map);
  });
  auto path = std::make_shared<std::string>();
  CLI::App* info = m->add_subcommand("info", "Check a map.json and summarize it as JSON");
  info->add_option("map", *path, "The map")->required()->check(CLI::ExistingFile);
  info->callback([path] {
    const RationalMap map = ReadMap(*path);
    double tmax = 0, bmax = 0;
    for (double e : map.top_exponents) tmax = std::max(tmax, e);
    for (double e : map.bottom_exponents) bmax = std::max(bmax, e);
    json j = {{"map", *path}, {"top_roots", map.top_count()}, {"bottom_roots", map.bottom_count()},
              {"variables", map.variable_count()}, {"ln_C", map.ln_C}, {"tau", map.tau}, {"beta", map.beta},
              {"largest_top_exponent", tmax}, {"largest_bottom_exponent", bmax},
              {"leading_zero_roots", map.leading_zero_roots},
              {"fractal_radius", map.frame.fractal_radius}};
    WriteOutput("", j.dump(1) + "\n");
  });
}

void AddTargetCommand(CLI::App& app) {
  auto shape = std::make_shared<std::string>();
  auto out = std::make_shared<std::string>();
  auto res = std::make_shared<int>(97);
  CLI::App* t = app.add_subcommand("target", "Write an analytic target (signed distance) as a .qgrid file");
  t->add_option("shape", *shape, "sphere[:radius=R] or torus[:major=R,minor=r]")->required();
  t->add_option("-r,--resolution", *res, "Cells per axis")->capture_default_str()->check(CLI::Range(2, 2048));
  t->add_option("-o,--out", *out, "Output .qgrid")->required();
  t->callback([shape, out, res] {
    const ScalarGrid grid = LoadTarget(*shape, *res);
    CreateParentFolder(*out);
    WriteGrid(*out, grid);
  });
}

}  // namespace quijibo::cli
