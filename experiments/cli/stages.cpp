// `quijibo sdf` and `quijibo monopoles`: from a mesh to a target field and an initial map.
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>

#include "experiments/cli/bind.h"
#include "experiments/cli/cli.h"
#include "experiments/pipeline/initial.h"
#include "experiments/pipeline/product.h"
#include "experiments/pipeline/target.h"
#include "mesh/normalize.h"
#include "mesh/sdf.h"
#include "mesh/sdf_command.h"
#include "mesh/triangle_mesh.h"
#include "monopole/fit_pipeline.h"
#include "monopole/initial_guess.h"
#include "monopole/kernel_fit.h"
#include "util/error.h"
#include "quijibo/frame.h"
#include "util/io.h"
#include "util/progress.h"

namespace quijibo::cli {

using nlohmann::json;

namespace {

void AddSdfCommand(CLI::App& app) {
  auto so = std::make_shared<mesh::SdfCommandOptions>();
  CLI::App* sdf = app.add_subcommand(
      "sdf", "Signed distance field of a mesh (OBJ, PLY, STL, OFF) on the target grid, as .qgrid (and .vdb)");
  sdf->add_option("mesh", so->input, "Input mesh")->required();
  sdf->add_option("-o,--out", so->output, "Output .qgrid (the frame goes to <name>.frame.json)")->required();
  sdf->add_option("--vdb", so->vdb_output, "Also write the field as an OpenVDB level set");
  AddTargetResolution(sdf, so->target.resolution, "-r,--resolution", "Cells per axis");
  sdf->add_option("--padding", so->target.padding, "Normalization padding")->capture_default_str();
  sdf->add_option("--fractal-radius", so->target.fractal_radius, "Fractal frame scale")->capture_default_str();
  sdf->add_option_function<std::string>(
         "--target-box", [so](const std::string& b) { so->target.box = ParseTargetBox(b); },
         "unit: the whole unit cube, a margin of `padding` around the shape (default); reference: the reference "
         "code's box, the shape plus one cell")
      ->check(CLI::IsMember({"unit", "reference"}));
  sdf->add_option_function<std::string>(
         "--origin", [so](const std::string& o) { so->target.origin = mesh::ParseOriginPlacement(o); },
         "center: the fractal origin at the bounding box's centre (default here); inside: at the point deepest "
         "inside the shape (mesh/normalize.h)")
      ->check(CLI::IsMember({"center", "inside"}));
  sdf->add_option_function<std::string>(
         "--frame-scale", [so](const std::string& v) { so->target.frame_scale = mesh::ParseFrameScale(v); },
         "With --origin inside: trap (default) chooses fractal_radius so that the unit ball about the origin "
         "just fits inside the shape; fixed keeps --fractal-radius (mesh/normalize.h)")
      ->check(CLI::IsMember({"trap", "fixed"}));
  sdf->add_flag("--refuse-open", [so](std::int64_t) { so->target.sdf.allow_open = false; },
                "Refuse meshes with holes instead of signing them by winding numbers");
  sdf->callback([so] { mesh::RunSdfCommand(*so); });
}

// monopoles: the target and initial-guess stages, bound to their Options.
void AddMonopolesCommand(CLI::App& app) {
  struct Args {
    std::string mesh, out;
    pipeline::TargetOptions target;
    pipeline::InitialGuessStageOptions guess;
  };
  auto a = std::make_shared<Args>();
  CLI::App* m = app.add_subcommand(
      "monopoles",
      "The initial guess: mesh -> SDF -> map.json, by default a least-squares fit of the log modulus to the "
      "signed distance (--initializer log-kernel); --initializer monopoles is the 2015 paper's §4.4 (BEM "
      "potential, greedy monopole fit). Also writes the roots as a coloured PLY and a PNG slice");
  m->add_option("mesh", a->mesh, "Input mesh")->required();
  m->add_option("-o,--out", a->out, "Output folder")->required();
  m->add_option("--initializer", a->guess.kind,
                "log-kernel: fit L = ln C + sum e_i log|x - p_i| to the signed distance by least squares "
                "(monopole/kernel_fit.h); monopoles: the paper's potential fit with its charges as exponents")
      ->capture_default_str()
      ->check(CLI::IsMember({"log-kernel", "monopoles"}));
  BindSettings(m, a->target, {"resolution", "padding", "fractal_radius", "box", "origin", "frame_scale"});
  BindSettings(m, a->guess);
  m->callback([a] {
    if (auto why = a->guess.Validate(); !why.empty()) throw Error("monopoles: " + why);
    a->target.mesh = a->mesh;
    const pipeline::TargetResult target = pipeline::Target(a->target);
    const pipeline::InitialGuessResult guess = pipeline::InitialGuess(target, a->guess);
    // Everything computed: now write.
    std::filesystem::create_directories(a->out);
    pipeline::WriteTarget(target, a->target, a->out);
    pipeline::WriteInitialGuess(guess, a->out);
    std::printf("%s\n", guess.summary.dump(1).c_str());
  });

}

struct StageBenchArgs {
  std::vector<std::string> meshes{"data/bunny.obj", "data/tooth.obj"};
  int resolution = kDefaultTargetResolution, repeats = 3;
  std::string fit_target =
      monopole::MonopoleOptions{}.target == monopole::MonopoleTarget::kOneMinusPotential ? "reference" : "potential";
  std::string out_md, out_json;
};

// The stages `bench stages` times, in the table's order.
constexpr const char* kStageNames[] = {"read", "sdf", "bem", "shell", "potential", "candidates", "fit", "ln_C_scan", "total"};

// One mesh's repeats: the seconds of every stage (kStageNames) per repeat, into `row` as medians
// and a line of the Markdown table.
std::string BenchStagesOf(const StageBenchArgs& b, const std::string& path, json& row) {
  using Clock = std::chrono::steady_clock;
  auto median = [](std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
  };
  std::vector<std::vector<double>> t(std::size(kStageNames));
  monopole::MonopoleResult last;
  std::int64_t triangles = 0;
  RationalMap map;
  for (int r = 0; r < b.repeats; ++r) {
    const auto t0 = Clock::now();
    const mesh::TriangleMesh user = mesh::ReadMesh(path);
    const FractalFrame frame = mesh::NormalizationFor(user);
    const mesh::TriangleMesh mesh = mesh::ToFractalFrame(user, frame);
    t[0].push_back(pipeline::Since(t0));
    auto t1 = Clock::now();
    const ScalarGrid sdf = mesh::SignedDistance(mesh, TargetGridFrame(b.resolution, frame));
    t[1].push_back(pipeline::Since(t1));
    monopole::MonopoleOptions mo;
    mo.target = b.fit_target == "reference" ? monopole::MonopoleTarget::kOneMinusPotential
                                            : monopole::MonopoleTarget::kPotential;
    last = monopole::FitMonopoles(mesh.vertices, mesh.triangles, sdf, mo);
    t[2].push_back(last.seconds.bem), t[3].push_back(last.seconds.shell), t[4].push_back(last.seconds.potential);
    t[5].push_back(last.seconds.sampling), t[6].push_back(last.seconds.fit);
    t1 = Clock::now();
    map = monopole::InitialMap(last.monopoles, frame, sdf, monopole::InitialGuessOptions{});
    t[7].push_back(pipeline::Since(t1));
    t[8].push_back(pipeline::Since(t0));
    triangles = std::int64_t(mesh.triangles.size());
  }
  row = {{"mesh", path}, {"triangles", triangles}, {"bem_elements", last.bem.elements},
         {"top_roots", map.top_count()}, {"bottom_roots", map.bottom_count()},
         {"relative_residual", last.fit.final_relative_residual}};
  std::string md = "| " + std::filesystem::path(path).filename().string() + " | " + std::to_string(triangles) + " | " +
                   std::to_string(last.bem.elements) + " | " + std::to_string(map.top_count()) + "/" +
                   std::to_string(map.bottom_count()) + " |";
  for (std::size_t i = 0; i < std::size(kStageNames); ++i) {
    const double m = median(t[i]);
    row["median_seconds"][kStageNames[i]] = m;
    char buf[32];
    std::snprintf(buf, sizeof buf, " %.2f |", m);
    md += buf;
  }
  return md + "\n";
}

// `quijibo bench stages`: every mesh's stages, then the table and the JSON.
void BenchStages(const StageBenchArgs& b) {
  std::string md = "| mesh | triangles | BEM elements | monopoles (top/bottom) |";
  for (const char* n : kStageNames) md += std::string(" ") + n + " s |";
  md += "\n|---|---|---|---|";
  for (std::size_t i = 0; i < std::size(kStageNames); ++i) md += "---|";
  md += "\n";
  json results = json::array();
  for (const std::string& path : b.meshes) {
    json row;
    md += BenchStagesOf(b, path, row);
    results.push_back(row);
  }
  rusage ru{};
  ::getrusage(RUSAGE_SELF, &ru);
  const std::time_t now = std::time(nullptr);
  char date[32];
  std::strftime(date, sizeof date, "%Y-%m-%d", std::gmtime(&now));
  const int cores = int(::sysconf(_SC_NPROCESSORS_ONLN));
  const std::string header = "Initial-guess stages, " + std::string(date) + ", " + std::to_string(cores) +
                             " cores, " + std::to_string(b.resolution) + "^3 target, fit of " +
                             (b.fit_target == "reference" ? "1 - P" : "P") + ", median of " +
                             std::to_string(b.repeats) + " runs; peak memory " +
                             std::to_string(ru.ru_maxrss / 1024) + " MB.\n\n";
  const json doc = {{"benchmark", "stages"}, {"date", date}, {"cores", cores}, {"resolution", b.resolution},
                    {"repeats", b.repeats}, {"fit_target", b.fit_target},
                    {"peak_memory_mb", ru.ru_maxrss / 1024.0}, {"results", results}};
  if (!b.out_md.empty()) WriteFileAtomically(b.out_md, header + md);
  if (!b.out_json.empty()) WriteFileAtomically(b.out_json, doc.dump(1) + "\n");
  std::fputs((header + md).c_str(), stdout);
}

// bench stages: the monopole stage's parts, timed on real meshes.
void AddBenchStagesCommand(CLI::App* bench) {
  auto b = std::make_shared<StageBenchArgs>();
  CLI::App* st = bench->add_subcommand(
      "stages", "Seconds of each part of the initial guess (mesh read, SDF, BEM, shell, P on the shell, "
                "candidates, greedy fit, ln C scan) per mesh, median of repeats, and the process's peak memory");
  st->add_option("meshes", b->meshes, "Meshes")->capture_default_str();
  AddTargetResolution(st, b->resolution, "-r,--resolution", "Target grid");
  st->add_option("--repeats", b->repeats, "Runs per mesh (the median is reported)")->capture_default_str()->check(CLI::Range(1, 100));
  st->add_option("--fit-target", b->fit_target, "reference (1 - P) or potential (P)")
      ->capture_default_str()->check(CLI::IsMember({"reference", "potential"}));
  st->add_option("--markdown", b->out_md, "Also write the Markdown table here");
  st->add_option("--json", b->out_json, "Also write the results as JSON here");
  st->callback([b] { BenchStages(*b); });
}

}  // namespace

void AddTargetAndStartCommands(CLI::App& app, CLI::App& bench) {
  AddSdfCommand(app);
  AddMonopolesCommand(app);
  AddBenchStagesCommand(&bench);
}

}  // namespace quijibo::cli
