// `quijibo sdf` and `quijibo monopoles`: from a mesh to a target field and an initial map.
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>

#include "experiments/cli.h"
#include "mesh/normalize.h"
#include "mesh/sdf.h"
#include "mesh/sdf_command.h"
#include "mesh/triangle_mesh.h"
#include "monopole/fit_pipeline.h"
#include "monopole/initial_guess.h"
#include "monopole/kernel_fit.h"
#include "quijibo/error.h"
#include "quijibo/frame.h"
#include "quijibo/image.h"
#include "quijibo/io.h"
#include "quijibo/progress.h"

namespace quijibo::cli {

using nlohmann::json;

namespace {

// Roots as a coloured point cloud (top blue, bottom red), binary PLY, atomically.
void WriteRootsPly(const std::string& path, const RationalMap& map, bool user_frame) {
  std::string body;
  int count = 0;
  auto add = [&](const Vec4& r, std::uint8_t red, std::uint8_t blue) {
    Vec3 p{r[0], r[1], r[2]};
    if (user_frame) p = map.frame.fractal_to_user(p);
    for (double c : p) {
      const float f = float(c);
      body.append(reinterpret_cast<const char*>(&f), 4);
    }
    const std::uint8_t rgb[3] = {red, 40, blue};
    body.append(reinterpret_cast<const char*>(rgb), 3);
    ++count;
  };
  for (int i = 0; i < map.top_count(); ++i) add(map.top_roots[i], 30, 230);
  for (int i = 0; i < map.bottom_count(); ++i) add(map.bottom_roots[i], 230, 30);
  const std::string header = "ply\nformat binary_little_endian 1.0\ncomment quijibo roots: blue top, red bottom\n"
                             "element vertex " + std::to_string(count) +
                             "\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\n"
                             "property uchar green\nproperty uchar blue\nend_header\n";
  WriteFileAtomically(path, header + body);
}

// The potential on the slice z = 0 of the fractal frame (through the mesh's centre), grey from
// 0 (black) to 1 (white), the target's outline in green, roots within two cells of the slice as
// discs: top roots blue, bottom roots red (the idea of the paper's Fig. 8).
void WritePotentialSlice(const std::string& path, const ExteriorPotential& potential, const ScalarGrid& sdf,
                         const RationalMap& map, int size) {
  const Vec3 lo = sdf.frame.min_corner;
  const double side = sdf.frame.spacing * sdf.frame.dims[0];
  Image img(size, size);
  auto pixel_point = [&](double x, double y) {
    return Vec3{lo[0] + side * (x + 0.5) / size, lo[1] + side * (size - y - 0.5) / size, 0.0};
  };
  // P is smooth at the pixel scale: evaluate it on a 4x coarser lattice and interpolate bilinearly
  // (the full-resolution evaluation took longer than the whole fit).
  const int step = 4, nc = (size + step - 1) / step + 1;
  std::vector<Vec3> coarse;
  coarse.reserve(std::size_t(nc) * nc);
  for (int j = 0; j < nc; ++j)
    for (int i = 0; i < nc; ++i) coarse.push_back(pixel_point(i * step, j * step));
  const std::vector<double> Pc = potential.Evaluate(coarse);
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      const int i = x / step, j = y / step;
      const double fx = double(x % step) / step, fy = double(y % step) / step;
      auto at = [&](int ii, int jj) { return Pc[std::size_t(jj) * nc + ii]; };
      const double P = (1 - fy) * ((1 - fx) * at(i, j) + fx * at(i + 1, j)) + fy * ((1 - fx) * at(i, j + 1) + fx * at(i + 1, j + 1));
      const auto g = std::uint8_t(std::lround(255 * std::clamp(P, 0.0, 1.0)));
      img.at(x, y) = {g, g, g};
    }
  std::vector<Vec3> points;
  points.reserve(std::size_t(size) * size);
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) points.push_back(pixel_point(x, y));
  // Outline: pixels whose sdf sign differs from a neighbour's.
  auto inside = [&](int x, int y) { return sdf.sample(points[std::size_t(y) * size + x]) < 0; };
  for (int y = 0; y + 1 < size; ++y)
    for (int x = 0; x + 1 < size; ++x)
      if (inside(x, y) != inside(x + 1, y) || inside(x, y) != inside(x, y + 1)) img.at(x, y) = {40, 200, 60};
  const double slab = 2 * sdf.frame.spacing;
  auto draw = [&](const Vec4& r, Rgb c) {
    if (std::abs(r[2]) > slab) return;
    img.disc((r[0] - lo[0]) / side * size, size - (r[1] - lo[1]) / side * size, std::max(2.0, size / 150.0), c);
  };
  for (const Vec4& r : map.top_roots) draw(r, {30, 80, 255});
  for (const Vec4& r : map.bottom_roots) draw(r, {255, 40, 30});
  WritePng(path, img);
}

