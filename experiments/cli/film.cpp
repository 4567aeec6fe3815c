// `quijibo film FILM.json [-o DIR]` or `quijibo film --map MAP --vary SETTING --to V ... -o DIR`: the
// parameter space as a film (pipeline::MakeFilm, experiments/pipeline/film.h).
#include <cstdio>

#include "experiments/cli/bind.h"
#include "experiments/cli/cli.h"
#include "experiments/pipeline/film.h"
#include "util/error.h"
#include "util/progress.h"

namespace quijibo::cli {

void AddFilmCommand(CLI::App& app) {
  struct Args {
    std::string file, out;
    pipeline::FilmOptions film;
  };
  auto a = std::make_shared<Args>();
  CLI::App* c = app.add_subcommand(
      "film",
      "A film of the parameter space: one setting of the iterated map (translate_potential, translation, detail, "
      "iterations, a root's position or exponent) moves over the frames; each frame meshed and ray-traced alike; "
      "numbered PNG frames and film.mp4; a rerun redoes only missing frames (docs/meshing.md \"Films\")");
  c->add_option("film", a->file, "A film file (.json; docs/meshing.md \"Films\"); or give --map and the flags");
  c->add_option("-o,--out", a->out, "Output folder (default with a film file: results/<name>)");
  BindSettings(c, a->film);
  BindSettings(c, a->film.mesh, {"resolution", "iterations", "escape", "detail", "iteration_frame", "translate"});
  c->callback([a, c] {
    pipeline::FilmOptions o = a->film;
    if (!a->file.empty()) {
      for (const CLI::Option* opt : c->get_options())
        if (opt->count() > 0 && opt->get_name() != "film" && opt->get_name() != "--out" && opt->get_name() != "--quiet" &&
            opt->get_name() != "--help")
          throw Error("film: " + opt->get_name() + ": give the settings in the film file or as flags, not both");
      o = pipeline::FilmOptions::FromFile(a->file);
    } else {
      if (a->out.empty()) throw Error("film: -o/--out is required without a film file");
      if (std::string why = o.Validate(); !why.empty()) throw Error("film: " + why);
    }
    const std::string out = !a->out.empty() ? a->out : "results/" + o.name;
    const pipeline::FilmSummary s = pipeline::MakeFilm(o, out, Progress::globally_quiet());
    if (!Progress::globally_quiet()) std::fprintf(stderr, "%s", s.Report().c_str());
    std::printf("%s\n", s.ToJson().dump(1).c_str());
  });
}

}  // namespace quijibo::cli
