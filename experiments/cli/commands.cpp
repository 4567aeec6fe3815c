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
  AddBenchCommand(app);
  AddOptimizeCommand(app);
  AddPlotCommand(app);
  AddModuleCommands(app);
  AddModulusCommands(app);
  AddJuliaCommands(app);
  AddShapeCommands(app);
  AddBenchBandCommand(app);
  AddRunCommand(app);
  AddSettingsCommand(app);
}

}  // namespace quijibo::cli