// The initial map's one-step set {L < 0} on the slice z = 0 against the target: both dark grey,
// set only orange, target only blue; roots within two cells of the slice as discs (top blue,
// bottom red).
void WriteStartSlice(const std::string& path, const ScalarGrid& sdf, const RationalMap& map, int size) {
  const Vec3 lo = sdf.frame.min_corner;
  const double side = sdf.frame.spacing * sdf.frame.dims[0];
  Image img(size, size);
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      const Vec3 p{lo[0] + side * (x + 0.5) / size, lo[1] + side * (size - y - 0.5) / size, 0.0};
      const bool set = OneStepLogModulus(map, p) < 0, inside = sdf.sample(p) < 0;
      img.at(x, y) = set && inside ? Rgb{70, 70, 70} : set ? Rgb{255, 140, 20} : inside ? Rgb{60, 120, 255} : Rgb{255, 255, 255};
    }
  const double slab = 2 * sdf.frame.spacing;
  auto draw = [&](const Vec4& r, Rgb c) {
    if (std::abs(r[2]) > slab) return;
    img.disc((r[0] - lo[0]) / side * size, size - (r[1] - lo[1]) / side * size, std::max(1.5, size / 250.0), c);
  };
  for (const Vec4& r : map.top_roots) draw(r, {30, 80, 255});
  for (const Vec4& r : map.bottom_roots) draw(r, {255, 40, 30});
  WritePng(path, img);
}

}  // namespace

