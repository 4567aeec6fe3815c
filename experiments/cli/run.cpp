// `quijibo run EXPERIMENT.json [--out DIR] [--resume] [--check]`: the experiment read and validated
// completely before anything is written (pipeline::Experiment), then run as a list of stage calls
// (pipeline::RunExperiment; docs/experiments.md).
#include <cstdio>

#include "experiments/cli/cli.h"
#include "experiments/pipeline/run.h"
#include "util/progress.h"

namespace quijibo::cli {

void AddRunCommand(CLI::App& app) {
  struct Args {
    std::string experiment;
    pipeline::RunOptions run;
  };
  auto a = std::make_shared<Args>();
  CLI::App* c = app.add_subcommand(
      "run", "Run a JSON experiment end to end (docs/experiments.md): initial guess, optimization, plot, mesh, "
             "pictures, fidelity and report.md (INCOMPLETE until the run ends; its Quality section warns where the "
             "result is not the shape) in a results folder; unchanged stages are reused");
  c->add_option("experiment", a->experiment, "The experiment (.json)")->required();
  c->add_option("-o,--out", a->run.out_dir, "Results folder (default: outputs.folder, else results/<name>)");
  c->add_flag("--resume", a->run.resume, "Continue an interrupted optimization from its checkpoint");
  c->add_flag("-q,--quiet", a->run.quiet, "No progress on stderr");
  c->add_flag("--check", a->run.check_only,
              "Only validate: print the resolved experiment (every default filled in) and exit");
  c->callback([a] {
    if (a->run.quiet) Progress::globally_quiet() = true;
    a->run.quiet = Progress::globally_quiet();
    a->run.handle_signals = true;
    const pipeline::Experiment e = pipeline::Experiment::FromFile(a->experiment);
    const pipeline::RunSummary s = pipeline::RunExperiment(e, a->run);
    if (a->run.check_only) std::printf("%s\n", s.resolved.dump(2).c_str());
  });
}

}  // namespace quijibo::cli
