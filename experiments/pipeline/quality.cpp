#include "experiments/pipeline/quality.h"

#include <cmath>
#include <cstdio>
#include <sstream>

#include "experiments/pipeline/stage_cache.h"
#include "monopole/kernel_fit.h"
#include "optim/lbfgsb.h"

namespace quijibo::pipeline {

using nlohmann::json;

std::string Fixed(double x, int digits) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", digits, x);
  return buf;
}

json MeasureQuality(const RationalMap& initial, const RationalMap& chosen, const ScalarGrid& target,
                    const JuliaOptions& julia, double iso, double alpha, const json& start,
                    const QualityOptions& options) {
  mesh::FidelityOptions o;
  o.lattice = options.lattice;
  o.julia = julia;
  o.iso = iso;
  o.iterated = options.iterated;
  const mesh::Fidelity f = mesh::MeasureSets(chosen, target, o);
  json j = f.ToJson();
  // The start's one-step set at the same jittered points: whether the optimization moved the
  // set's volume towards the target's, free of the lattice's aliasing (docs/fidelity.md §10).
  mesh::FidelityOptions one = o;
  one.julia.iterations = 0;
  one.iterated.reset();  // `initial`'s, not made: the one-step set only
  j["one_step"]["start_volume_iou"] = mesh::MeasureSets(initial, target, one).one_step.volume_iou;
  j["lattice"] = o.lattice;
  j["iterations"] = julia.iterations;
  // Orbits are trapped at the fractal origin (docs/fidelity.md §3): phi there, outside the grid
  // counted as outside.
  const Vec3 lo = target.frame.min_corner, ext = target.frame.extent();
  bool in_grid = true;
  for (int a = 0; a < 3; ++a) in_grid = in_grid && lo[a] <= 0 && 0 <= lo[a] + ext[a];
  const double phi0 = in_grid ? target.sample({0.0, 0.0, 0.0}) : 1.0;
  j["origin"] = {{"phi", phi0}, {"inside", phi0 < 0}};
  if (start.is_object()) {
    j["start"] = start;
  } else {
    const monopole::StartCheck s = monopole::CheckStart(initial, target, alpha);
    j["start"] = {{"iou", s.iou},
                  {"median_L_inside", s.median_inside},
                  {"median_L_outside", s.median_outside},
                  {"saturated_fraction", s.saturated},
                  {"inverted", s.inverted}};
  }
  // The chosen map on the grid the energy saw, beside the start's figure on the same grid: whether
  // the optimization made the one-step set closer to the target (docs/fidelity.md §7).
  const monopole::StartCheck c = monopole::CheckStart(chosen, target, alpha);
  j["target_grid"] = {{"resolution", target.frame.dims[0]}, {"start_iou", j["start"].value("iou", 0.0)}, {"iou", c.iou}};
  // ... and between its nodes, where a fit tight only at the nodes shows (docs/fidelity.md).
  j["target_grid"]["node_fit"] = mesh::MeasureNodeFit(chosen, target).ToJson();
  return j;
}

namespace {

// What a user can do about a set that follows the shape only coarsely: what the run's own files
// say about it (the last pass at its iteration cap; the monopole start, whose hull misses thin parts).
std::string CoarseRemedy(const Experiment& e, const std::string& results) {
  std::string remedy;
  const json summary = ReadStageFile(results + "/optimized/summary.json");
  if (summary.is_object() && summary.contains("passes") && summary["passes"].is_array() && !summary["passes"].empty() &&
      summary["passes"].back().value("stop", "") == optim::StopReasonName(optim::StopReason::kMaxIterations))
    remedy += "; the last pass stopped at its iteration cap: a schedule with more iterations may go further";
  if (e.initial.kind == "monopoles")
    remedy += "; the paper's monopole start stops short of thin parts (docs/fidelity.md §12): the log-kernel start "
              "(\"initial\": {\"kind\": \"log-kernel\"}, the default) follows them";
  return remedy;
}

}  // namespace