void AddModuleCommands(CLI::App& app) {
  // sdf
  auto so = std::make_shared<SdfCommandOptions>();
  CLI::App* sdf = app.add_subcommand(
      "sdf", "Signed distance field of a mesh (OBJ, PLY, STL, OFF) on the target grid, as .qgrid (and .vdb)");
  sdf->add_option("mesh", so->input, "Input mesh")->required();
  sdf->add_option("-o,--out", so->output, "Output .qgrid (the frame goes to <name>.frame.json)")->required();
  sdf->add_option("--vdb", so->vdb_output, "Also write the field as an OpenVDB level set");
  sdf->add_option("-r,--resolution", so->resolution, "Cells per axis")->capture_default_str()->check(CLI::Range(4, 2048));
  sdf->add_option("--padding", so->padding, "Normalization padding")->capture_default_str();
  sdf->add_option("--fractal-radius", so->fractal_radius, "Fractal frame scale")->capture_default_str();
  sdf->add_option_function<std::string>(
         "--target-box", [so](const std::string& b) { so->box = ParseTargetBox(b); },
         "unit: the whole unit cube, a margin of `padding` around the shape (default); reference: the reference "
         "code's box, the shape plus one cell")
      ->check(CLI::IsMember({"unit", "reference"}));
  sdf->add_option_function<std::string>(
         "--origin", [so](const std::string& o) { so->origin = ParseOriginPlacement(o); },
         "center: the fractal origin at the bounding box's centre (default here); inside: at the point deepest "
         "inside the shape (mesh/normalize.h)")
      ->check(CLI::IsMember({"center", "inside"}));
  sdf->add_flag("--refuse-open", [so](std::int64_t) { so->sdf.allow_open = false; },
                "Refuse meshes with holes instead of signing them by winding numbers");
  sdf->callback([so] { RunSdfCommand(*so); });

  // monopoles
  struct Args {
    std::string mesh, out, fit_target = "reference", initializer = "log-kernel";
    int resolution = 97, png_size = 800;
    MonopoleOptions monopole;
    InitialGuessOptions guess;
    KernelFitOptions kernel;
    double padding = 0.125, fractal_radius = 4.0;
    std::string target_box = "unit", origin = "inside";
  };
  auto a = std::make_shared<Args>();
  a->monopole.target = MonopoleTarget::kOneMinusPotential;
  CLI::App* m = app.add_subcommand(
      "monopoles",
      "The initial guess (2015 paper §4.4): mesh -> SDF -> BEM potential -> greedy monopole fit -> map.json, "
      "with the roots as a coloured PLY and a PNG slice of the potential");
  m->add_option("mesh", a->mesh, "Input mesh")->required();
  m->add_option("-o,--out", a->out, "Output folder")->required();
  m->add_option("-r,--resolution", a->resolution, "Target grid cells per axis")->capture_default_str()->check(CLI::Range(8, 1024));
  m->add_option("--initializer", a->initializer,
                "log-kernel: fit L = ln C + sum e_i log|x - p_i| to the signed distance by least squares (default; "
                "monopole/kernel_fit.h); monopoles: the paper's potential fit with its charges as exponents")
      ->capture_default_str()
      ->check(CLI::IsMember({"log-kernel", "monopoles"}));
  m->add_option("--roots", a->kernel.roots, "log-kernel: at least this many root positions (pairs on the surface normals)")
      ->capture_default_str();
  m->add_option("--max-roots", a->kernel.max_roots,
                "log-kernel: at most this many roots (or --roots, if larger) where the spacing rule asks for more")
      ->capture_default_str();
  m->add_option("--root-spacing", a->kernel.spacing,
                "log-kernel: largest distance between root pairs, in units of their offset (sets how many roots a shape gets)")
      ->capture_default_str();
  m->add_option("--root-offset", a->kernel.offset_cells, "log-kernel: distance of the roots from the surface, in cells")->capture_default_str();
  m->add_option("--band", a->kernel.band_cells, "log-kernel: half-width of the band where L follows the distance, in cells")->capture_default_str();
  m->add_option("--band-amplitude", a->kernel.amplitude, "log-kernel: |L| at the band's edge")->capture_default_str();
  m->add_option("--ridge", a->kernel.ridge, "log-kernel: Tikhonov weight on the exponents")->capture_default_str();
  m->add_option("--refine-rounds", a->kernel.refine_rounds,
                "log-kernel: rounds that add root pairs where the fit is on the wrong side (thin walls)")
      ->capture_default_str();
  m->add_option("--epsilon", a->monopole.fit.epsilon, "Stop at this relative residual")->capture_default_str();
  m->add_option("--fit-target", a->fit_target,
                "reference: fit 1 - P as the reference code (top and bottom roots, the paper's results); "
                "potential: fit P as the paper's text (positive monopoles only)")
      ->capture_default_str()
      ->check(CLI::IsMember({"reference", "potential"}));
  m->add_option("--candidates", a->monopole.sampling.count, "Blue-noise candidates on the surface")->capture_default_str();
  m->add_option("--batch", a->monopole.fit.batch_size, "Fresh candidates per greedy step")->capture_default_str();
  m->add_option("--seed", a->monopole.fit.seed, "Seed of the candidate order")->capture_default_str();
  m->add_option("--sampling-seed", a->monopole.sampling.seed, "Seed of the blue-noise sampling")->capture_default_str();
  m->add_option("--offset", a->monopole.shell.offset_cells, "Offset of the fitting shell, in cells")->capture_default_str();
  m->add_option("--bem-elements", a->monopole.bem.max_elements, "BEM elements (patches)")->capture_default_str();
  m->add_option("--amplitude", a->guess.amplitude, "Exponent multiplier (reference code: 3000, which saturates tanh with our fit; see docs/benchmarks.md)")->capture_default_str();
  m->add_flag("--no-origin-root", [a](std::int64_t) { a->kernel.origin_root = false; },
              "log-kernel: leave out the top root at the fractal origin (monopole/kernel_fit.h)");
  m->add_flag("--no-zero-roots", [a](std::int64_t) { a->guess.leading_zero_roots = false; },
              "Leave out the reference's leading zero roots");
  m->add_option("--scan-resolution", a->guess.scan_resolution, "Grid of the ln C scan")->capture_default_str();
  m->add_option("--padding", a->padding, "Normalization padding")->capture_default_str();
  m->add_option("--fractal-radius", a->fractal_radius, "Fractal frame scale")->capture_default_str();
  m->add_option("--target-box", a->target_box,
                "unit: the whole unit cube, a margin of `padding` around the shape; reference: the reference code's "
                "box, the shape plus one cell (quijibo/frame.h)")
      ->capture_default_str()
      ->check(CLI::IsMember({"unit", "reference"}));
  m->add_option("--origin", a->origin,
                "inside: the fractal origin at the point deepest inside the shape, where iterating the map traps "
                "orbits (default); center: at the bounding box's centre, as the reference code (mesh/normalize.h)")
      ->capture_default_str()
      ->check(CLI::IsMember({"center", "inside"}));
  m->add_option("--png-size", a->png_size, "Pixels per side of potential.png")->capture_default_str()->check(CLI::Range(16, 8192));
  m->callback([a] {
    a->monopole.target = a->fit_target == "reference" ? MonopoleTarget::kOneMinusPotential : MonopoleTarget::kPotential;
    if (auto why = a->monopole.validate(); !why.empty()) throw Error("monopoles: " + why);
    if (auto why = a->guess.validate(); !why.empty()) throw Error("monopoles: " + why);
    MeshReadReport report;
    const TriangleMesh user = ReadMesh(a->mesh, &report);
    FractalFrame frame = NormalizationFor(user, a->padding, a->fractal_radius);
    if (ParseOriginPlacement(a->origin) == OriginPlacement::kInside) frame = PlaceOriginInside(user, frame, a->mesh);
    const TriangleMesh mesh = ToFractalFrame(user, frame);
    SdfOptions sdf_options;
    sdf_options.name = a->mesh;
    const auto t0 = std::chrono::steady_clock::now();
    const ScalarGrid sdf = SignedDistance(mesh, TargetGridFrame(a->resolution, frame, ParseTargetBox(a->target_box)), sdf_options);
    const double sdf_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const bool kernel = a->initializer == "log-kernel";
    MonopoleResult fit;
    RationalMap map;
    LnCScan scan;
    KernelFitSummary kfit;
    double scan_seconds = 0;
    if (kernel) {
      a->kernel.seed = a->monopole.sampling.seed;
      map = KernelFitMap(mesh.vertices, mesh.triangles, sdf, frame, a->kernel, &kfit);
      map.provenance = {{"made_by", "quijibo monopoles"}, {"initializer", "log-kernel"},
                        {"mesh", std::filesystem::path(a->mesh).filename().string()},
                        {"resolution", a->resolution}, {"roots", a->kernel.roots}, {"max_roots", a->kernel.max_roots},
                        {"root_spacing", a->kernel.spacing},
                        {"offset_cells", a->kernel.offset_cells}, {"band_cells", a->kernel.band_cells},
                        {"band_amplitude", a->kernel.amplitude}, {"ridge", a->kernel.ridge},
                        {"origin_root", a->kernel.origin_root}, {"refine_rounds", a->kernel.refine_rounds},
                        {"sampling_seed", a->monopole.sampling.seed}};
    } else {
      Progress progress("monopoles", 1.0, false);
      fit = FitMonopoles(mesh.vertices, mesh.triangles, sdf, a->monopole, [&](const MonopoleProgress& p) {
        if (p.stage == "fit")
          progress.update(std::min(0.99, std::log(p.relative_residual) / std::log(a->monopole.fit.epsilon)),
                          "step " + std::to_string(p.step) + ", residual " + std::to_string(p.relative_residual));
        else
          progress.update(0.0, p.stage + " done");
      });
      progress.finish();
      const auto t1 = std::chrono::steady_clock::now();
      map = InitialMap(fit.monopoles, frame, sdf, a->guess, &scan);
      scan_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count();
      map.provenance = {{"made_by", "quijibo monopoles"}, {"initializer", "monopoles"},
                        {"mesh", std::filesystem::path(a->mesh).filename().string()},
                        {"resolution", a->resolution}, {"epsilon", a->monopole.fit.epsilon},
                        {"fit_target", a->fit_target}, {"candidates", a->monopole.sampling.count},
                        {"seed", a->monopole.fit.seed}, {"sampling_seed", a->monopole.sampling.seed},
                        {"amplitude", a->guess.amplitude}, {"relative_residual", fit.fit.final_relative_residual},
                        {"monopoles", fit.monopoles.size()}};
    }
    const StartCheck start = CheckStart(map, sdf, a->guess.alpha);
    if (start.inverted)
      std::fprintf(stderr,
                   "quijibo: warning: the initial map is inverted: L is not lower inside the shape than outside "
                   "(medians %.3g inside, %.3g outside); the optimizer may not recover\n",
                   start.median_inside, start.median_outside);
    // Everything computed: now write.
    std::filesystem::create_directories(a->out);
    const std::string dir = a->out + "/";
    ScalarGrid target = sdf;
    WriteGrid(dir + "target.qgrid", target);
    WriteFrameJson(FrameJsonPathFor(dir + "target.qgrid"), frame, a->mesh, a->resolution);
    WriteMap(dir + "map.json", map);
    WriteRootsPly(dir + "roots.ply", map, true);
    const auto t2 = std::chrono::steady_clock::now();
    if (kernel)
      WriteStartSlice(dir + "start.png", sdf, map, a->png_size);
    else
      WritePotentialSlice(dir + "potential.png", *fit.potential, sdf, map, a->png_size);
    const double png_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t2).count();
    json summary = {
        {"mesh", a->mesh}, {"initializer", a->initializer}, {"triangles", mesh.triangles.size()},
        {"degenerate_dropped", report.degenerate_dropped},
        {"top_roots", map.top_count()}, {"bottom_roots", map.bottom_count()}, {"ln_C", map.ln_C},
        {"start", {{"median_L_inside", start.median_inside}, {"median_L_outside", start.median_outside},
                   {"iou", start.iou}, {"saturated_fraction", start.saturated}, {"inverted", start.inverted}}}};
    if (kernel) {
      summary["log_kernel"] = {{"rows", kfit.rows}, {"band_rows", kfit.band_rows}, {"far_rows", kfit.far_rows},
                               {"active_set_iterations", kfit.iterations}, {"refine_rounds", kfit.refine_rounds}, {"top", kfit.top},
                               {"bottom", kfit.bottom}, {"exponent_sum", kfit.exponent_sum},
                               {"spacing", kfit.spacing}, {"rms_band", kfit.rms_band}, {"sign_agreement", kfit.sign_agreement}};
      summary["seconds"] = {{"sdf", sdf_seconds}, {"fit", kfit.seconds}, {"png", png_seconds}};
    } else {
      summary.update(json{{"monopoles", fit.monopoles.size()}, {"positive", fit.positive_count()},
                          {"negative", fit.negative_count()}, {"relative_residual", fit.fit.final_relative_residual},
                          {"steps", fit.fit.steps}, {"shell_points", fit.shell_points}, {"candidates", fit.candidates},
                          {"bem_elements", fit.bem.elements}});
      summary["seconds"] = {{"sdf", sdf_seconds}, {"bem", fit.seconds.bem}, {"shell", fit.seconds.shell},
                            {"potential", fit.seconds.potential}, {"sampling", fit.seconds.sampling},
                            {"fit", fit.seconds.fit}, {"ln_C_scan", scan_seconds}, {"png", png_seconds}};
    }
    WriteFileAtomically(dir + "monopoles.json", summary.dump(1) + "\n");
    std::printf("%s\n", summary.dump(1).c_str());
  });

  // bench stages: the monopole stage's parts, timed on real meshes.
  struct BenchArgs {
    std::vector<std::string> meshes{"data/bunny.obj", "data/tooth.obj"};
    int resolution = 97, repeats = 3;
    std::string fit_target = "reference", out_md, out_json;
  };
  auto b = std::make_shared<BenchArgs>();
  CLI::App* bench = app.get_subcommand("bench");
  CLI::App* st = bench->add_subcommand(
      "stages", "Seconds of each part of the initial guess (mesh read, SDF, BEM, shell, P on the shell, "
                "candidates, greedy fit, ln C scan) per mesh, median of repeats, and the process's peak memory");
  st->add_option("meshes", b->meshes, "Meshes")->capture_default_str();
  st->add_option("-r,--resolution", b->resolution, "Target grid")->capture_default_str()->check(CLI::Range(8, 1024));
  st->add_option("--repeats", b->repeats, "Runs per mesh (the median is reported)")->capture_default_str()->check(CLI::Range(1, 100));
  st->add_option("--fit-target", b->fit_target, "reference (1 - P) or potential (P)")
      ->capture_default_str()->check(CLI::IsMember({"reference", "potential"}));
  st->add_option("--markdown", b->out_md, "Also write the Markdown table here");
  st->add_option("--json", b->out_json, "Also write the results as JSON here");
  st->callback([b] {
    using Clock = std::chrono::steady_clock;
    auto since = [](Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); };
    auto median = [](std::vector<double> v) {
      std::sort(v.begin(), v.end());
      return v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
    };
    const char* names[] = {"read", "sdf", "bem", "shell", "potential", "candidates", "fit", "ln_C_scan", "total"};
    std::string md = "| mesh | triangles | BEM elements | monopoles (top/bottom) |";
    for (const char* n : names) md += std::string(" ") + n + " s |";
    md += "\n|---|---|---|---|";
    for (std::size_t i = 0; i < std::size(names); ++i) md += "---|";
    md += "\n";
    json results = json::array();
    for (const std::string& path : b->meshes) {
      std::vector<std::vector<double>> t(std::size(names));
      MonopoleResult last;
      std::int64_t triangles = 0;
      RationalMap map;
      for (int r = 0; r < b->repeats; ++r) {
        const auto t0 = Clock::now();
        const TriangleMesh user = ReadMesh(path);
        const FractalFrame frame = NormalizationFor(user);
        const TriangleMesh mesh = ToFractalFrame(user, frame);
        t[0].push_back(since(t0));
        auto t1 = Clock::now();
        const ScalarGrid sdf = SignedDistance(mesh, TargetGridFrame(b->resolution, frame));
        t[1].push_back(since(t1));
        MonopoleOptions mo;
        mo.target = b->fit_target == "reference" ? MonopoleTarget::kOneMinusPotential : MonopoleTarget::kPotential;
        last = FitMonopoles(mesh.vertices, mesh.triangles, sdf, mo);
        t[2].push_back(last.seconds.bem), t[3].push_back(last.seconds.shell), t[4].push_back(last.seconds.potential);
        t[5].push_back(last.seconds.sampling), t[6].push_back(last.seconds.fit);
        t1 = Clock::now();
        map = InitialMap(last.monopoles, frame, sdf, InitialGuessOptions{});
        t[7].push_back(since(t1));
        t[8].push_back(since(t0));
        triangles = std::int64_t(mesh.triangles.size());
      }
      json row = {{"mesh", path}, {"triangles", triangles}, {"bem_elements", last.bem.elements},
                  {"top_roots", map.top_count()}, {"bottom_roots", map.bottom_count()},
                  {"relative_residual", last.fit.final_relative_residual}};
      md += "| " + std::filesystem::path(path).filename().string() + " | " + std::to_string(triangles) + " | " +
            std::to_string(last.bem.elements) + " | " + std::to_string(map.top_count()) + "/" +
            std::to_string(map.bottom_count()) + " |";
      for (std::size_t i = 0; i < std::size(names); ++i) {
        const double m = median(t[i]);
        row["median_seconds"][names[i]] = m;
        char buf[32];
        std::snprintf(buf, sizeof buf, " %.2f |", m);
        md += buf;
      }
      md += "\n";
      results.push_back(row);
    }
    rusage ru{};
    ::getrusage(RUSAGE_SELF, &ru);
    const std::time_t now = std::time(nullptr);
    char date[32];
    std::strftime(date, sizeof date, "%Y-%m-%d", std::gmtime(&now));
    const int cores = int(::sysconf(_SC_NPROCESSORS_ONLN));
    const std::string header = "Initial-guess stages, " + std::string(date) + ", " + std::to_string(cores) +
                               " cores, " + std::to_string(b->resolution) + "^3 target, fit of " +
                               (b->fit_target == "reference" ? "1 - P" : "P") + ", median of " +
                               std::to_string(b->repeats) + " runs; peak memory " +
                               std::to_string(ru.ru_maxrss / 1024) + " MB.\n\n";
    const json doc = {{"benchmark", "stages"}, {"date", date}, {"cores", cores}, {"resolution", b->resolution},
                      {"repeats", b->repeats}, {"fit_target", b->fit_target},
                      {"peak_memory_mb", ru.ru_maxrss / 1024.0}, {"results", results}};
    if (!b->out_md.empty()) WriteFileAtomically(b->out_md, header + md);
    if (!b->out_json.empty()) WriteFileAtomically(b->out_json, doc.dump(1) + "\n");
    std::fputs((header + md).c_str(), stdout);
  });
}

}  // namespace quijibo::cli
