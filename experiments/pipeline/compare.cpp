#include "experiments/pipeline/compare.h"

#include <omp.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>

#include "mesh/fidelity.h"
#include "mesh/julia_field.h"
#include "mesh/marching_cubes.h"
#include "mesh/modulus_target.h"
#include "mesh/pictures.h"
#include "mesh/sdf_command.h"
#include "quijibo/energy.h"
#include "quijibo/error.h"
#include "quijibo/io.h"
#include "quijibo/iou.h"
#include "quijibo/json_reader.h"
#include "quijibo/mask.h"
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
  if (std::string why = modulus_iteration.validate(); !why.empty()) return why;
  return quijibo_iteration.validate();
}

CompareResult Compare(const CompareOptions& o) {
  if (std::string why = o.Validate(); !why.empty()) throw Error("compare: " + why);
  Outputs outs;
  const RationalMap rmap = ReadMap(o.map);
  mesh::CheckSameFrame(rmap.frame, o.map, o.target);
  const auto grid = std::make_shared<ScalarGrid>(ReadGrid(o.target));
  // QUIJIBO fit time.
  json qj_fit = nullptr;
  if (o.quijibo_seconds) {
    qj_fit = *o.quijibo_seconds;
  } else {
    const auto summary = std::filesystem::path(o.map).parent_path() / "summary.json";
    if (std::filesystem::exists(summary)) {
      const json sj = ParseJson(ReadFile(summary.string()), summary.string());
      JsonReader sr(sj, summary.string());
      if (sr.has("/seconds")) qj_fit = sr.number("/seconds");
    }
  }
  // Shape modulus "fit": load the target into the unit frame and get a versor.
  double t0 = WallSeconds();
  FractalFrame f;
  if (std::filesystem::exists(mesh::FrameJsonPathFor(o.target)))
    f = mesh::ReadFrameJson(mesh::FrameJsonPathFor(o.target));
  double k = 1;
  ModulusTarget target = ModulusTargetFromGrid(grid, f.fractal_radius, f.padding, &k);
  const Versor v = o.modulus.versor.Make(target);
  ShapeModulusOptions so = o.modulus.shape;
  if (o.modulus.params) mesh::ReadModulusParams(*o.modulus.params, so, o.modulus.sdf_resolution);
  auto sm = std::make_shared<ShapeModulusMap>(target, v, so);
  const double sm_fit = WallSeconds() - t0;
  auto qj = std::make_shared<RationalQuaternionMap>(rmap);
  const IterationOptions sjo = o.modulus_iteration, qjo = o.quijibo_iteration;
  if (auto why = sjo.validate(); !why.empty()) throw Error(why);
  if (auto why = qjo.validate(); !why.empty()) throw Error(why);
  // Fields on the grid (fractal frame): one application (the 2015 energy's L) and n iterates.
  const EnergyGrid eg = MakeEnergyGrid(*grid, ParseWeightField(o.weights));
  const std::int64_t cells = eg.frame.cell_count();
  std::vector<double> qj1(cells), qjn(cells), sm1(cells), smn(cells);
#pragma omp parallel for schedule(dynamic, 1024)
  for (std::int64_t c = 0; c < cells; ++c) {
    const Vec3 w = eg.frame.cell_center(c);
    const Quat qw{w[0], w[1], w[2], eg.slice}, qu{k * w[0], k * w[1], k * w[2], 0.0};
    qj1[c] = qj->LogModulus(qw);
    qjn[c] = IterateField(*qj, qw, qjo);
    sm1[c] = sm->LogModulus(qu);
    smn[c] = IterateField(*sm, qu, sjo);
  }
  auto iou = [&](const std::vector<double>& fld) {
    std::int64_t both = 0, either = 0;
    for (std::int64_t c = 0; c < cells; ++c) {
      const bool a1 = fld[c] < 0, b1 = grid->values[c] < 0;
      both += a1 && b1;
      either += a1 || b1;
    }
    return IntersectionOverUnion(both, either);
  };
  // Meshes over the grid's box, in the fractal frame.
  mesh::MeshingOptions mo;
  mo.min_corner = grid->frame.min_corner;
  for (int ax = 0; ax < 3; ++ax) mo.max_corner[ax] = mo.min_corner[ax] + grid->frame.extent()[ax];
  mo.resolution = o.resolution;
  mesh::BatchField target_field;
  target_field.evaluate = [grid](const Vec3* p, std::size_t n, double* out) {
    for (std::size_t i = 0; i < n; ++i) out[i] = ExtendedSample(*grid, p[i]);
  };
  mesh::MeshingSummary ms_t, ms_q, ms_s;
  const mesh::TriangleMesh target_mesh = mesh::MeshField(target_field, mo, &ms_t);
  double m0 = WallSeconds(), c0 = CpuSeconds();
  const mesh::TriangleMesh qj_mesh = mesh::MeshField(mesh::MakeQuaternionMapField(qj, qjo, 1.0), mo, &ms_q);
  const double qj_mesh_s = WallSeconds() - m0, qj_mesh_cpu = CpuSeconds() - c0;
  m0 = WallSeconds(), c0 = CpuSeconds();
  const mesh::TriangleMesh sm_mesh = mesh::MeshField(mesh::MakeQuaternionMapField(sm, sjo, k), mo, &ms_s);
  const double sm_mesh_s = WallSeconds() - m0, sm_mesh_cpu = CpuSeconds() - c0;
  const auto ts = mesh::SampleSurface(target_mesh, o.samples, 1);
  auto chamfer = [&](const mesh::TriangleMesh& m) -> json {
    const auto ms = mesh::SampleSurface(m, o.samples, 2);
    if (ms.empty()) return {{"to_target", nullptr}, {"from_target", nullptr}, {"chamfer", nullptr}};
    const double to = mesh::Mean(mesh::NearestPointDistances(ms, ts));
    const double from = mesh::Mean(mesh::NearestPointDistances(ts, ms));
    return {{"to_target", to}, {"from_target", from}, {"chamfer", to + from}};
  };
  const json qj_ch = chamfer(qj_mesh), sm_ch = chamfer(sm_mesh);
  const Image qj_img = mesh::InsideSlice(
      [&](const Vec3& p) {
        return IterateField(*qj, {p[0], p[1], p[2], 0}, qjo);
      },
      *grid, o.png_size);
  const Image sm_img = mesh::InsideSlice(
      [&](const Vec3& p) {
        return IterateField(*sm, {k * p[0], k * p[1], k * p[2], 0}, sjo);
      },
      *grid, o.png_size);
  auto method = [&](const std::string& name, json fit, double psi1, double psin, double io, const json& ch,
                    const mesh::TriangleMesh& m, double ms, double mcpu, const std::string& png,
                    const std::string& ply) {
    return json{{"method", name},
                {"fit_seconds", fit},
                {"psi_one_application", psi1},
                {"psi_iterated", psin},
                {"iou", io},
                {"chamfer", ch},
                {"triangles", m.triangles.size()},
                {"mesh_seconds", ms},
                {"mesh_cpu_seconds", mcpu},
                {"picture", png},
                {"mesh", ply}};
  };
  const double diag = std::hypot(grid->frame.extent()[0], grid->frame.extent()[1], grid->frame.extent()[2]);
  json report = {{"target", o.target},
                 {"map", o.map},
                 {"grid", {{"dims", grid->frame.dims}, {"spacing", grid->frame.spacing}, {"box_diagonal", diag}}},
                 {"energy", {{"alpha", o.energy_alpha}, {"weights", o.weights}, {"eta", eg.eta}}},
                 {"mesh_resolution", o.resolution},
                 {"unit_per_fractal", k},
                 {"shape_modulus",
                  {{"alpha", ParameterFieldToJson(so.alpha)},
                   {"beta", ParameterFieldToJson(so.beta)},
                   {"iterations", sjo.iterations},
                   {"escape_radius", sjo.escape_radius},
                   {"versor", v.polynomial.description}}},
                 {"quijibo", {{"iterations", qjo.iterations}, {"escape_radius", qjo.escape_radius}}},
                 {"target_mesh_triangles", target_mesh.triangles.size()},
                 {"methods", json::array({method("QUIJIBO", qj_fit, EnergyOfField(eg, qj1, o.energy_alpha),
                                                 EnergyOfField(eg, qjn, o.energy_alpha), iou(qjn), qj_ch, qj_mesh,
                                                 qj_mesh_s, qj_mesh_cpu, "quijibo.png", "quijibo.ply"),
                                          method("shape modulus", sm_fit, EnergyOfField(eg, sm1, o.energy_alpha),
                                                 EnergyOfField(eg, smn, o.energy_alpha), iou(smn), sm_ch, sm_mesh,
                                                 sm_mesh_s, sm_mesh_cpu, "modulus.png", "modulus.ply")})}};
  // Markdown.
  std::ostringstream md;
  auto num = [](const json& j, int prec = 4) {
    if (j.is_null()) return std::string("n/a");
    char b[64];
    std::snprintf(b, sizeof b, "%.*g", prec, j.get<double>());
    return std::string(b);
  };
  md << "# QUIJIBO vs shape modulus on " << o.target << "\n\n"
     << "Map: `" << o.map << "`. Grid " << grid->frame.dims[0] << "x" << grid->frame.dims[1] << "x"
     << grid->frame.dims[2] << " (the target SDF's cells). psi: 2015 energy, tanh sharpness " << o.energy_alpha << ", "
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
  std::filesystem::create_directories(o.out_dir);
  auto path = [&](const std::string& n) { return (std::filesystem::path(o.out_dir) / n).string(); };
  WritePng(path("quijibo.png"), qj_img), outs.Add(path("quijibo.png"));
  WritePng(path("modulus.png"), sm_img), outs.Add(path("modulus.png"));
  mesh::WritePly(path("quijibo.ply"), qj_mesh), outs.Add(path("quijibo.ply"));
  mesh::TriangleMesh sm_fractal = sm_mesh;  // already in the fractal frame (points scaled by k inside the field)
  mesh::WritePly(path("modulus.ply"), sm_fractal), outs.Add(path("modulus.ply"));
  WriteFileAtomically(path("compare.json"), report.dump(1) + "\n"), outs.Add(path("compare.json"));
  WriteFileAtomically(path("compare.md"), md.str()), outs.Add(path("compare.md"));
  outs.Commit();
  return {report, md.str()};
}

}  // namespace quijibo::pipeline
