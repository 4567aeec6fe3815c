// Every subcommand of `quijibo` on one app (main.cpp, and the tests that compare the command line's
// options with the schemas), and `quijibo settings`: the schemas themselves.
#include "experiments/cli/cli.h"
#include "experiments/pipeline/experiment.h"

namespace quijibo::cli {

namespace {

void AddSettingsCommand(CLI::App& app) {
  auto out = std::make_shared<std::string>();
  CLI::App* c = app.add_subcommand(
      "settings",
      "Every setting of an experiment by section, as JSON: key, flag, help, type, default, range, choices (the one "
      "definition `run`, the subcommands and the Python module read)");
  c->add_option("-o,--out", *out, "Write the JSON here (default: stdout)");
  c->callback([out] { WriteOutput(*out, pipeline::DescribeSettings().dump(1) + "\n"); });
}

}  // namespace

void AddCommands(CLI::App& app) {
  AddEnergyCommand(app);
  AddMapCommand(app);
  AddTargetCommand(app);
  CLI::App* bench = app.add_subcommand("bench", "Benchmarks (results go to docs/benchmarks.md)");
  bench->require_subcommand(1);
  AddBenchPrecisionCommands(*bench);
  AddOptimizeCommand(app);
  AddPlotCommand(app);
  AddTargetAndStartCommands(app, *bench);
  AddModulusCommands(app, *bench);
  AddJuliaCommands(app, *bench);
  AddShapeCommands(app, *bench);
  AddBenchBandCommand(*bench);
  AddRunCommand(app);
  AddFilmCommand(app);
  AddReportHtmlCommand(app);
  AddSettingsCommand(app);
}

}  // namespace quijibo::cli
