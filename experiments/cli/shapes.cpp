// `quijibo fidelity` (how well one Julia set takes its target's shape) and `quijibo bench shapes`
// (the shape suite: every shape through `quijibo run`, then the fidelity figures, a table and a
// picture sheet). Definitions of the figures: mesh/fidelity.h.
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <filesystem>

#include "experiments/cli/bind.h"
#include "experiments/cli/cli.h"
#include "experiments/pipeline/mesh.h"
#include "mesh/fidelity.h"
#include "mesh/frame_file.h"
#include "mesh/triangle_mesh.h"
#include "optim/optimizer.h"
#include "util/child_process.h"
#include "util/error.h"
#include "util/io.h"
#include "util/json_reader.h"
#include "util/progress.h"

namespace quijibo::cli {

using nlohmann::json;
namespace fs = std::filesystem;

namespace {

struct FidelityArgs {
  std::string map, target, julia_mesh, shape_mesh, out;
  mesh::FidelityOptions o;
  pipeline::MeshStageOptions iteration;  // the mesh stage's iteration_frame, detail, translate(_potential), capture
};

void AddFidelityOptions(CLI::App* c, mesh::FidelityOptions& o) {
  c->add_option("--lattice", o.lattice, "Lattice nodes per axis")->capture_default_str()->check(CLI::Range(8, 512));
  c->add_option("--extend", o.extend, "Growth of the shape box on every side, as a fraction of its side")
      ->capture_default_str()->check(CLI::Range(0.0, 2.0));
  c->add_option("-n,--iterations", o.julia.iterations, "Iterations of the n-step set (0: skip it)")
      ->capture_default_str()->check(CLI::Range(0, 64));
  c->add_option("--escape", o.julia.escape_radius, "Escape radius of the n-step iteration")->capture_default_str();
  c->add_option("--samples", o.surface_samples, "Points per mesh for Chamfer and Hausdorff")->capture_default_str();
}

json Measure(const FidelityArgs& a) {
  const RationalMap map = ReadMap(a.map);
  mesh::CheckSameFrame(map.frame, a.map, a.target);
  const ScalarGrid target = ReadGrid(a.target);
  mesh::FidelityOptions o = a.o;
  pipeline::MeshStageOptions iteration = a.iteration;
  iteration.julia = o.julia;
  iteration.julia.capture_radius = a.iteration.julia.capture_radius;
  const auto setup = std::make_shared<JuliaSetup>(iteration.Iterated(map));
  o.julia = setup->julia;
  o.iterated = std::shared_ptr<const RationalMap>(setup, &setup->map);
  mesh::Fidelity f = mesh::MeasureSets(map, target, o);
  if (!a.julia_mesh.empty() || !a.shape_mesh.empty()) {
    if (a.julia_mesh.empty() || a.shape_mesh.empty())
      throw Error("fidelity: Chamfer and Hausdorff need both --julia and --shape");
    const mesh::TriangleMesh julia = mesh::ReadMesh(a.julia_mesh), shape = mesh::ReadMesh(a.shape_mesh);
    mesh::MeasureSurfaceDistances(julia, shape, o, f);
    json j = f.ToJson();
    // The shape box's side in the meshes' (user) frame: the boxes of the box-counting dimension.
    const double side = (1.0 - 2.0 * map.frame.padding) / map.frame.scale;
    j["detail"] = mesh::MeasureMeshDetail(julia, &shape, side).ToJson();
    j["node_fit"] = mesh::MeasureNodeFit(map, target).ToJson();
    return j;
  }
  json j = f.ToJson();
  j["node_fit"] = mesh::MeasureNodeFit(map, target).ToJson();
  return j;
}

// Runs `quijibo args...` (this executable), stdout and stderr to files; returns the exit code.
int RunSelf(const std::vector<std::string>& args, const std::string& out, const std::string& err) {
  ChildOptions c;
  c.program = SelfExecutable();
  c.argv0 = "quijibo";
  c.args = args;
  c.stdin_path = "";
  c.stdout_path = out;
  c.stderr_path = err;
  try {
    return RunChild(c).exit_code;
  } catch (const Error& e) {
    throw Error(std::string("bench shapes: ") + e.what());
  }
}

std::string LastLine(const std::string& path) {
  std::string text;
  try {
    text = ReadFile(path);
  } catch (const Error&) {
    return {};
  }
  while (!text.empty() && (text.back() == '\n' || text.back() == '\r')) text.pop_back();
  const auto nl = text.rfind('\n');
  return nl == std::string::npos ? text : text.substr(nl + 1);
}

std::string F(double v, int digits) {
  char b[64];
  std::snprintf(b, sizeof b, "%.*f", digits, v);
  return b;
}

struct Shape {
  std::string name, mesh, why;
};

struct ShapeBenchArgs {
  std::string suite, out = "results/shapes", schedule = "experiments/schedules/demo.json", markdown, images,
                   initializer = "log-kernel", json_out, target_box = "unit";
  std::vector<std::string> meshes, only;
  int resolution = kDefaultTargetResolution, mesh_resolution = 128;
  bool initial_only = false, report_only = false;
  mesh::FidelityOptions o;
  optim::OptimizeOptions optimizer;  // the settings bound below (between_nodes), written into each experiment
};

// The suite's shapes whose meshes are there (a missing one is skipped with a note), then the
// meshes given, restricted to --only.
std::vector<Shape> ReadShapes(const ShapeBenchArgs& b) {
  std::vector<Shape> shapes;
  if (!b.suite.empty()) {
    const json doc = ParseJson(ReadFile(b.suite), b.suite);
    JsonReader r(doc, b.suite);
    if (!doc.is_array()) r.fail("", "expected an array of shapes");
    const fs::path base = fs::absolute(b.suite).parent_path();
    for (std::size_t k = 0; k < doc.size(); ++k) {
      const std::string p = "/" + std::to_string(k);
      Shape sh{r.string(p + "/name"), (base / r.string(p + "/mesh")).string(), r.string_or(p + "/why", "")};
      if (!fs::exists(sh.mesh)) {
        std::fprintf(stderr, "quijibo: bench shapes: %s: %s is missing (scripts/fetch-shapes.sh fetches it); skipped\n",
                     sh.name.c_str(), sh.mesh.c_str());
        continue;
      }
      shapes.push_back(sh);
    }
  }
  for (const std::string& m : b.meshes) shapes.push_back({fs::path(m).stem().string(), fs::absolute(m).string(), ""});
  if (!b.only.empty())
    std::erase_if(shapes, [&](const Shape& sh) { return std::find(b.only.begin(), b.only.end(), sh.name) == b.only.end(); });
  return shapes;
}

// --report-only: the rows saved in <out>/shapes.json, restricted to --only.
json SavedResults(const ShapeBenchArgs& b) {
  const std::string saved = (fs::path(b.out) / "shapes.json").string();
  json results = ParseJson(ReadFile(saved), saved);
  if (b.only.empty()) return results;
  json kept = json::array();
  for (const json& r : results)
    if (std::find(b.only.begin(), b.only.end(), r.value("name", "")) != b.only.end()) kept.push_back(r);
  return kept;
}

// --initial-only: the shape's initial guess (`quijibo monopoles`), its one-step figures, start
// check and time.
json MeasureInitialGuess(const ShapeBenchArgs& b, const Shape& sh, const fs::path& dir) {
  const fs::path init = dir / ("initial-" + b.initializer);
  const auto t0 = std::chrono::steady_clock::now();
  const int code = RunSelf({"monopoles", sh.mesh, "-o", init.string(), "-r", std::to_string(b.resolution),
                            "--initializer", b.initializer, "--target-box", b.target_box},
                           (dir / "initial.out").string(), (dir / "initial.err").string());
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  json row = {{"name", sh.name}, {"mesh", sh.mesh}, {"seconds", seconds}, {"exit_code", code}};
  try {
    if (code != 0) throw Error("quijibo monopoles failed: " + LastLine((dir / "initial.err").string()));
    const RationalMap initial = ReadMap((init / "map.json").string());
    mesh::FidelityOptions one = b.o;
    one.julia.iterations = 0;
    row["roots"] = initial.root_count();
    row["initial"] = mesh::MeasureSets(initial, ReadGrid((init / "target.qgrid").string()), one).ToJson();
    row["start"] = ParseJson(ReadFile((init / "monopoles.json").string()), "monopoles.json")["start"];
  } catch (const Error& e) {
    row["error"] = e.what();
  }
  return row;
}

// The figures of a finished run folder into `row`: the initial map's one-step figures, the
// optimized map's lattice figures, Chamfer, Hausdorff and detail of its mesh, psi at start and end.
void MeasureRun(const ShapeBenchArgs& b, const Shape& sh, const fs::path& run, json& row) {
  const mesh::TriangleMesh shape = mesh::ReadMesh(sh.mesh);
  row["triangles"] = shape.triangles.size();
  const ScalarGrid target = ReadGrid((run / "initial/target.qgrid").string());
  mesh::FidelityOptions one = b.o;
  one.julia.iterations = 0;
  const RationalMap initial = ReadMap((run / "initial/map.json").string());
  row["roots"] = initial.root_count();
  row["initial"] = mesh::MeasureSets(initial, target, one).ToJson();
  if (!fs::exists(run / "optimized/map.json")) return;
  const RationalMap opt = ReadMap((run / "optimized/map.json").string());
  mesh::FidelityOptions o = b.o;
  if (o.julia.iterations > 0) {  // iterated as the run's mesh stage does by default (map frame, its detail)
    pipeline::MeshStageOptions iteration;
    iteration.julia = o.julia;
    o.iterated = std::make_shared<const RationalMap>(iteration.Iterated(opt).map);
  }
  mesh::Fidelity f = mesh::MeasureSets(opt, target, o);
  json detail;
  if (fs::exists(run / "mesh/julia.ply")) {
    const mesh::TriangleMesh julia = mesh::ReadMesh((run / "mesh/julia.ply").string());
    mesh::MeasureSurfaceDistances(julia, shape, b.o, f);
    detail = mesh::MeasureMeshDetail(julia, &shape, (1.0 - 2.0 * opt.frame.padding) / opt.frame.scale).ToJson();
  }
  row["optimized"] = f.ToJson();
  if (!detail.is_null()) row["optimized"]["detail"] = detail;
  row["optimized"]["node_fit"] = mesh::MeasureNodeFit(opt, target).ToJson();
  const json summary = ParseJson(ReadFile((run / "optimized/summary.json").string()), "summary.json");
  row["psi_start"] = summary.value("absolute_start", 0.0);
  row["psi_end"] = summary.value("absolute_end", 0.0);
}

// One shape through `quijibo run` (an experiment written into its folder), measured; its render
// and slice copied to --images.
json RunShape(const ShapeBenchArgs& b, const Shape& sh, const fs::path& dir, const std::string& schedule) {
  json optimizer = {{"schedule", schedule}, {"absolute_every", 50}};
  optim::OptimizeOptions::Settings().WriteChanged(b.optimizer, optimizer);  // the optimizer flags given
  const json exp = {{"name", sh.name},
                    {"target", {{"mesh", sh.mesh}, {"resolution", b.resolution}, {"box", b.target_box}}},
                    {"initial", {{"kind", b.initializer}}},
                    {"optimizer", optimizer},
                    {"mesh", {{"resolution", b.mesh_resolution}, {"iterations", b.o.julia.iterations}, {"vdb", false}}},
                    {"pictures", {{"slice_iterations", 1}}}};
  const std::string exp_path = (dir / "experiment.json").string();
  WriteFileAtomically(exp_path, exp.dump(1) + "\n");
  const auto t0 = std::chrono::steady_clock::now();
  const int code = RunSelf({"run", exp_path, "--out", (dir / "run").string(), "--quiet"}, (dir / "run.out").string(),
                           (dir / "run.err").string());
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  json row = {{"name", sh.name}, {"mesh", sh.mesh}, {"why", sh.why}, {"seconds", seconds}, {"exit_code", code}};
  const fs::path run = dir / "run";
  try {
    MeasureRun(b, sh, run, row);
  } catch (const Error& e) {
    row["error"] = e.what();
  }
  if (code != 0) row["error"] = "quijibo run failed: " + LastLine((dir / "run.err").string());
  if (!b.images.empty())
    for (const char* pic : {"render.png", "slice-n1.png"}) {
      const fs::path from = run / "pictures" / pic;
      if (fs::exists(from))
        fs::copy_file(from, fs::path(b.images) / (sh.name + "-" + pic), fs::copy_options::overwrite_existing);
    }
  return row;
}

// A figure of the table: j[a][k] with 3 decimals, "–" when absent.
std::string TableFigure(const json& j, const char* a, const char* k) {
  if (!j.is_object()) return "–";
  if (!j.contains(a) || !j[a].contains(k)) return "–";
  return F(j[a][k].get<double>(), 3);
}

// --initial-only's table: header line and Markdown.
std::string InitialGuessTable(const ShapeBenchArgs& b, const json& results) {
  std::vector<double> ious;
  std::string md = "| shape | roots | start one-step IoU | leak | median L inside / outside | inverted | time |\n"
                   "|---|---:|---:|---:|---|---|---:|\n";
  for (const json& r : results) {
    md += "| " + r["name"].get<std::string>() + " | " + std::to_string(r.value("roots", 0)) + " | " +
          TableFigure(r.value("initial", json::object()), "one_step", "iou") + " | " +
          TableFigure(r.value("initial", json::object()), "one_step", "leak") + " | ";
    if (r.contains("start"))
      md += F(r["start"]["median_L_inside"], 3) + " / " + F(r["start"]["median_L_outside"], 3) + " | " +
            (r["start"]["inverted"].get<bool>() ? "**yes**" : "no");
    else
      md += "– | –";
    md += " | " + F(r["seconds"], 1) + " s |" + (r.contains("error") ? " " + r["error"].get<std::string>() : "") + "\n";
    if (r.contains("initial")) ious.push_back(r["initial"]["one_step"]["iou"]);
  }
  std::sort(ious.begin(), ious.end());
  if (!ious.empty()) md += "\nStart one-step IoU: median " + F(ious[ious.size() / 2], 3) + ", lowest " + F(ious.front(), 3) + ".\n";
  const std::string header = "Initial guesses on the shape suite: initializer " + b.initializer + ", target " +
                             std::to_string(b.resolution) + "³ (" + b.target_box + " box); lattice " +
                             std::to_string(b.o.lattice) + "³.\n\n";
  return header + md;
}

// The suite's table (one row a shape, the median one-step IoU) and, with --images and
// --markdown, the picture sheet; under a header line with the date, machine and settings.
std::string SuiteTable(const ShapeBenchArgs& b, const json& results) {
  std::vector<double> ious;
  int gained = 0, compared = 0;
  std::string md = "| shape | triangles | roots | start IoU | ψ start → end | one-step IoU | leak | volume IoU: start → "
                   "optimized | grid IoU: nodes / between | n-step IoU | n-step volume IoU | n-step leak | Chamfer | "
                   "Hausdorff | area ratio | box dim. | components | time |\n"
                   "|---|---:|---:|---:|---|---:|---:|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
  for (const json& r : results) {
    const json opt = r.value("optimized", json::object()), init = r.value("initial", json::object());
    md += "| " + r["name"].get<std::string>() + " | " + std::to_string(r.value("triangles", 0)) + " | " +
          std::to_string(r.value("roots", 0)) + " | " + TableFigure(init, "one_step", "iou") +
          " | " + (r.contains("psi_end") ? F(r["psi_start"], 3) + " → " + F(r["psi_end"], 3) : "–") + " | " +
          TableFigure(opt, "one_step", "iou") + " | " + TableFigure(opt, "one_step", "leak") + " | " +
          TableFigure(init, "one_step", "volume_iou") + " → " +
          TableFigure(opt, "one_step", "volume_iou") + " | " + TableFigure(opt, "node_fit", "on_nodes_iou") + " / " +
          TableFigure(opt, "node_fit", "between_nodes_iou") + " | " + TableFigure(opt, "n_step", "iou") + " | " +
          TableFigure(opt, "n_step", "volume_iou") + " | " + TableFigure(opt, "n_step", "leak") + " | " +
          (opt.contains("chamfer") ? F(opt["chamfer"], 4) : "–") + " | " +
          (opt.contains("hausdorff") ? F(opt["hausdorff"], 3) : "–") + " | " + TableFigure(opt, "detail", "area_ratio") +
          " | " + TableFigure(opt, "detail", "box_dimension") + " | " +
          (opt.contains("detail") ? std::to_string(opt["detail"].value("components", 0)) : "–") + " | " +
          F(r["seconds"], 0) + " s |";
    if (r.contains("error")) md += " " + r["error"].get<std::string>();
    md += "\n";
    if (opt.contains("one_step")) ious.push_back(opt["one_step"]["iou"]);
    if (opt.contains("one_step") && opt["one_step"].contains("volume_iou") && init.contains("one_step") &&
        init["one_step"].contains("volume_iou")) {
      ++compared;
      gained += opt["one_step"]["volume_iou"].get<double>() >= init["one_step"]["volume_iou"].get<double>();
    }
  }
  if (!ious.empty()) {
    std::sort(ious.begin(), ious.end());
    const std::size_t m = ious.size();
    const double median = m % 2 ? ious[m / 2] : 0.5 * (ious[m / 2 - 1] + ious[m / 2]);
    md += "\nOne-step IoU: median " + F(median, 3) + ", lowest " + F(ious.front(), 3) + " (" + std::to_string(m) +
          " shapes).\n";
  }
  if (compared > 0)
    md += "The optimized map's one-step volume IoU is at least its start's on " + std::to_string(gained) + " of " +
          std::to_string(compared) + " shapes.\n";
  if (!b.images.empty() && !b.markdown.empty()) {
    const fs::path rel = fs::relative(fs::absolute(b.images), fs::absolute(b.markdown).parent_path());
    md += "\n| shape | slice z = 0 (n = 1; grey both, orange set only, blue target only) | render (n = " +
          std::to_string(b.o.julia.iterations) + ") |\n|---|---|---|\n";
    for (const json& r : results) {
      const std::string n = r["name"];
      md += "| " + n + " | ![](" + (rel / (n + "-slice-n1.png")).string() + ") | ![](" +
            (rel / (n + "-render.png")).string() + ") |\n";
    }
  }
  const std::time_t now = std::time(nullptr);
  char date[32];
  std::strftime(date, sizeof date, "%Y-%m-%d", std::gmtime(&now));
  const std::string header = "Shape suite, " + std::string(date) + ", " + std::to_string(::sysconf(_SC_NPROCESSORS_ONLN)) +
                             " cores; initializer " + b.initializer + ", schedule `" + b.schedule + "`" +
                             ", between_nodes " + AutoSwitchName(b.optimizer.between_nodes) + ", target " +
                             std::to_string(b.resolution) + "³ (" + b.target_box + " box), mesh " +
                             std::to_string(b.mesh_resolution) + "³ n = " + std::to_string(b.o.julia.iterations) +
                             "; lattice " + std::to_string(b.o.lattice) + "³ over the shape box grown " +
                             F(100 * b.o.extend, 0) + " % per side.\n\n";
  return header + md;
}

// `quijibo bench shapes`: every shape run (or its initial guess) and measured, shapes.json
// written after each, then the table to --markdown and standard output.
void BenchShapes(const ShapeBenchArgs& b) {
  std::vector<Shape> shapes = ReadShapes(b);
  if (shapes.empty() && !b.report_only) throw Error("bench shapes: no shapes (give --suite or meshes)");
  std::string schedule = b.schedule;
  if (fs::exists(schedule)) schedule = fs::absolute(schedule).string();
  fs::create_directories(b.out);
  if (!b.images.empty()) fs::create_directories(b.images);
  json results = json::array();
  if (b.report_only) {
    results = SavedResults(b);
    shapes.clear();
  }
  Progress progress("bench shapes", double(shapes.size()), false);
  for (std::size_t k = 0; k < shapes.size(); ++k) {
    const Shape& sh = shapes[k];
    progress.update(double(k), sh.name);
    const fs::path dir = fs::absolute(fs::path(b.out) / sh.name);
    fs::create_directories(dir);
    if (b.initial_only) {
      results.push_back(MeasureInitialGuess(b, sh, dir));
      continue;
    }
    results.push_back(RunShape(b, sh, dir, schedule));
    WriteFileAtomically((fs::path(b.out) / "shapes.json").string(), results.dump(1) + "\n");
  }
  progress.finish();
  const std::string table = b.initial_only ? InitialGuessTable(b, results) : SuiteTable(b, results);
  if (!b.markdown.empty()) WriteFileAtomically(b.markdown, table);
  if (!b.json_out.empty()) WriteFileAtomically(b.json_out, results.dump(1) + "\n");
  std::fputs(table.c_str(), stdout);
}

void AddFidelityCommand(CLI::App& app) {
  auto a = std::make_shared<FidelityArgs>();
  CLI::App* c = app.add_subcommand(
      "fidelity", "How well a map's Julia set takes its target's shape: one-step and n-step IoU and leak on a "
                  "lattice around the shape box, Chamfer and Hausdorff distance of a meshed set (mesh/fidelity.h)");
  c->add_option("-m,--map", a->map, "map.json")->required();
  c->add_option("-t,--target", a->target, "The target's .qgrid (the run's initial/target.qgrid)")->required();
  c->add_option("--julia", a->julia_mesh, "The meshed Julia set (same frame as --shape; `quijibo mesh` writes the user frame)");
  c->add_option("--shape", a->shape_mesh, "The target mesh");
  c->add_option("-o,--out", a->out, "Write the JSON here (default: standard output)");
  AddFidelityOptions(c, a->o);
  c->add_option("--closing", a->o.closing, "Closed IoU: half side of the closing's cube, lattice cells")
      ->capture_default_str()->check(CLI::Range(0, 16));
  BindSettings(c, a->iteration, {"iteration_frame", "detail", "translate", "translate_potential", "capture"});
  c->callback([a] { WriteOutput(a->out, Measure(*a).dump(1) + "\n"); });
}

void AddBenchShapesCommand(CLI::App* bench) {
  auto b = std::make_shared<ShapeBenchArgs>();
  CLI::App* s = bench->add_subcommand(
      "shapes", "The shape suite: each shape through `quijibo run` (initial guess, schedule, mesh, pictures), then "
                "one-step and n-step IoU and leak, Chamfer and Hausdorff, roots and time; a Markdown table and a "
                "picture sheet");
  s->add_option("--suite", b->suite, "A suite.json (data/suite/suite.json: entries with name, mesh, why)");
  s->add_option("meshes", b->meshes, "More meshes (named by their file)");
  s->add_option("--only", b->only, "Only these shape names (with --report-only: only these rows)");
  s->add_option("--schedule", b->schedule, "The optimizer schedule (notation or JSON file)")->capture_default_str();
  BindSettings(s, b->optimizer, {"between_nodes"});
  s->add_option("--initializer", b->initializer, "log-kernel or monopoles")
      ->capture_default_str()->check(CLI::IsMember({"log-kernel", "monopoles"}));
  s->add_option("--target-box", b->target_box, "unit or reference (quijibo/frame.h)")
      ->capture_default_str()->check(CLI::IsMember({"unit", "reference"}));
  AddTargetResolution(s, b->resolution, "-r,--resolution", "Target grid");
  s->add_option("--mesh-resolution", b->mesh_resolution, "Meshing lattice")->capture_default_str()->check(CLI::Range(8, 4096));
  s->add_option("-o,--out", b->out, "Results folder (one run per shape)")->capture_default_str();
  s->add_option("--markdown", b->markdown, "Also write the table and picture sheet here");
  s->add_option("--images", b->images, "Copy each shape's render and slice here (for the picture sheet)");
  s->add_option("--json", b->json_out, "Also write the figures as JSON here");
  s->add_flag("--report-only", b->report_only, "Run nothing: write the table again from <out>/shapes.json");
  s->add_flag("--initial-only", b->initial_only,
              "Only the initial guess (`quijibo monopoles` with --initializer): its one-step IoU and leak, whether it "
              "is inverted, and its time; to compare initializers");
  AddFidelityOptions(s, b->o);
  s->callback([b] { BenchShapes(*b); });
}

}  // namespace

void AddShapeCommands(CLI::App& app, CLI::App& bench) {
  AddFidelityCommand(app);
  AddBenchShapesCommand(&bench);
}

}  // namespace quijibo::cli
