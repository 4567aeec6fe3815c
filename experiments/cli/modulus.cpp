// `quijibo modulus`, `quijibo portal`, `quijibo compare` and `quijibo bench modulus`: the shape
// modulus (2023) and portals (2024), in 2D (PNG) and 3D (PLY through the shared mesher), and a
// side-by-side comparison with a QUIJIBO map, bound to the pipeline's stages
// (experiments/pipeline/modulus.h, portal.h, compare.h). Conventions: docs/modulus-portals.md.
#include <omp.h>

#include <algorithm>
#include <cstdio>

#include "experiments/cli/bind.h"
#include "experiments/cli/cli.h"
#include "experiments/pipeline/compare.h"
#include "experiments/pipeline/julia_set.h"
#include "experiments/pipeline/modulus.h"
#include "experiments/pipeline/portal.h"
#include "experiments/pipeline/product.h"
#include "mesh/julia_field.h"
#include "methods/modulus_target.h"
#include "util/error.h"
#include "util/io.h"

namespace quijibo::cli {

using nlohmann::json;

namespace {

// The versor's and the output's options (the output's format follows -o's extension).
void AddVersorOptions(CLI::App* c, pipeline::VersorOptions& v, std::string* write_poly) {
  BindSettings(c, v);
  if (write_poly) c->add_option("--write-poly", *write_poly, "Write the (generated) polynomial here");
  c->add_option("--noise-versor", v.noise_frequency, "Use a noise versor of this frequency instead of a polynomial");
  c->add_option("--noise-octaves", v.noise_octaves, "Octaves of the noise versor")->capture_default_str()->check(CLI::Range(1, 16));
}

void AddOutputOptions(CLI::App* c, std::string& out, pipeline::ProductOutputOptions& o) {
  c->add_option("-o,--out", out, ".png (2D, complex plane) or .ply (3D mesh)")->required();
  BindSettings(c, o);
  AddMesherOptions(c, o.meshing);
}

void AddModulusCommand(CLI::App& app) {
  struct Args {
    std::string target, out, write_poly;
    pipeline::ModulusStageOptions o;
  };
  auto a = std::make_shared<Args>();
  CLI::App* c = app.add_subcommand("modulus",
                                   "Shape modulus Julia set (Schor and Kim 2023) of a target: 2D PNG or 3D PLY");
  c->add_option("target", a->target, "Mesh (.obj/.ply/.stl/.off), .qgrid from `quijibo sdf`, or sphere/disc/hexagram")
      ->required();
  BindSettings(c, a->o);
  c->add_flag("--2d", a->o.two_d, "Complex plane (slice z = 0 of a 3D target); implied by a .png output");
  c->add_option("--authors-frame", a->o.authors_frame,
                "Compatibility: reproduce the authors' program from its own inputs (docs/modulus-portals.md): "
                "read the target as it reads its SDF file (x and z swapped, stretched by (NODES-1)/RES; RES = "
                "their sdfGen resolution, NODES = nodes per side of their .f3d, default RES), and take --alpha, "
                "--beta (and --params values) as their a and b: distances in the mesh file's units, "
                "exp(a (d - b)); the report's alpha and beta are the converted a/s and -b s")
      ->expected(1, 2)
      ->delimiter(',');
  AddVersorOptions(c, a->o.versor, &a->write_poly);
  AddOutputOptions(c, a->out, a->o.output);
  c->callback([a] {
    const pipeline::ModulusStageResult r = pipeline::Modulus(a->target, a->o, a->out);
    pipeline::WriteModulus(r, a->out, a->write_poly);
    std::printf("%s\n", r.report.dump(1).c_str());
  });
}

void AddPortalCommand(CLI::App& app) {
  struct Args {
    std::string spec, out, write_spec, write_poly;
    pipeline::PortalStageOptions o;
  };
  auto a = std::make_shared<Args>();
  CLI::App* c = app.add_subcommand("portal", "Portals (Schor and Kim 2024) in a shape modulus or QUIJIBO map: 2D PNG or 3D PLY");
  c->add_option("spec", a->spec, "Portal spec JSON (docs/modulus-portals.md)");
  BindSettings(c, a->o);
  c->add_option("--write-spec", a->write_spec, "Also write the spec used (e.g. the preset) here");
  c->add_option("--write-poly", a->write_poly, "Write the generated versor polynomial here");
  AddOutputOptions(c, a->out, a->o.output);
  c->callback([a] {
    a->o.spec_file = a->spec;
    const pipeline::PortalStageResult r = pipeline::Portal(a->o, a->out);
    pipeline::WritePortal(r, a->out, a->write_spec, a->write_poly);
    std::printf("%s\n", r.report.dump(1).c_str());
  });
}

void AddJuliaCommand(CLI::App& app) {
  struct Args {
    std::string out;
    pipeline::JuliaSetStageOptions o;
  };
  auto a = std::make_shared<Args>();
  CLI::App* c = app.add_subcommand(
      "julia", "The Julia set of a map of any kind (q^d + c, a QUIJIBO map, ...; docs/map-kinds.md): 2D PNG or 3D PLY");
  c->add_option("map", a->o.map_file, "Map JSON: {\"kind\": ..., ...} (docs/map-kinds.md)")->required();
  AddOutputOptions(c, a->out, a->o.output);
  c->callback([a] {
    a->o.output.format = HasExtension(a->out, ".ply") ? "ply" : "png";
    const pipeline::JuliaSetStageResult r = pipeline::JuliaSet(a->o);
    pipeline::WriteProduct(r.product, a->out);
    std::printf("%s\n", r.report.dump(1).c_str());
  });
}

void AddCompareCommand(CLI::App& app) {
  struct Args {
    pipeline::CompareOptions o;
    std::string out;
  };
  auto a = std::make_shared<Args>();
  CLI::App* c = app.add_subcommand(
      "compare", "QUIJIBO map vs shape modulus on one target: fit time, psi, IoU, Chamfer, pictures");
  c->add_option("--target", a->o.target, ".qgrid from `quijibo sdf` (fractal frame; its .frame.json is used)")->required();
  c->add_option("--map", a->o.map, "QUIJIBO map.json (fractal frame)")->required();
  BindSettings(c, a->o.modulus.versor, {"poly"});
  BindSettings(c, a->o.modulus, {"params", "alpha", "beta"});
  BindSettings(c, a->o);
  c->add_option("-o,--out", a->out, "Output folder (compare.md, compare.json, PNGs, PLYs)")->required();
  c->callback([a] {
    const pipeline::CompareResult r = pipeline::Compare(a->o);
    pipeline::WriteCompare(r, a->out);
    std::printf("%s", r.markdown.c_str());
  });
}

struct BenchModulusArgs {
  std::string target = "data/bunny.obj", poly = "data/sm-baseline-poly10.json", out_json;
  int resolution = 400, sdf_resolution = 100, repeats = 1, iterations = 3;
  double alpha = 30, beta = -0.02, escape = 20;
  bool mesh = false;
};

// `quijibo bench modulus`: the dense field's cost (and the mesher's, with --mesh), as JSON.
void BenchModulus(const BenchModulusArgs& a) {
  mesh::LoadedTarget lt = mesh::LoadModulusTarget(a.target, a.sdf_resolution);
  Versor v;
  v.polynomial = ReadVersorPolynomial(a.poly);
  ShapeModulusOptions so;
  so.alpha = a.alpha;
  so.beta = a.beta;
  auto map = std::make_shared<ShapeModulusMap>(lt.target, v, so);
  IterationOptions jo{a.iterations, a.escape};
  const int n = a.resolution;
  // The authors' node placement: min + i span / res, i < res, on [-0.5, 0.5]^3.
  std::vector<double> wall, cpu;
  std::int64_t inside = 0;
  std::vector<std::int64_t> iters(a.iterations + 1, 0);
  for (int rep = 0; rep < a.repeats; ++rep) {
    const double w0 = pipeline::WallSeconds(), c0 = pipeline::CpuSeconds();
    std::int64_t in = 0;
    std::vector<std::int64_t> it(a.iterations + 1, 0);
#pragma omp parallel
    {
      std::vector<std::int64_t> local(a.iterations + 1, 0);
      std::int64_t lin = 0;
#pragma omp for schedule(dynamic, 1) collapse(2)
      for (int z = 0; z < n; ++z)
        for (int y = 0; y < n; ++y)
          for (int x = 0; x < n; ++x) {
            int used = 0;
            const double f = IterateField(*map, {-0.5 + double(x) / n, -0.5 + double(y) / n, -0.5 + double(z) / n, 0.0}, jo, &used);
            lin += f < 0;
            ++local[used];
          }
#pragma omp critical
      {
        in += lin;
        for (int i = 0; i <= a.iterations; ++i) it[i] += local[i];
      }
    }
    wall.push_back(pipeline::WallSeconds() - w0);
    cpu.push_back(pipeline::CpuSeconds() - c0);
    inside = in;
    iters = it;
  }
  auto median = [](std::vector<double> x) {
    std::sort(x.begin(), x.end());
    return x[x.size() / 2];
  };
  const double nodes = double(n) * n * n;
  json rep = {{"target", a.target}, {"poly", a.poly}, {"resolution", n}, {"nodes", nodes},
              {"alpha", a.alpha}, {"beta", a.beta}, {"iterations", a.iterations}, {"escape_radius", a.escape},
              {"repeats", a.repeats}, {"threads", omp_get_max_threads()},
              {"wall_seconds_median", median(wall)}, {"cpu_seconds_median", median(cpu)},
              {"cpu_us_per_node", 1e6 * median(cpu) / nodes}, {"inside_nodes", inside},
              {"iterations_histogram", iters}};
  if (a.mesh) {
    // The shape modulus stage's 3D product (the shared mesher) on the same box and resolution.
    pipeline::ProductOutputOptions po;
    po.format = "ply";
    po.meshing.resolution = n;
    po.box = std::vector<double>{-0.5, -0.5, -0.5, 0.5, 0.5, 0.5};
    const pipeline::Product p = pipeline::Produce(map, po, jo, lt.target, false);
    const double w = p.report["seconds"], c = p.report["cpu_seconds"];
    const std::size_t triangles = p.mesh.triangles.size();
    rep["mesh"] = {{"triangles", triangles}, {"wall_seconds", w}, {"cpu_seconds", c},
                   {"cpu_us_per_triangle", 1e6 * c / std::max<double>(1, double(triangles))},
                   {"reference_cpu_us_per_triangle", 1e6 * 338.1 / 2381944},
                   {"nodes_evaluated", p.report["nodes_evaluated"]},
                   {"bisection_evaluations", p.report["bisection_evaluations"]}, {"summary", p.report}};
  }
  if (!a.out_json.empty()) WriteFileAtomically(a.out_json, rep.dump(1) + "\n");
  std::printf("%s\n", rep.dump(1).c_str());
}

void AddBenchModulusCommand(CLI::App* bench) {
  auto a = std::make_shared<BenchModulusArgs>();
  CLI::App* b = bench->add_subcommand(
      "modulus", "Shape modulus field cost: dense res^3 evaluation (OpenMP), CPU seconds via getrusage");
  b->add_option("--target", a->target, "Target mesh")->capture_default_str();
  b->add_option("--poly", a->poly, "Versor polynomial")->capture_default_str();
  b->add_option("-r,--resolution", a->resolution, "Nodes per side of [-0.5,0.5]^3")->capture_default_str()->check(CLI::Range(2, 4096));
  b->add_option("--sdf-resolution", a->sdf_resolution, "SDF cells")->capture_default_str();
  b->add_option("--alpha", a->alpha, "alpha")->capture_default_str();
  b->add_option("--beta", a->beta, "beta (paper's sign)")->capture_default_str();
  b->add_option("--iterations", a->iterations, "iterations")->capture_default_str();
  b->add_option("--escape", a->escape, "escape radius")->capture_default_str();
  b->add_option("--repeats", a->repeats, "Repeats (median reported)")->capture_default_str()->check(CLI::Range(1, 20));
  b->add_flag("--mesh", a->mesh, "Also mesh the set at the same resolution (the modulus stage's mesher) and report CPU per triangle");
  b->add_option("--json", a->out_json, "Write the results here");
  b->callback([a] { BenchModulus(*a); });
}

}  // namespace

void AddModulusCommands(CLI::App& app, CLI::App& bench) {
  AddModulusCommand(app);
  AddPortalCommand(app);
  AddJuliaCommand(app);
  AddCompareCommand(app);
  AddBenchModulusCommand(&bench);
}

}  // namespace quijibo::cli
