#include "experiments/pipeline/compare.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>

#include "mesh/fidelity.h"
#include "mesh/julia_field.h"
#include "mesh/marching_cubes.h"
#include "methods/modulus_target.h"
#include "mesh/pictures.h"
#include "mesh/frame_file.h"
#include "quijibo/energy.h"
#include "util/error.h"
#include "util/io.h"
#include "quijibo/iou.h"
#include "util/json_reader.h"
#include "methods/mask.h"
#include "quijibo/target.h"

namespace quijibo::pipeline {

using nlohmann::json;

const Schema<CompareOptions>& CompareOptions::Settings() {
  using O = CompareOptions;
  static const Schema<O> s =
      Schema<O>()
          .Integer(
              "modulus_iterations", "--sm-iterations", "Shape modulus iterations",
              [](auto& o) -> int& { return o.modulus_iteration.iterations; }, 1, 100000)
          .Number(
              "modulus_escape", "--sm-escape", "Shape modulus escape radius",
              [](auto& o) -> double& { return o.modulus_iteration.escape_radius; }, 0, 1e300, true)
          .Integer(
              "quijibo_iterations", "--quijibo-iterations", "QUIJIBO iterations",
              [](auto& o) -> int& { return o.quijibo_iteration.iterations; }, 1, 100000)
          .Number(
              "quijibo_escape", "--quijibo-escape", "QUIJIBO escape radius",
              [](auto& o) -> double& { return o.quijibo_iteration.escape_radius; }, 0, 1e300, true)
          .Number(
              "quijibo_seconds", "--quijibo-seconds", "QUIJIBO fit time (else summary.json next to the map)",
              [](auto& o) -> std::optional<double>& { return o.quijibo_seconds; }, 0, 1e12)
          .Number(
              "energy_alpha", "--energy-alpha", "tanh sharpness of psi (2015: 10)",
              [](auto& o) -> double& { return o.energy_alpha; }, 0, 1e6, true)
          .Choice("weights", "--weights", "Weight field of psi: layer or inverse",
                  [](auto& o) -> std::string& { return o.weights; }, {"layer", "inverse", "balanced"})
          .Integer(
              "resolution", "-r,--resolution", "Marching cubes cells along the grid box",
              [](auto& o) -> int& { return o.resolution; }, 4, 8192)
          .Integer(
              "samples", "--samples", "Surface samples per mesh for Chamfer", [](auto& o) -> int& { return o.samples; },
              1, 100000000)
          .Integer(
              "png_size", "--png-size", "Pixels of each slice picture", [](auto& o) -> int& { return o.png_size; }, 8,
              32768);
  return s;
}

std::string CompareOptions::Validate() const {
  if (std::string why = Settings().Check(*this); !why.empty()) return why;
  if (std::string why = modulus.Validate(); !why.empty()) return why;
  if (std::string why = modulus_iteration.Validate(); !why.empty()) return why;
  return quijibo_iteration.Validate();
}

namespace {

// QUIJIBO's fit time: the option, else the optimizer's summary.json next to the map, else null.
json QuijiboFitSeconds(const CompareOptions& o) {
  if (o.quijibo_seconds) return *o.quijibo_seconds;
  const auto summary = std::filesystem::path(o.map).parent_path() / "summary.json";
  if (!std::filesystem::exists(summary)) return nullptr;
  const json sj = ParseJson(ReadFile(summary.string()), summary.string());
  JsonReader sr(sj, summary.string());
  return sr.has("/seconds") ? json(sr.number("/seconds")) : json(nullptr);
}

// The shape modulus "fit": the target in the unit frame (k unit lengths per fractal-frame one)
// and its versor, timed.
struct ModulusFit {
  double k = 1;
  ShapeModulusOptions shape;
  Versor versor;
  std::shared_ptr<const ShapeModulusMap> map;
  double seconds = 0;
};

ModulusFit FitModulus(const CompareOptions& o, const std::shared_ptr<const ScalarGrid>& grid) {
  const double t0 = WallSeconds();
  FractalFrame f;
  if (std::filesystem::exists(mesh::FrameJsonPathFor(o.target))) f = mesh::ReadFrameJson(mesh::FrameJsonPathFor(o.target));
  ModulusFit fit;
  ModulusTarget target = ModulusTargetFromGrid(grid, f.fractal_radius, f.padding, &fit.k);
  fit.versor = o.modulus.versor.Make(target);
  fit.shape = o.modulus.shape;
  if (o.modulus.params) mesh::ReadModulusParams(*o.modulus.params, fit.shape, o.modulus.sdf_resolution);
  fit.map = std::make_shared<ShapeModulusMap>(target, fit.versor, fit.shape);
  fit.seconds = WallSeconds() - t0;
  return fit;
}

// A method's fields on the energy grid's cells: one application (the 2015 energy's L) and n iterates.
struct MethodFields {
  std::vector<double> one, iterated;
};

// Both methods' fields, QUIJIBO's at the cells (fractal frame), the shape modulus's at k times them.
std::pair<MethodFields, MethodFields> SampleFields(const EnergyGrid& eg, const RationalQuaternionMap& qj,
                                                  const IterationOptions& qjo, const ModulusFit& sm,
                                                  const IterationOptions& sjo) {
  const std::int64_t cells = eg.frame.cell_count();
  MethodFields q{std::vector<double>(cells), std::vector<double>(cells)};
  MethodFields s{std::vector<double>(cells), std::vector<double>(cells)};
  const double k = sm.k;
#pragma omp parallel for schedule(dynamic, 1024)
  for (std::int64_t c = 0; c < cells; ++c) {
    const Vec3 w = eg.frame.cell_center(c);
    const Quat qw{w[0], w[1], w[2], eg.slice}, qu{k * w[0], k * w[1], k * w[2], 0.0};
    q.one[c] = qj.LogModulus(qw);
    q.iterated[c] = IterateField(qj, qw, qjo);
    s.one[c] = sm.map->LogModulus(qu);
    s.iterated[c] = IterateField(*sm.map, qu, sjo);
  }
  return {std::move(q), std::move(s)};
}

// A mesh with its wall and CPU seconds.
struct TimedMesh {
  mesh::TriangleMesh mesh;
  double seconds = 0, cpu_seconds = 0;
};

TimedMesh MeshTimed(const mesh::BatchField& field, const mesh::MeshingOptions& mo) {
  const double m0 = WallSeconds(), c0 = CpuSeconds();
  TimedMesh t;
  t.mesh = mesh::MeshField(field, mo);
  t.seconds = WallSeconds() - m0, t.cpu_seconds = CpuSeconds() - c0;
  return t;
}

// The meshing box: the target grid's, in the fractal frame.
mesh::MeshingOptions GridBox(const ScalarGrid& grid, int resolution) {
  mesh::MeshingOptions mo;
  mo.min_corner = grid.frame.min_corner;
  for (int ax = 0; ax < 3; ++ax) mo.max_corner[ax] = mo.min_corner[ax] + grid.frame.extent()[ax];
  mo.resolution = resolution;
  return mo;
}

// The sample Chamfer of a method's mesh against the target's samples (nulls without a surface).
json ChamferJson(const mesh::TriangleMesh& m, const std::vector<Vec3>& target_samples, int samples) {
  const auto ms = mesh::SampleSurface(m, samples, 2);
  if (ms.empty()) return {{"to_target", nullptr}, {"from_target", nullptr}, {"chamfer", nullptr}};
  const mesh::SampleChamfer c = mesh::MeasureSampleChamfer(ms, target_samples);
  return {{"to_target", c.to_target}, {"from_target", c.from_target}, {"chamfer", c.sum()}};
}

// One method's entry of compare.json.
json MethodJson(const std::string& name, const json& fit_seconds, const EnergyGrid& eg, double alpha,
                const MethodFields& fields, const ScalarGrid& grid, const json& chamfer, const TimedMesh& m,
                const std::string& picture, const std::string& ply) {
  return json{{"method", name},
              {"fit_seconds", fit_seconds},
              {"psi_one_application", EnergyOfField(eg, fields.one, alpha)},
              {"psi_iterated", EnergyOfField(eg, fields.iterated, alpha)},
              {"iou", InsideIntersectionOverUnion(fields.iterated, grid.values)},
              {"chamfer", chamfer},
              {"triangles", m.mesh.triangles.size()},
              {"mesh_seconds", m.seconds},
              {"mesh_cpu_seconds", m.cpu_seconds},
              {"picture", picture},
              {"mesh", ply}};
}

// compare.md: the table of the two methods' figures in `report`.
std::string CompareMarkdown(const CompareOptions& o, const ScalarGrid& grid, double diag, const json& report) {
  auto num = [](const json& j, int prec = 4) {
    if (j.is_null()) return std::string("n/a");
    char b[64];
    std::snprintf(b, sizeof b, "%.*g", prec, j.get<double>());
    return std::string(b);
  };
  std::ostringstream md;
  md << "# QUIJIBO vs shape modulus on " << o.target << "\n\n"
     << "Map: `" << o.map << "`. Grid " << grid.frame.dims[0] << "x" << grid.frame.dims[1] << "x"
     << grid.frame.dims[2] << " (the target SDF's cells). psi: 2015 energy, tanh sharpness " << o.energy_alpha << ", "
     << o.weights << " weights. Chamfer in fractal-frame units (box diagonal " << num(diag)
     << "), mean nearest-sample distance each way, " << o.samples << " samples per mesh; meshes at " << o.resolution
     << " cells. Inside = log|q_n| < 0.\n\n"
     << "| | QUIJIBO | shape modulus |\n|---|---:|---:|\n";
  const json& q = report["methods"][0];
  const json& s = report["methods"][1];
  md << "| time to fit (s) | " << num(q["fit_seconds"]) << " | " << num(s["fit_seconds"]) << " |\n"
     << "| psi, one application (2015 energy) | " << num(q["psi_one_application"]) << " | "
     << num(s["psi_one_application"]) << " |\n"
     << "| psi, n iterates | " << num(q["psi_iterated"]) << " | " << num(s["psi_iterated"]) << " |\n"
     << "| IoU inside vs target (grid) | " << num(q["iou"]) << " | " << num(s["iou"]) << " |\n"
     << "| Chamfer to + from target | " << num(q["chamfer"]["chamfer"]) << " | " << num(s["chamfer"]["chamfer"])
     << " |\n"
     << "| triangles | " << q["triangles"].get<std::size_t>() << " | " << s["triangles"].get<std::size_t>() << " |\n"
     << "| meshing wall / CPU (s) | " << num(q["mesh_seconds"]) << " / " << num(q["mesh_cpu_seconds"]) << " | "
     << num(s["mesh_seconds"]) << " / " << num(s["mesh_cpu_seconds"]) << " |\n"
     << "| picture (slice z = 0; red = target) | ![](quijibo.png) | ![](modulus.png) |\n";
  return md.str();
}

}  // namespace

CompareResult Compare(const CompareOptions& o) {
  if (std::string why = o.Validate(); !why.empty()) throw Error("compare: " + why);
  const RationalMap rmap = ReadMap(o.map);
  mesh::CheckSameFrame(rmap.frame, o.map, o.target);
  const auto grid = std::make_shared<const ScalarGrid>(ReadGrid(o.target));
  const json qj_fit = QuijiboFitSeconds(o);
  const ModulusFit sm = FitModulus(o, grid);
  const auto qj = std::make_shared<const RationalQuaternionMap>(rmap);
  const IterationOptions& sjo = o.modulus_iteration;
  const IterationOptions& qjo = o.quijibo_iteration;
  const EnergyGrid eg = MakeEnergyGrid(*grid, ParseWeightField(o.weights));
  const auto [qj_fields, sm_fields] = SampleFields(eg, *qj, qjo, sm, sjo);

  // Meshes over the grid's box, in the fractal frame (the shape modulus's field scales by k).
  const mesh::MeshingOptions mo = GridBox(*grid, o.resolution);
  mesh::BatchField target_field;
  target_field.evaluate = [grid](const Vec3* p, std::size_t n, double* out) {
    for (std::size_t i = 0; i < n; ++i) out[i] = ExtendedSample(*grid, p[i]);
  };
  const mesh::TriangleMesh target_mesh = mesh::MeshField(target_field, mo);
  TimedMesh qj_mesh = MeshTimed(mesh::MakeQuaternionMapField(qj, qjo, 1.0), mo);
  TimedMesh sm_mesh = MeshTimed(mesh::MakeQuaternionMapField(sm.map, sjo, sm.k), mo);
  const auto ts = mesh::SampleSurface(target_mesh, o.samples, 1);

  CompareResult result;
  result.quijibo.picture = mesh::InsideSlice(
      [&](const Vec3& p) { return IterateField(*qj, {p[0], p[1], p[2], 0}, qjo); }, *grid, o.png_size);
  result.modulus.picture = mesh::InsideSlice(
      [&](const Vec3& p) { return IterateField(*sm.map, {sm.k * p[0], sm.k * p[1], sm.k * p[2], 0}, sjo); }, *grid,
      o.png_size);
  const double diag = std::hypot(grid->frame.extent()[0], grid->frame.extent()[1], grid->frame.extent()[2]);
  result.report = {
      {"target", o.target},
      {"map", o.map},
      {"grid", {{"dims", grid->frame.dims}, {"spacing", grid->frame.spacing}, {"box_diagonal", diag}}},
      {"energy", {{"alpha", o.energy_alpha}, {"weights", o.weights}, {"eta", eg.eta}}},
      {"mesh_resolution", o.resolution},
      {"unit_per_fractal", sm.k},
      {"shape_modulus",
       {{"alpha", ParameterFieldToJson(sm.shape.alpha)},
        {"beta", ParameterFieldToJson(sm.shape.beta)},
        {"iterations", sjo.iterations},
        {"escape_radius", sjo.escape_radius},
        {"versor", sm.versor.polynomial.description}}},
      {"quijibo", {{"iterations", qjo.iterations}, {"escape_radius", qjo.escape_radius}}},
      {"target_mesh_triangles", target_mesh.triangles.size()},
      {"methods", json::array({MethodJson("QUIJIBO", qj_fit, eg, o.energy_alpha, qj_fields, *grid,
                                          ChamferJson(qj_mesh.mesh, ts, o.samples), qj_mesh, "quijibo.png",
                                          "quijibo.ply"),
                               MethodJson("shape modulus", sm.seconds, eg, o.energy_alpha, sm_fields, *grid,
                                          ChamferJson(sm_mesh.mesh, ts, o.samples), sm_mesh, "modulus.png",
                                          "modulus.ply")})}};
  result.markdown = CompareMarkdown(o, *grid, diag, result.report);
  result.quijibo.mesh = std::move(qj_mesh.mesh);
  result.modulus.mesh = std::move(sm_mesh.mesh);
  return result;
}

void WriteCompare(const CompareResult& r, const std::string& out_dir) {
  Outputs outs;
  std::filesystem::create_directories(out_dir);
  auto path = [&](const std::string& n) { return (std::filesystem::path(out_dir) / n).string(); };
  WritePng(path("quijibo.png"), r.quijibo.picture), outs.Add(path("quijibo.png"));
  WritePng(path("modulus.png"), r.modulus.picture), outs.Add(path("modulus.png"));
  mesh::WritePly(path("quijibo.ply"), r.quijibo.mesh), outs.Add(path("quijibo.ply"));
  mesh::WritePly(path("modulus.ply"), r.modulus.mesh), outs.Add(path("modulus.ply"));
  WriteFileAtomically(path("compare.json"), r.report.dump(1) + "\n"), outs.Add(path("compare.json"));
  WriteFileAtomically(path("compare.md"), r.markdown), outs.Add(path("compare.md"));
  outs.Commit();
}

}  // namespace quijibo::pipeline