json RunQuality(const Experiment& e, const std::string& results, const QualityThresholds& t) {
  auto P = [&](const std::string& rel) { return results + "/" + rel; };
  json figures = json::object(), warnings = json::array();
  auto warn = [&](const std::string& w) { warnings.push_back(w); };
  const json f = ReadStageFile(P("fidelity/fidelity.json"));
  if (f.is_object()) {
    const double lattice_nodes = std::pow(double(f.value("lattice", QualityOptions().lattice)), 3);
    const int n = f.value("iterations", 0);
    figures["lattice"] = f["lattice"];
    figures["one_step"] = {{"iou", f["one_step"]["iou"]}, {"leak", f["one_step"]["leak"]}};
    if (f["one_step"].contains("volume_iou") && f["one_step"].contains("start_volume_iou"))
      figures["one_step"]["volume_iou"] = f["one_step"]["volume_iou"],
      figures["one_step"]["start_volume_iou"] = f["one_step"]["start_volume_iou"];
    const double iou1 = f["one_step"].value("iou", 0.0), leak1 = f["one_step"].value("leak", 0.0);
    if (iou1 < t.min_iou)
      warn("the optimized map's one-step set does not follow the shape: one-step IoU " + Fixed(iou1, 3) +
           " (below " + Fixed(t.min_iou, 2) + ")");
    else if (iou1 < t.coarse_iou)
      warn("the optimized map's one-step set follows the shape only coarsely: one-step IoU " + Fixed(iou1, 3) +
           " (below " + Fixed(t.coarse_iou, 2) + "; thin parts are missing or filled in)" + CoarseRemedy(e, results));
    if (leak1 > t.max_leak)
      warn("the one-step set leaks: its part outside the shape box is " + Fixed(leak1, 3) +
           " of the shape's volume (above " + Fixed(t.max_leak, 2) + ")");
    if (f.contains("n_step")) {
      const double iou = f["n_step"].value("iou", 0.0), leak = f["n_step"].value("leak", 0.0);
      const double fill = double(f["n_step"].value("set_nodes", 0LL)) / lattice_nodes;
      figures["n_step"] = {{"n", n}, {"iou", iou}, {"leak", leak}, {"fill", fill}};
      const std::string set = "the n = " + std::to_string(n) + " set";
      if (fill > t.max_fill)
        warn(set + " fills the box: " + Fixed(fill, 3) + " of the lattice is in it (above " + Fixed(t.max_fill, 2) +
             "; the shape box is 0.36 of it); the mesh is not the shape");
      // At n = 1 the n-step set is the one-step set: its IoU and leak are warned about above.
      if (leak > t.max_leak && n > 1)
        warn(set + " leaks: its part outside the shape box is " + Fixed(leak, 3) + " of the shape's volume (above " +
             Fixed(t.max_leak, 2) + ")");
      if (iou < t.min_iou && n > 1)
        warn(set + " does not follow the shape: n-step IoU " + Fixed(iou, 3) + " (below " + Fixed(t.min_iou, 2) +
             ", one-step " + Fixed(iou1, 3) + "); try fewer iterations (mesh.iterations) or look at the slices");
    }
    if (f.contains("target_grid")) {
      const json& g = f["target_grid"];
      figures["target_grid"] = g;
      const double before = g.value("start_iou", 0.0), after = g.value("iou", 0.0);
      if (after < before - t.max_iou_loss)
        warn("the optimization made the one-step set worse on the target grid: IoU " + Fixed(before, 4) +
             " at the start, " + Fixed(after, 4) + " optimized; passes on levels coarser than the target fit their "
             "own grid, not the target (docs/fidelity.md §7): give the finest level the work");
      if (g.contains("node_fit")) {
        const double nodes = g["node_fit"].value("on_nodes_iou", 0.0), between = g["node_fit"].value("between_nodes_iou", 0.0);
        if (between < nodes - t.max_node_gap)
          warn("the one-step set fits the target grid's nodes (IoU " + Fixed(nodes, 3) + ") but not the space between "
               "them (IoU " + Fixed(between, 3) + " at the cell corners): parts about as thin as two or three cells are "
               "beaded or broken between the nodes; \"optimizer\": {\"between_nodes\": \"on\"} makes the energy see "
               "the corners too (docs/fidelity.md §8)");
      }
    }
    const json& s = f["start"];
    figures["start"] = {{"iou", s["iou"]}, {"saturated", s["saturated_fraction"]}, {"inverted", s["inverted"]}};
    if (s.value("inverted", false))
      warn("the start is inverted: L is not lower inside the shape than outside (medians " +
           Fixed(s.value("median_L_inside", 0.0), 3) + " inside, " + Fixed(s.value("median_L_outside", 0.0), 3) +
           " outside)");
    if (s.value("saturated_fraction", 0.0) > t.max_saturated)
      warn("the start is saturated: tanh(alpha L) is flat in " + Fixed(s.value("saturated_fraction", 0.0), 3) +
           " of the cells (above " + Fixed(t.max_saturated, 2) + "), where the optimizer has no gradient");
  }
  const json ms = ReadStageFile(P("mesh/summary.json"));
  if (ms.is_object()) {
    figures["mesh"] = {{"triangles", ms.value("triangles", 0LL)},
                       {"components", ms.value("components", 0LL)},
                       {"open_edges", ms.value("open_edges", ms.value("boundary_edges", 0LL))},
                       {"open_edges_inside", ms.value("open_edges_inside", 0LL)}};
    if (ms.value("open_edges_inside", 0LL) > 0)
      warn("the mesh is not closed: " + std::to_string(ms.value("open_edges_inside", 0LL)) +
           " open edges away from the box faces");
  }
  // The same trap for both methods; what moves the origin differs.
  const json mod = ReadStageFile(P("modulus/modulus.json"));
  const json origin = mod.is_object() && mod.contains("origin") ? mod["origin"]
                      : f.is_object() && f.contains("origin") ? f["origin"]
                                                              : json();
  if (origin.is_object()) {
    figures["origin"] = origin;
    if (!origin.value("inside", true))
      warn("the iteration's origin lies outside the shape (phi " + Fixed(origin.value("phi", 0.0), 3) +
           " there): orbits are trapped at it, so the n-step set erodes or vanishes; " +
           (mod.is_object() ? "move the shape over it (modulus.offset, --offset)"
                            : "for a mesh target, target.origin \"inside\" (the default) puts it deep inside"));
  }
  (void)e;
  if (figures.empty()) return nullptr;
  return {{"figures", figures}, {"warnings", warnings}};
}

