#include "experiments/pipeline/target.h"

#include <algorithm>
#include <cctype>
#include <chrono>

#include "mesh/frame_file.h"
#include "mesh/mesh_target.h"
#include "util/error.h"
#include "quijibo/target.h"

namespace quijibo::pipeline {

using nlohmann::json;
namespace fs = std::filesystem;

namespace {

bool IsMeshPath(const std::string& s) {
  std::string e = fs::path(s).extension().string();
  for (char& c : e) c = char(std::tolower(static_cast<unsigned char>(c)));
  return e == ".obj" || e == ".ply" || e == ".stl" || e == ".off";
}

}  // namespace

std::string TargetOptions::kind() const {
  if (!mesh.empty()) return "mesh";
  if (!qgrid.empty()) return "qgrid";
  if (!analytic.empty()) return "analytic";
  return "";
}

const Schema<TargetOptions>& TargetOptions::Settings() {
  static const Schema<TargetOptions> s =
      Schema<TargetOptions>()
          .Path("mesh", "", "A mesh (.obj, .ply, .stl, .off)", [](auto& o) -> std::string& { return o.mesh; })
          .Doc("`.obj`, `.ply`, `.stl` or `.off`; normalized into the fractal frame (`mesh/normalize.h`), its SDF "
               "computed (`quijibo sdf`)")
          .When([](const TargetOptions& o) { return !o.mesh.empty(); })
          .Path("qgrid", "", "A signed distance grid from `quijibo sdf` (fractal frame)",
                [](auto& o) -> std::string& { return o.qgrid; })
          .Doc("a signed distance grid from `quijibo sdf`/`monopoles` (fractal frame); its `.frame.json` is used "
               "when present")
          .When([](const TargetOptions& o) { return !o.qgrid.empty(); })
          .String("analytic", "", "An analytic shape: sphere[:radius=R], torus[:major=R,minor=r]",
                  [](auto& o) -> std::string& { return o.analytic; })
          .Doc("`sphere[:radius=R]`, `torus[:major=R,minor=r]` (QUIJIBO); for `modulus` also `disc`, `hexagram`")
          .When([](const TargetOptions& o) { return !o.analytic.empty(); })
          .Integer(
              "resolution", "-r,--resolution", "Target grid cells per axis",
              [](auto& o) -> int& { return o.resolution; }, kTargetResolutionRange)
          .Doc("cells per axis of the target grid (mesh and analytic targets; the paper: 97; every command's "
               "target grid takes this default and range)")
          .Number(
              "padding", "--padding", "Normalization padding: the mesh's longest side spans 1 - 2 padding",
              [](auto& o) -> double& { return o.padding; }, 0.0, 0.4999)
          .Doc("normalization padding: the mesh's longest side spans 1 − 2·padding of the unit cube (mesh targets)")
          .Number(
              "fractal_radius", "--fractal-radius", "Fractal frame scale: w = fractal_radius (p - origin)",
              [](auto& o) -> double& { return o.fractal_radius; }, 0.0, FractalFrame::kMaxFractalRadius, true)
          .Doc("the fractal frame's scale, w = fractal_radius · (p − origin) (mesh targets); with `frame_scale` "
               "`\"trap\"` the target stage chooses it instead")
          .Enum(
              "box", "--target-box",
              "unit: the whole unit cube, a margin of `padding` around the shape; reference: the reference code's "
              "box, the shape plus one cell (quijibo/frame.h)",
              {"unit", "reference"}, [](const TargetOptions& o) { return TargetBoxName(o.box); },
              [](TargetOptions& o, const std::string& v) { o.box = ParseTargetBox(v); })
          .When([](const TargetOptions& o) { return !o.mesh.empty(); })
          .Doc("mesh targets: the target grid covers the whole normalized unit cube (a margin of `padding` around "
               "the shape, the box `mesh` and the pictures use), or the reference code's box (the shape plus one "
               "cell), where the set can grow unseen beside the shape ([fidelity.md](fidelity.md))")
          .Enum(
              "origin", "--origin",
              "inside: the fractal origin at the point deepest inside the shape, where iterating the map traps "
              "orbits; center: at the bounding box's centre, as the reference code (mesh/normalize.h)",
              {"inside", "center"},
              [](const TargetOptions& o) {
                return mesh::OriginPlacementName(o.origin.value_or(mesh::OriginPlacement::kCenter));
              },
              [](TargetOptions& o, const std::string& v) { o.origin = mesh::ParseOriginPlacement(v); })
          .When([](const TargetOptions& o) { return !o.mesh.empty() && o.origin.has_value(); })
          .Doc("QUIJIBO mesh targets: the fractal origin at the point deepest inside the shape (orbits are trapped "
               "at the origin, so it must be inside for the n-step set to exist), or at the bounding box's centre "
               "(reference)")
          .Enum(
              "frame_scale", "--frame-scale",
              "trap: fractal_radius chosen so that the unit ball about the origin, where the map sends the "
              "one-step set, just fits inside the shape (the n-step set keeps thin parts); fixed: fractal_radius "
              "as given, as the reference code (mesh/normalize.h)",
              {"trap", "fixed"}, [](const TargetOptions& o) { return mesh::FrameScaleName(o.frame_scale); },
              [](TargetOptions& o, const std::string& v) { o.frame_scale = mesh::ParseFrameScale(v); })
          .When([](const TargetOptions& o) { return !o.mesh.empty() && o.origin == mesh::OriginPlacement::kInside; })
          .Doc("QUIJIBO mesh targets with `origin` `\"inside\"`: `fractal_radius` chosen so that the unit ball "
               "about the origin, into which the map sends every point of the one-step set, just fits inside the "
               "shape (the distance from the origin to the surface becomes 1; written to the map's frame), so the "
               "n-step set keeps thin parts; or `fractal_radius` as given (reference). The one-step set does not "
               "depend on it ([fidelity.md](fidelity.md) §3)");
  return s;
}

std::string TargetOptions::Validate() const {
  const int kinds = !mesh.empty() + !qgrid.empty() + !analytic.empty();
  if (kinds != 1) return "expected exactly one of \"mesh\", \"qgrid\" or \"analytic\"";
  if (!mesh.empty() && !IsMeshPath(mesh)) return "mesh: expected a .obj, .ply, .stl or .off file, found " + mesh;
  return Settings().Check(*this);
}

TargetOptions TargetOptions::FromJson(const JsonReader& r, const std::string& p, const fs::path& base,
                                      const TargetOptions& start) {
  TargetOptions o = start;
  o.mesh.clear(), o.qgrid.clear(), o.analytic.clear();
  if (!r.has(p)) r.fail(p, "missing: an object with \"mesh\", \"qgrid\" or \"analytic\"");
  if (!r.at(p).is_object()) r.fail(p, "expected an object, found " + JsonReader::describe(r.at(p)));
  int kinds = 0;
  for (const char* k : {"mesh", "qgrid", "analytic"}) kinds += r.has(p + "/" + k);
  if (kinds != 1) r.fail(p, "expected exactly one of \"mesh\", \"qgrid\" or \"analytic\"");
  // The kind first: the other settings depend on it.
  if (r.has(p + "/mesh")) o.mesh = "?";
  if (r.has(p + "/qgrid")) o.qgrid = "?";
  if (r.has(p + "/analytic")) o.analytic = "?";
  const std::string kind = o.kind();
  if (r.has(p + "/kind") && r.string(p + "/kind") != kind)
    r.fail(p + "/kind", "expected \"" + kind + "\" (the target's key), found \"" + r.string(p + "/kind") + "\"");
  if (kind != "mesh" && r.has(p + "/box"))
    r.fail(p + "/box", "only mesh targets choose their box (analytic targets use the reference box)");
  if ((kind != "mesh" || !o.origin) && r.has(p + "/origin"))
    r.fail(p + "/origin", "only QUIJIBO mesh targets place the fractal origin");
  if (r.has(p + "/frame_scale")) {
    const bool inside = r.has(p + "/origin") ? r.at(p + "/origin") == "inside"
                                             : o.origin == mesh::OriginPlacement::kInside;
    if (kind != "mesh" || !o.origin || !inside)
      r.fail(p + "/frame_scale", "applies only to QUIJIBO mesh targets with \"origin\": \"inside\" (the trap is "
                                 "the ball about an origin inside the shape)");
  }
  Settings().Read(r, p, base, o, {"kind"});
  if (kind == "mesh" && !IsMeshPath(o.mesh))
    r.fail(p + "/mesh", "expected a .obj, .ply, .stl or .off file, found " + o.mesh);
  if (kind == "analytic" && o.analytic.empty())
    r.fail(p + "/analytic", "expected a shape such as \"sphere\" or \"torus:major=1,minor=0.3\"");
  return o;
}

json TargetOptions::ToJson() const {
  json j = {{"kind", kind()}};
  Settings().Write(*this, j);
  return j;
}

TargetResult Target(const TargetOptions& o) {
  if (const std::string why = o.Validate(); !why.empty()) throw Error("target: " + why);
  TargetResult t;
  if (!o.mesh.empty()) {
    const mesh::TriangleMesh user = mesh::ReadMesh(o.mesh, &t.read_report);
    mesh::MeshTargetOptions mo;
    mo.resolution = o.resolution, mo.padding = o.padding, mo.fractal_radius = o.fractal_radius, mo.box = o.box;
    // Methods without a fractal origin (the shape modulus, portals) keep the unit frame's centre.
    mo.origin = o.origin.value_or(mesh::OriginPlacement::kCenter);
    mo.frame_scale = o.frame_scale;
    const auto t0 = std::chrono::steady_clock::now();
    mesh::MeshTargetResult made = mesh::MeshTarget(user, o.mesh, mo);
    t.sdf_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    t.frame = made.frame;
    t.mesh = std::move(made.mesh);
    t.grid = std::move(made.grid);
    t.source = o.mesh;
  } else if (!o.qgrid.empty()) {
    t.grid = ReadGrid(o.qgrid);
    const std::string fp = mesh::FrameJsonPathFor(o.qgrid);
    if (fs::exists(fp)) t.frame = mesh::ReadFrameJson(fp);
    t.source = o.qgrid;
  } else {
    // Analytic shapes live in the default frame, on the reference box.
    t.grid = AnalyticTarget(o.analytic, TargetGridFrame(o.resolution, t.frame));
    t.source = "analytic:" + o.analytic;
  }
  return t;
}

void WriteTarget(const TargetResult& t, const TargetOptions& o, const std::string& dir) {
  const std::string grid = dir + "/target.qgrid";
  WriteGrid(grid, t.grid);
  mesh::WriteFrameJson(mesh::FrameJsonPathFor(grid), t.frame, t.source,
                       o.mesh.empty() ? t.grid.frame.dims[0] : o.resolution);
}

}  // namespace quijibo::pipeline
