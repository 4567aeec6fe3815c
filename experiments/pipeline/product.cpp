#include "experiments/pipeline/product.h"

#include <sys/resource.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>

#include "experiments/pipeline/mesh.h"
#include "mesh/julia_field.h"
#include "util/error.h"
#include "util/io.h"

namespace quijibo::pipeline {

using nlohmann::json;
namespace fs = std::filesystem;

double Since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

double WallSeconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

double CpuSeconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return double(u.ru_utime.tv_sec) + 1e-6 * u.ru_utime.tv_usec + double(u.ru_stime.tv_sec) + 1e-6 * u.ru_stime.tv_usec;
}

void Outputs::Rollback() {
  for (const auto& p : written_) {
    std::error_code ec;
    fs::remove(p, ec);
  }
  written_.clear();
}

const Schema<ProductOutputOptions>& ProductOutputOptions::Settings() {
  using O = ProductOutputOptions;
  static const Schema<O> s =
      Schema<O>()
          .Choice("format", "", "ply: a 3D mesh; png: the complex plane",
                  [](auto& o) -> std::string& { return o.format; }, {"ply", "png"})
          .Integer(
              "resolution", "-r,--resolution", "3D: marching cubes cells along the box's longest side",
              [](auto& o) -> int& { return o.meshing.resolution; }, 4, 8192)
          .Integer(
              "png_size", "--png-size", "2D: pixels per side", [](auto& o) -> int& { return o.view.width; }, 8, 32768)
          .Integer(
              "iterations", "--iterations", "Map applications (unset: the map kind's or the spec's; the shape modulus: 3)",
              [](auto& o) -> std::optional<int>& { return o.iterations; }, 1, 100000)
          .Fallback([](const O&) { return IterationOptions{}.iterations; })
          .Number(
              "escape", "--escape", "Escape radius (unset: the map kind's or the spec's; the shape modulus: 20)",
              [](auto& o) -> std::optional<double>& { return o.escape; }, 0.0, 1e300, true)
          .Fallback([](const O&) { return IterationOptions{}.escape_radius; })
          .Numbers(
              "box", "--box", "Region: x0 y0 x1 y1 (2D) or x0 y0 z0 x1 y1 z1 (3D), unit frame",
              [](auto& o) -> std::optional<std::vector<double>>& { return o.box; }, {4, 6}, -1e6, 1e6);
  return s;
}

std::string ProductOutputOptions::Validate() const { return Settings().Check(*this); }

ProductOutputOptions ProductOutputOptions::FromJson(const JsonReader& r, const std::string& p, const fs::path& base,
                                                    const ProductOutputOptions& start) {
  return Settings().FromJson(r, p, base, start);
}

json ProductOutputOptions::ToJson() const { return Settings().ToJson(*this); }

Product Produce(std::shared_ptr<const QuaternionMap> map, const ProductOutputOptions& o, const IterationOptions& jo,
                const ModulusTarget& target, bool two_d) {
  if (auto why = jo.Validate(); !why.empty()) throw Error(why);
  if (auto why = o.Validate(); !why.empty()) throw Error("output: " + why);
  const std::vector<double> box = o.box ? *o.box : ModulusRegion(target, two_d);
  Product p;
  const double t0 = WallSeconds(), c0 = CpuSeconds();
  if (two_d) {
    View2D v = o.view;
    if (box.size() != 4) throw Error("--box needs 4 numbers in 2D (x0 y0 x1 y1)");
    v.x_min = box[0], v.y_min = box[1], v.x_max = box[2], v.y_max = box[3];
    v.height = v.width;
    if (auto why = v.Validate(); !why.empty()) throw Error(why);
    const std::vector<double> field = SampleField2D(*map, jo, v);
    std::int64_t inside = 0;
    for (double f : field) inside += f < 0;
    p.kind = "png";
    p.image = FieldImage(field, v, std::log(jo.escape_radius));
    p.report = {{"pixels", field.size()}, {"inside_pixels", inside}, {"view", {v.x_min, v.y_min, v.x_max, v.y_max}}};
  } else {
    mesh::MeshingOptions mo = o.meshing;
    if (box.size() != 6) throw Error("--box needs 6 numbers in 3D (x0 y0 z0 x1 y1 z1)");
    mo.min_corner = {box[0], box[1], box[2]};
    mo.max_corner = {box[3], box[4], box[5]};
    if (auto why = mo.Validate(); !why.empty()) throw Error("meshing: " + why);
    mesh::MeshingSummary ms;
    p.mesh = mesh::MeshField(mesh::MakeQuaternionMapField(map, jo, 1.0), mo, &ms);
    p.kind = "ply";
    p.report = MesherSummaryJson(ms, mo);
    p.report["box"] = {mo.min_corner[0], mo.min_corner[1], mo.min_corner[2],
                       mo.max_corner[0], mo.max_corner[1], mo.max_corner[2]};
    p.report["resolution"] = mo.resolution;
    p.report["nodes_evaluated"] = ms.nodes_evaluated;
    p.report["bisection_evaluations"] = ms.bisection_evaluations;
    p.report["non_finite_values"] = ms.non_finite_values;
  }
  p.report["seconds"] = WallSeconds() - t0;
  p.report["cpu_seconds"] = CpuSeconds() - c0;
  p.report["iterations"] = jo.iterations;
  p.report["escape_radius"] = jo.escape_radius;
  return p;
}

void WriteProduct(const Product& p, const std::string& path) {
  if (p.kind == "png") {
    if (!HasExtension(path, ".png")) throw Error("2D output must be a .png, found \"" + path + "\"");
    WritePng(path, p.image);
  } else {
    if (!HasExtension(path, ".ply")) throw Error("3D output must be a .ply, found \"" + path + "\"");
    mesh::WritePly(path, p.mesh);
  }
}

}  // namespace quijibo::pipeline
