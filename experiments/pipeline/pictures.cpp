#include "experiments/pipeline/pictures.h"

#include <algorithm>
#include <cmath>

#include "experiments/pipeline/mesh.h"
#include "mesh/julia_field.h"
#include "mesh/frame_file.h"
#include "mesh/triangle_mesh.h"
#include "util/error.h"
#include "util/io.h"

namespace quijibo::pipeline {

using nlohmann::json;
namespace fs = std::filesystem;

const Schema<PicturesOptions>& PicturesOptions::Settings() {
  using O = PicturesOptions;
  static const Schema<O> s =
      Schema<O>()
          .Boolean("enabled", "", "Draw the pictures", [](auto& o) -> bool& { return o.enabled; })
          .Integer(
              "slice_iterations", "-n,--iterations", "Map applications n of the set against the target",
              [](auto& o) -> int& { return o.slice_iterations; }, 1, 1000)
          .Doc("n of the slices against the target")
          .Integer(
              "slice_size", "--size", "Pixels along the longer side of the slice",
              [](auto& o) -> int& { return o.slice.size; }, 16, 8192)
          .Integer(
              "render_size", "--size", "Pixels per view of the render", [](auto& o) -> int& { return o.render.size; },
              16, 8192)
          .Integer(
              "render_views", "--views", "Views of the render: front, side, top, three-quarter",
              [](auto& o) -> int& { return o.render.views; }, 1, 4)
          .Doc("views of `render.png`: front, side, top, three-quarter")
          .Choice(
              "render_shading", "--shading",
              "Shading of the renders: depth (ray-traced ambient occlusion, soft shadows, ground) or flat (Lambert)",
              [](auto& o) -> std::string& { return o.render.shading; }, {"depth", "flat"})
          .Integer(
              "render_samples", "--samples", "Camera rays per pixel of the renders (depth shading)",
              [](auto& o) -> int& { return o.render.samples; }, 1, 256)
          .Integer(
              "render_ao_rays", "--ao-rays", "Ambient-occlusion rays per camera ray of the renders (depth shading)",
              [](auto& o) -> int& { return o.render.ao_rays; }, 0, 256)
          .Boolean("triptych", "", "The triptych: target, Julia set and intricate surface rendered alike",
                   [](auto& o) -> bool& { return o.triptych; })
          .Doc("the 2015 paper's Fig. 1 for the run's mesh, `triptych/`: the target, the Julia set and the intricate "
               "surface (`intricate`) rendered alike; report.md opens with it")
          .Integer(
              "triptych_size", "", "Pixels per panel of the triptych", [](auto& o) -> int& { return o.triptych_size; },
              64, 4096);
  return s;
}

std::string PicturesOptions::Validate() const { return Settings().Check(*this); }

PicturesOptions PicturesOptions::FromJson(const JsonReader& r, const std::string& p, const fs::path& base,
                                          const PicturesOptions& start) {
  return Settings().FromJson(r, p, base, start);
}

json PicturesOptions::ToJson() const { return Settings().ToJson(*this); }

SlicePicture SliceAgainstTargetPicture(const RationalMap& map, const ScalarGrid& target, const std::string& target_path,
                                       const mesh::SliceView& view, const JuliaOptions& julia, double iso,
                                       Precision precision) {
  if (target.coordinates != "fractal")
    throw Error(target_path + ": expected a grid in fractal coordinates, found \"" + target.coordinates + "\"");
  mesh::CheckSameFrame(map.frame, "the map", target_path);
  if (auto why = view.Validate(); !why.empty()) throw Error("picture: " + why);
  if (auto why = julia.Validate(); !why.empty()) throw Error(why);
  const mesh::BatchField field = mesh::MakeJuliaField(map, julia, iso, precision);
  SlicePicture p;
  p.image = mesh::SliceAgainstTarget(field, target, view, &p.agreement);
  return p;
}

json SliceReport(const SlicePicture& p, const std::string& out, const JuliaOptions& julia, double iso,
                 Precision precision) {
  const mesh::SliceAgreement& a = p.agreement;
  return {{"out", out},
          {"agreement", a.agreement()},
          {"both_inside", a.both_inside},
          {"both_outside", a.both_outside},
          {"julia_only", a.julia_only},
          {"target_only", a.target_only},
          {"julia", JuliaJson(julia, iso, precision)}};
}

mesh::SliceView TargetSliceView(const ScalarGrid& target, const PicturesOptions& o) {
  mesh::SliceView v = o.slice;
  const Vec3 lo = target.frame.min_corner, ext = target.frame.extent();
  v.min_corner = lo;
  v.max_corner = {lo[0] + ext[0], lo[1] + ext[1], lo[2] + ext[2]};
  return v;
}

void Pictures(const PicturesOptions& o, const RationalMap& initial, const RationalMap& optimized,
              const std::string& target_path, const std::string& mesh_path, const std::string& dir) {
  if (auto why = o.Validate(); !why.empty()) throw Error("pictures: " + why);
  const ScalarGrid target = ReadGrid(target_path);
  const mesh::SliceView view = TargetSliceView(target, o);
  JuliaOptions julia;
  julia.iterations = o.slice_iterations;
  const std::string n = std::to_string(o.slice_iterations);
  for (const auto& [map, name] :
       {std::pair{&optimized, std::string("slice")}, std::pair{&initial, std::string("initial-slice")}}) {
    const std::string png = dir + "/" + name + "-n" + n + ".png";
    const SlicePicture p = SliceAgainstTargetPicture(*map, target, target_path, view, julia, 0.0, Precision::kDouble);
    WritePng(png, p.image);
    WriteFileAtomically(dir + "/" + name + ".out", SliceReport(p, png, julia, 0.0, Precision::kDouble).dump(2) + "\n");
  }
  if (!mesh_path.empty()) WritePng(dir + "/render.png", mesh::RenderMesh(mesh::ReadMesh(mesh_path), o.render));
}

}  // namespace quijibo::pipeline
