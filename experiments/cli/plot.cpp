// `quijibo plot`: the plot stage (experiments/pipeline/plot.h) on the command line.
#include "experiments/cli/bind.h"
#include "experiments/cli/cli.h"
#include "experiments/pipeline/plot.h"

namespace quijibo::cli {

void AddPlotCommand(CLI::App& app) {
  auto o = std::make_shared<pipeline::PlotOptions>();
  CLI::App* c = app.add_subcommand(
      "plot",
      "Convergence plot of optimizer logs (log.jsonl) like Fig. 11 of the 2015 paper, as PREFIX.png and "
      "PREFIX.svg (needs gnuplot)");
  c->footer(
      "y is (psi + 1) / 2 on a log axis, x the optimization step. Each log gives its relative energy (line; "
      "broken at pass starts, since each level has its own grid and weights) and its absolute energy "
      "(finest grid, original weights: dashed line with points). Pass starts are dashed vertical lines "
      "labelled \"<level> <pass>\"; with several logs, only the first log's are drawn. An unparsable last "
      "line (a killed run) is skipped with a warning.");
  c->add_option("logs", o->logs, "Optimizer logs (log.jsonl), one curve pair each")
      ->required()
      ->check(CLI::ExistingFile);
  c->add_option("-o,--out", o->out, "Output prefix: writes PREFIX.png and PREFIX.svg")->required();
  c->add_option("--label", o->labels,
                "Legend name of each log, in order (repeat the option; default: the run's \"label\", "
                "else the file's stem, or its folder's name for log.jsonl)")
      ->allow_extra_args(false);
  c->add_option("--title", o->title, "Plot title (default: QUIJIBO convergence[: label (backend, ...)])");
  BindSettings(c, *o);
  c->callback([o] { pipeline::Plot(*o); });
}

}  // namespace quijibo::cli
