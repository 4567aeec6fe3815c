#include "experiments/pipeline/report.h"

#include <ctime>
#include <filesystem>
#include <sstream>

#include "experiments/pipeline/quality.h"
#include "experiments/pipeline/run.h"
#include "experiments/pipeline/triptych.h"
#include "util/io.h"
#include "quijibo/rational_map.h"

namespace quijibo::pipeline {

using nlohmann::json;
namespace fs = std::filesystem;

namespace {

// report.md while it is written: the results folder's files and the page so far.
struct Page {
  std::string results;
  std::ostringstream md;
  std::string Path(const std::string& rel) const { return results + "/" + rel; }
  bool Exists(const std::string& rel) const { return fs::exists(Path(rel)); }
  // An image with its caption, when a stage wrote it.
  void Image(const std::string& rel, const std::string& caption) {
    if (Exists(rel)) md << "![" << caption << "](" << rel << ")\n\n*" << caption << "* (`" << rel << "`)\n\n";
  }
};

// The initial guess: the log-kernel fit's or the monopoles' figures, else the map's roots; its pictures.
void InitialSection(Page& page) {
  std::ostringstream& md = page.md;
  const json monopoles = ReadStageFile(page.Path("initial/monopoles.json"));
  if (monopoles.is_object() && monopoles.value("initializer", "") == "log-kernel") {
    const json& st = monopoles["start"];
    md << "## Initial guess (log-kernel fit)\n\n| mesh triangles | roots (top/bottom) | ln C | median L inside / "
          "outside | "
          "one-step IoU on the target grid | inverted |\n|---|---|---|---|---|---|\n| "
       << monopoles.value("triangles", 0) << " | " << monopoles.value("top_roots", 0) << "/"
       << monopoles.value("bottom_roots", 0) << " | " << Fixed(monopoles.value("ln_C", 0.0), 3) << " | "
       << Fixed(st.value("median_L_inside", 0.0), 3) << " / " << Fixed(st.value("median_L_outside", 0.0), 3) << " | "
       << Fixed(st.value("iou", 0.0), 3) << " | " << (st.value("inverted", false) ? "**yes**" : "no") << " |\n\n";
  } else if (monopoles.is_object()) {
    md << "## Initial guess\n\n| mesh triangles | monopoles (top/bottom) | relative residual | BEM elements | ln C |\n"
          "|---|---|---|---|---|\n| "
       << monopoles.value("triangles", 0) << " | " << monopoles.value("monopoles", 0) << " ("
       << monopoles.value("top_roots", 0) << "/" << monopoles.value("bottom_roots", 0) << " roots"
       << (monopoles.value("zero_exponent_roots", 0) > 0
               ? ", " + std::to_string(monopoles.value("zero_exponent_roots", 0)) + " of them at exponent 0"
               : std::string())
       << ") | "
       << Fixed(monopoles.value("relative_residual", 0.0), 4) << " | " << monopoles.value("bem_elements", 0) << " | "
       << Fixed(monopoles.value("ln_C", 0.0), 3) << " |\n\n";
    const int hollow = monopoles.value("hollow_roots", 0), attract = monopoles.value("attract_roots", 0);
    if (hollow + attract > 0) {
      md << hollow << " hollow roots (bottom, outside where the start spills) and " << attract
         << " attract roots (top, inside where it falls short)";
      const json scan = monopoles.value("offset_scan", json());
      if (scan.is_object() && scan.value("iou", 0.0) > 0)
        md << ", starting at the common exponent " << Fixed(scan.value("exponent", 0.0), 4)
           << ": the start's one-step IoU on the target grid "
           << Fixed(scan.value("iou_before", 0.0), 3) << " at exponent 0, " << Fixed(scan.value("iou", 0.0), 3)
           << " (`offset_scan`)";
      md << ".\n\n";
    }
  } else if (page.Exists("initial/map.json")) {
    const RationalMap map = ReadMap(page.Path("initial/map.json"));
    md << "## Initial map\n\n"
       << map.top_count() << " top and " << map.bottom_count() << " bottom roots, ln C = " << Fixed(map.ln_C, 3)
       << ".\n\n";
  }
  page.Image("initial/potential.png", "the potential on z = 0 and the monopoles (top roots blue, bottom red)");
  page.Image("initial/start.png",
             "the initial one-step set {L < 0} on z = 0 against the target (both grey, set only orange, "
             "target only blue; top roots blue, bottom red)");
}

// One optimizer's run: its energies, the best pass, a row per pass and the stalled passes.
void OptimizerSection(Page& page, const OptimizeStageOptions& o) {
  std::ostringstream& md = page.md;
  const std::string name = o.name;
  const json s = ReadStageFile(page.Path(name + "/summary.json"));
  if (!s.is_object()) return;
  if (!page.Exists(name + "/map.json")) {
    md << "### " << name << ": not finished\n\nNo map yet; the checkpoint `" << name
       << "/checkpoint.json` continues it (--resume).\n\n";
    return;
  }
  md << "### " << name << ": " << o.optimizer.schedule.notation() << ", " << s.value("evaluator", "")
     << " evaluator, " << s.value("precision", "") << ", " << s.value("backend", "") << "\n\n"
     << "Absolute energy psi " << Fixed(s.value("absolute_start", 0.0), 6) << " -> "
     << Fixed(s.value("absolute_end", 0.0), 6)
     << " (normalized (psi+1)/2: " << Fixed((s.value("absolute_start", 0.0) + 1) / 2, 6) << " -> "
     << Fixed((s.value("absolute_end", 0.0) + 1) / 2, 6) << ") in " << Fixed(s.value("seconds", 0.0), 1)
     << " s. Map: `" << name << "/map.json`, ";
  const json& passes = s["passes"];
  const int best = s.value("best_pass", -1);
  if (best >= 0 && best < int(passes.size()))
    md << "the map after level " << passes[best].value("level", 0) << " pass "
       << passes[best].value("pass", std::string("?")) << " (pass " << best + 1 << " of " << passes.size()
       << (s.value("keep", std::string("lowest-psi")) == "iou"
               ? "), the lowest absolute energy among the maps whose one-step IoU on the target grid is at least "
                 "the start's.\n\n"
               : "), the lowest absolute energy of the run.\n\n");
  else
    md << "the start map: no pass lowered the absolute energy"
       << (s.value("keep", std::string("lowest-psi")) == "iou" ? " without lowering the one-step IoU" : "") << ".\n\n";
  md << "| level | pass | stop | iterations | evaluations | seconds | energy start | energy end | absolute end |\n"
        "|---|---|---|---|---|---|---|---|---|\n";
  for (std::size_t k = 0; k < passes.size(); ++k) {
    const json& p = passes[k];
    md << "| " << p.value("level", 0) << " | " << p.value("pass", std::string("?")) << " | "
       << p.value("stop", std::string()) << (p.value("stalled", false) ? " (**stalled**)" : "") << " | "
       << p.value("iterations", 0) << " | " << p.value("evaluations", 0) << " | "
       << Fixed(p.value("seconds", 0.0), 2) << " | " << Fixed(p.value("energy_start", 0.0), 6) << " | "
       << Fixed(p.value("energy_end", 0.0), 6) << " | " << Fixed(p.value("absolute_end", 0.0), 6)
       << (int(k) == best ? " (best)" : "") << " |\n";
  }
  md << "\n";
  for (const json& p : passes)
    if (p.value("stalled", false))
      md << "**Stalled:** level " << p.value("level", 0) << " pass " << p.value("pass", std::string("?"))
         << " (pass " << p.value("pass_index", 0) + 1
         << " of the level) made no iteration: " << p.value("stall_reason", p.value("stop", std::string()))
         << ".\n\n";
  for (const json& p : passes)
    if (p.value("iou_loss", false))
      md << "**Set worse:** level " << p.value("level", 0) << " pass " << p.value("pass", std::string("?"))
         << " lowered the one-step IoU on the target grid from " << Fixed(p.value("iou_start", 0.0), 4) << " to "
         << Fixed(p.value("iou_end", 0.0), 4) << ".\n\n";
  const int lowest = s.value("lowest_psi_pass", -1);
  if (lowest >= 0 && lowest < int(passes.size()))
    md << "**Not kept:** the lowest absolute energy, " << Fixed(s.value("lowest_psi", 0.0), 6) << " after level "
       << passes[lowest].value("level", 0) << " pass " << passes[lowest].value("pass", std::string("?"))
       << ", has one-step IoU " << Fixed(passes[lowest].value("iou_end", 0.0), 4) << " on the target grid, below the "
       << "start's " << Fixed(s.value("iou_start", 0.0), 4) << " (`\"keep\": \"lowest-psi\"` returns it).\n\n";
}

// The mesh: its files and figures, or "No surface".
void MeshSection(Page& page) {
  std::ostringstream& md = page.md;
  const json ms = ReadStageFile(page.Path("mesh/summary.json"));
  if (!ms.is_object()) return;
  if (ms.value("triangles", 0LL) == 0) {
    md << "## Mesh\n\n**No surface:** log|q_n| = " << json(ms["julia"].value("iso", 0.0)).dump()
       << " does not cross the box at n = " << ms["julia"].value("iterations", 0) << " (" << ms.value("resolution", 0)
       << "^3 cells): the set is empty there or fills it. Try fewer iterations (`mesh.iterations`), or look at "
          "the slice pictures.\n\n";
    return;
  }
  md << "## Mesh\n\n`mesh/julia.ply`" << (page.Exists("mesh/julia.vdb") ? ", `mesh/julia.vdb`" : "")
     << (page.Exists("mesh/julia.obj") ? ", `mesh/julia.obj`" : "") << " (" << ms.value("frame", std::string("user"))
     << " frame): " << ms.value("vertices", 0LL) << " vertices, " << ms.value("triangles", 0LL) << " triangles, "
     << ms.value("components", 0LL) << " components, " << ms.value("open_edges", ms.value("boundary_edges", 0LL))
     << " open edges (" << ms.value("open_edges_inside", 0LL) << " away from the box faces), "
     << (ms.value("speck_removal", true) ? std::to_string(ms.value("specks_removed", 0LL)) + " one-node specks removed"
                                         : std::string("one-node specks kept"))
     << ", " << ms.value("resolution", 0) << "^3 cells, n = " << ms["julia"].value("iterations", 0) << ", "
     << Fixed(ms.value("seconds", 0.0), 1) << " s.\n\n";
  if (ms.contains("iteration_frame") && (ms["iteration_frame"].value("name", "map") != "map" ||
                                         ms["iteration_frame"].value("detail", 1.0) != 1.0))
    md << "Iterated in the " << ms["iteration_frame"].value("name", "map") << " frame with detail "
       << ms["iteration_frame"].value("detail", 1.0) << " (fractal radius "
       << Fixed(ms["iteration_frame"].value("fractal_radius", 0.0), 3) << "), root translation "
       << ms["julia"]["root_translation"].dump()
       << (ms["iteration_frame"].value("translate_potential", json()).is_number()
               ? " (the length that leaves L = " + ms["iteration_frame"]["translate_potential"].dump() + " at -t)"
               : std::string())
       << ".\n\n";
  if (ms.contains("detail")) {
    const json& d = ms["detail"];
    md << "Detail: surface area " << Fixed(d.value("area_ratio", 0.0), 2)
       << "× the target mesh's, box-counting dimension " << Fixed(d.value("box_dimension", 0.0), 3) << " (2 for a "
       << "smooth surface; boxes of 1/8 to 1/128 of the shape's side).\n\n";
  }
}

// The shape modulus's and the portals' outputs, and the slice and render pictures.
void ProductsAndPictures(Page& page, const Experiment& e) {
  std::ostringstream& md = page.md;
  for (const char* prod : {"modulus", "portal", "julia"}) {
    const std::string dir = prod;
    for (const char* ext : {"ply", "png"})
      if (page.Exists(dir + "/julia." + ext)) {
        md << "## " << prod << "\n\nOutput `" << dir << "/julia." << ext << "`; the command's report in `" << dir
           << "/" << prod << ".json`.\n\n";
        if (std::string(ext) == "png") page.Image(dir + "/julia.png", std::string("the ") + prod + " Julia set");
      }
  }
  const std::string n = std::to_string(e.pictures.slice_iterations);
  if (page.Exists("pictures/slice-n" + n + ".png")) md << "## Pictures\n\n";
  page.Image("pictures/initial-slice-n" + n + ".png",
             "initial map: the set (n = " + n + ") against the target on z = 0 (orange: set only, blue: target only)");
  page.Image("pictures/slice-n" + n + ".png",
             "optimized map: the set (n = " + n + ") against the target on z = 0 (orange: set only, blue: target only)");
  page.Image("pictures/render.png", "the mesh, shaded (front, side, top, three-quarter)");
}

}  // namespace

std::string RunReport(const Experiment& e, const std::vector<StageRecord>& records, const std::string& results,
                      double total_seconds, const RunState& state) {
  Page page;
  page.results = results;
  std::ostringstream& md = page.md;
  const std::time_t now = std::time(nullptr);
  char date[64];
  std::strftime(date, sizeof date, "%Y-%m-%d %H:%M UTC", std::gmtime(&now));
  const bool incomplete = !state.stopped_in.empty();
  md << "# " << e.name << (incomplete ? " (INCOMPLETE)" : "") << "\n\n";
  if (incomplete)
    md << "**INCOMPLETE:** the run stopped in stage " << state.stopped_in << ": " << state.reason
       << ". What follows is what the stages before it left; the stages after it have no output (a stage that "
          "computes removes the outputs of the stages that read it). Resume with\n\n    "
       << state.resume << "\n\n";
  if (!e.description.empty()) md << e.description << "\n\n";
  md << "Experiment `" << e.path << "` (resolved: `experiment.resolved.json`), method " << e.method << ", run " << date
     << ", " << Fixed(total_seconds, 1) << " s " << (incomplete ? "so far" : "in all") << ".\n\n";
  if (e.method == "quijibo") md << TriptychSection(results);  // first: the result, as the paper's Fig. 1
  md << QualitySection(RunQuality(e, results));  // then what the figures below are worth
  InitialSection(page);
  if (e.method == "quijibo") {
    md << "## Optimization\n\n";
    for (const OptimizeStageOptions& o : e.optimizers) OptimizerSection(page, o);
    page.Image("plot/convergence.png", "convergence: (psi+1)/2 per step (line: current level, dashed: finest grid)");
    if (page.Exists("plot/no-plot.txt"))
      md << "No convergence plot: no iterations and no absolute energies in the logs.\n\n";
  }
  MeshSection(page);
  ProductsAndPictures(page, e);
  md << "## Stages\n\n| stage | status | seconds |\n|---|---|---|\n";
  for (const auto& r : records) md << "| " << r.name << " | " << r.status << " | " << Fixed(r.seconds, 1) << " |\n";
  md << "\nReused stages show the time of the run that made them. Times of the whole run: `run.json`.\n";
  return md.str();
}

}  // namespace quijibo::pipeline