std::string QualitySection(const json& q) {
  if (q.is_null()) return {};
  std::ostringstream md;
  const json& f = q["figures"];
  md << "## Quality\n\n";
  for (const json& w : q["warnings"]) md << "**Warning:** " << w.get<std::string>() << ".\n\n";
  if (q["warnings"].empty()) md << "No warning.\n\n";
  md << "| figure | value |\n|---|---|\n";
  if (f.contains("one_step"))
    md << "| one-step IoU / leak (" << f.value("lattice", 0) << "^3 lattice) | " << Fixed(f["one_step"]["iou"], 3)
       << " / " << Fixed(f["one_step"]["leak"], 3) << " |\n";
  if (f.contains("one_step") && f["one_step"].contains("volume_iou"))
    md << "| one-step volume IoU (a point drawn in each lattice cell): start -> optimized | "
       << Fixed(f["one_step"]["start_volume_iou"], 3) << " -> " << Fixed(f["one_step"]["volume_iou"], 3) << " |\n";
  if (f.contains("n_step"))
    md << "| n-step (n = " << f["n_step"].value("n", 0) << ") IoU / leak / fill | " << Fixed(f["n_step"]["iou"], 3)
       << " / " << Fixed(f["n_step"]["leak"], 3) << " / " << Fixed(f["n_step"]["fill"], 3) << " |\n";
  if (f.contains("mesh"))
    md << "| mesh components / open edges (away from the box faces) | " << f["mesh"]["components"].get<long long>()
       << " / " << f["mesh"]["open_edges"].get<long long>() << " (" << f["mesh"]["open_edges_inside"].get<long long>()
       << ") |\n";
  if (f.contains("target_grid"))
    md << "| one-step IoU on the target grid (" << f["target_grid"].value("resolution", 0) << "^3): start -> optimized | "
       << Fixed(f["target_grid"]["start_iou"], 4) << " -> " << Fixed(f["target_grid"]["iou"], 4) << " |\n";
  if (f.contains("target_grid") && f["target_grid"].contains("node_fit"))
    md << "| one-step IoU away from the surface (\\|φ\\| ≥ h/4): on the target grid's nodes / between them (cell corners) | "
       << Fixed(f["target_grid"]["node_fit"]["on_nodes_iou"], 4) << " / "
       << Fixed(f["target_grid"]["node_fit"]["between_nodes_iou"], 4) << " |\n";
  if (f.contains("start"))
    md << "| start: one-step IoU / saturated cells / inverted | " << Fixed(f["start"]["iou"], 3) << " / "
       << Fixed(f["start"]["saturated"], 3) << " / " << (f["start"]["inverted"].get<bool>() ? "**yes**" : "no")
       << " |\n";
  if (f.contains("origin"))
    md << "| origin inside the shape (phi there) | " << (f["origin"].value("inside", true) ? "yes" : "**no**") << " ("
       << Fixed(f["origin"].value("phi", 0.0), 3) << ") |\n";
  md << "\nFigures: `mesh/fidelity.h`, docs/fidelity.md; thresholds of the warnings: docs/experiments.md.\n\n";
  return md.str();
}

}  // namespace quijibo::pipeline
