#include "experiments/cli/cli.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <sstream>

#include "experiments/cli/bind.h"
#include "experiments/pipeline/energy.h"
#include "experiments/pipeline/target.h"
#include "mesh/frame_file.h"
#include "util/error.h"
#include "quijibo/frame.h"
#include "util/io.h"
#include "util/progress.h"
#include "quijibo/target.h"

namespace quijibo::cli {

using nlohmann::json;

ScalarGrid LoadTarget(const std::string& spec, int resolution) {
  const bool looks_like_file = spec.find('/') != std::string::npos ||
                               spec.ends_with(".qgrid") || std::filesystem::exists(spec);
  pipeline::TargetOptions o;
  if (looks_like_file) {
    o.qgrid = spec;
  } else {
    if (auto why = CheckRange("--target-resolution", SettingType::kInteger, resolution, kTargetResolutionRange);
        !why.empty())
      throw Error(why);
    o.analytic = spec;
    o.resolution = resolution;
  }
  return pipeline::Target(o).grid;  // the run's target stage, so both read a target the same way
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

void AddEnergyCommand(CLI::App& app) {
  struct Args {
    std::string target, map_path, out;
    int target_resolution = kDefaultTargetResolution;
    pipeline::EnergyStageOptions o;
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
  BindSettings(c, a->o);
  AddTargetResolution(c, a->target_resolution, "--target-resolution", "Grid of an analytic target");
  c->add_option("-o,--out", a->out, "Write the JSON report here (default: stdout)");
  c->callback([a] {
    const RationalMap map = ReadMap(a->map_path);
    mesh::CheckSameFrame(map.frame, a->map_path, a->target);
    const ScalarGrid sdf = LoadTarget(a->target, a->target_resolution);
    json report = pipeline::EnergyStage(map, sdf, a->o);
    report["target"] = a->target;
    report["map"] = a->map_path;
    if (report["overflowed_cells"].get<long long>() > 0)
      std::fprintf(stderr, "quijibo: warning: %lld cells overflowed in %s and were left out\n",
                   report["overflowed_cells"].get<long long>(), PrecisionName(a->o.precision).c_str());
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
  AddTargetResolution(r, *target_res, "--target-resolution", "Grid of an analytic --center-on target");
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
  auto res = std::make_shared<int>(kDefaultTargetResolution);
  CLI::App* t = app.add_subcommand("target", "Write an analytic target (signed distance) as a .qgrid file");
  t->add_option("shape", *shape, "sphere[:radius=R] or torus[:major=R,minor=r]")->required();
  AddTargetResolution(t, *res, "-r,--resolution", "Cells per axis");
  t->add_option("-o,--out", *out, "Output .qgrid")->required();
  t->callback([shape, out, res] {
    const ScalarGrid grid = LoadTarget(*shape, *res);
    CreateParentFolder(*out);
    WriteGrid(*out, grid);
  });
}

void SetUpApp(CLI::App& app, const std::string& name, bool& quiet, bool silent) {
  app.set_version_flag("--version", name + " " QUIJIBO_VERSION);
  app.require_subcommand(1);
  app.add_flag("-q,--quiet", quiet, "No progress on stderr");
  app.parse_complete_callback([&quiet, silent] { Progress::globally_quiet() = quiet || silent; });
}

}  // namespace quijibo::cli
