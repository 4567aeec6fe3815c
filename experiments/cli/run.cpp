// `quijibo run EXPERIMENT.json [--out DIR] [--resume] [--check]`: the experiment read and validated
// completely before anything is written (pipeline::Experiment), then run as a list of stage calls
// (pipeline::RunExperiment; docs/experiments.md).
#include <cstdio>

#include "experiments/cli/cli.h"
#include "experiments/pipeline/report_html.h"
#include "experiments/pipeline/run.h"
#include "util/error.h"
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

void AddReportHtmlCommand(CLI::App& app) {
  struct Args {
    std::string results;
    std::vector<std::string> meshes;
    bool only = false;
    pipeline::ReportHtmlOptions html;
  };
  auto a = std::make_shared<Args>();
  CLI::App* c = app.add_subcommand(
      "report-html", "Write RESULTS/report.html: report.md as one self-contained page with a 3D viewer (orbit, "
                     "zoom) of the run's meshes (target, Julia set, intricate surface, ...) decimated to a browser's "
                     "budget; `quijibo run` writes it too (outputs.report_html)");
  c->add_option("results", a->results, "The results folder (with report.md)")->required()->check(CLI::ExistingDirectory);
  c->add_option("--mesh", a->meshes, "Also show this mesh: NAME=PATH (repeatable)");
  c->add_flag("--only", a->only, "Show only the --mesh meshes, not the run's");
  c->add_option("--max-triangles", a->html.max_triangles_per_mesh, "Triangles per mesh at most")
      ->capture_default_str()
      ->check(CLI::Range(std::int64_t(1), std::int64_t(1) << 31));
  c->add_option("--max-total", a->html.max_triangles_total, "Triangles of all meshes at most")
      ->capture_default_str()
      ->check(CLI::Range(std::int64_t(1), std::int64_t(1) << 31));
  c->callback([a] {
    std::vector<pipeline::ViewerMesh> meshes;
    if (!a->only) meshes = pipeline::RunMeshes(a->results);
    for (const std::string& m : a->meshes) {
      const std::size_t eq = m.find('=');
      if (eq == std::string::npos || eq == 0 || eq + 1 == m.size())
        throw Error("--mesh " + m + ": expected NAME=PATH");
      meshes.push_back({m.substr(0, eq), m.substr(0, eq), m.substr(eq + 1)});
    }
    const pipeline::ReportHtmlSummary s = pipeline::WriteReportHtml(a->results, meshes, a->html);
    std::printf("%s: %.1f MB", s.path.c_str(), double(s.bytes) / 1e6);
    for (const auto& m : s.meshes)
      std::printf(", %s %lld of %lld triangles", m.name.c_str(), (long long)m.triangles_out, (long long)m.triangles_in);
    std::printf("%s\n", s.viewer ? "" : " (no 3D viewer: its script was not found)");
  });
}

}  // namespace quijibo::cli
