#include "experiments/pipeline/triptych.h"

#include <chrono>
#include <cmath>
#include <filesystem>
#include <sstream>

#include "experiments/pipeline/quality.h"
#include "experiments/pipeline/stage_cache.h"
#include "mesh/fidelity.h"
#include "quijibo/julia_setup.h"
#include "util/error.h"

namespace quijibo::pipeline {

using nlohmann::json;
namespace fs = std::filesystem;

MeshStageOptions IntricateDefaults(const MeshStageOptions& mesh) {
  MeshStageOptions o = mesh;
  o.meshing.resolution = 128;
  o.detail = 4.0;
  o.translate_potential = -2.0;
  o.translate = std::vector<double>{0.0, 0.0, 1.0};
  o.iteration_frame = IterationFrame::kMap;
  o.box.clear();
  o.rotation.clear();
  o.vdb = true;
  o.obj = false;
  o.stream = false;
  return o;
}

json SetFidelity(const RationalMap& map, const JuliaSetup& setup, const ScalarGrid& target, const MeshStageOptions& o,
                 int lattice) {
  // The set as the mesh shows it, without its placement (it moves the set off the target).
  mesh::FidelityOptions f;
  f.lattice = lattice;
  f.julia.iterations = o.julia.iterations;
  f.julia.escape_radius = o.julia.escape_radius;
  f.julia.capture_radius = o.julia.capture_radius;
  f.julia.slice = o.julia.slice;
  f.julia.root_translation = setup.julia.root_translation;
  f.iso = o.iso;
  f.iterated = std::make_shared<const RationalMap>(setup.map);
  json fid = mesh::MeasureSets(map, target, f).ToJson();
  fid["lattice"] = lattice;
  fid["closing"] = f.closing;
  return fid;
}

json RenderTriptych(const std::string& target_mesh, const std::string& set_mesh, const std::string& intricate_mesh,
                    const mesh::RenderOptions& render, int size, const std::string& dir) {
  const auto t0 = std::chrono::steady_clock::now();
  struct Panel {
    std::string name, path;
    mesh::TriangleMesh mesh;
  };
  std::vector<Panel> panels;
  for (const auto& [name, path] : {std::pair<std::string, std::string>{"target", target_mesh},
                                   {"set", set_mesh},
                                   {"intricate", intricate_mesh}})
    if (!path.empty() && fs::exists(path)) panels.push_back({name, path, mesh::ReadMesh(path)});
  if (panels.empty()) throw Error("triptych: no mesh to render");
  // Framed alike, on the target (the first panel): the three are in its frame.
  std::array<double, 4> framing = mesh::Framing(panels.front().mesh);
  framing[3] *= 1.04;
  mesh::RenderOptions o = render;
  o.size = size;
  o.views = 1;
  o.framing = framing;
  std::vector<Image> images;
  json out = {{"panels", json::array()}, {"triangles", json::array()}, {"render_seconds", json::array()}};
  for (const Panel& p : panels) {
    mesh::RenderSummary s;
    images.push_back(mesh::RenderView(p.mesh, mesh::kViewAngles[3][0], mesh::kViewAngles[3][1], o, &s));
    WritePng(dir + "/" + p.name + ".png", images.back());
    out["panels"].push_back(p.name);
    out["triangles"].push_back(p.mesh.triangles.size());
    out["render_seconds"].push_back(s.seconds);
  }
  WritePng(dir + "/triptych.png", mesh::SideBySide(images, 8));
  out["size"] = size;
  out["view"] = {mesh::kViewAngles[3][0], mesh::kViewAngles[3][1]};
  out["seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

namespace {

std::string Thousands(long long n) {
  std::string s = std::to_string(n < 0 ? -n : n);
  for (int i = int(s.size()) - 3; i > 0; i -= 3) s.insert(std::size_t(i), ",");
  return (n < 0 ? "-" : "") + s;
}

// One line of figures under a panel.
std::string FiguresLine(const json& f, bool is_target) {
  std::ostringstream s;
  if (!f.is_object()) return "–";
  const json d = f.value("detail", json());
  if (is_target) {
    s << Thousands(f.value("triangles", 0LL)) << " triangles";
    if (d.is_object())
      s << ", box dimension " << Fixed(d.value("box_dimension", 0.0), 3) << ", " << d.value("components", 0LL)
        << (d.value("components", 0LL) == 1 ? " component" : " components");
    return s.str();
  }
  if (f.value("triangles", 0LL) == 0) return "no surface in the box";
  if (d.is_object())
    s << "area " << Fixed(d.value("area_ratio", 0.0), 2) << "× the target's, box dimension "
      << Fixed(d.value("box_dimension", 0.0), 3) << ", ";
  const json fid = f.value("fidelity", json());
  if (fid.is_object() && fid.contains("n_step"))
    s << "closed IoU " << Fixed(fid["n_step"].value("closed_iou", 0.0), 3) << " (n-step IoU "
      << Fixed(fid["n_step"].value("iou", 0.0), 3) << "), ";
  if (d.is_object())
    s << d.value("components", 0LL) << (d.value("components", 0LL) == 1 ? " component" : " components");
  return s.str();
}

}  // namespace

std::string TriptychSection(const std::string& results) {
  const json t = ReadStageFile(results + "/triptych/triptych.json");
  if (!t.is_object() || !t.contains("panels")) return "";
  const json ms = ReadStageFile(results + "/mesh/summary.json"), is = ReadStageFile(results + "/intricate/summary.json");
  json figures = t.value("figures", json::object());
  // The set's figures: its detail from the mesh stage, its fidelity from the fidelity stage.
  const json fid = ReadStageFile(results + "/fidelity/fidelity.json");
  if (ms.is_object() && ms.value("triangles", 0LL) > 0) {
    figures["set"]["triangles"] = ms.value("triangles", 0LL);
    if (ms.contains("detail")) figures["set"]["detail"] = ms["detail"];
    if (fid.is_object() && fid.contains("n_step")) figures["set"]["fidelity"] = fid;
  }
  if (is.is_object() && is.value("triangles", 0LL) > 0) {
    figures["intricate"]["triangles"] = is.value("triangles", 0LL);
    if (is.contains("detail")) figures["intricate"]["detail"] = is["detail"];
  }
  auto title = [&](const std::string& panel) -> std::string {
    if (panel == "target") return "(a) the target";
    if (panel == "set")
      return "(b) the Julia set, n = " + std::to_string(ms.is_object() ? ms["julia"].value("iterations", 0) : 0);
    std::string s = "(c) intricate";
    if (is.is_object()) {
      const json& f = is["iteration_frame"];
      s += ", detail " + Fixed(f.value("detail", 0.0), 2);
      if (f.value("translate_potential", json()).is_number())
        s += ", L = " + Fixed(f["translate_potential"].get<double>(), 2) + " at −t";
    }
    return s;
  };
  std::ostringstream md, head, rule, pics, line;
  for (const json& p : t["panels"]) {
    const std::string name = p.get<std::string>();
    head << "| " << title(name) << " ";
    rule << "|:-:";
    pics << "| ![" << title(name) << "](triptych/" << name << ".png) ";
    line << "| " << FiguresLine(figures.value(name, json()), name == "target") << " ";
  }
  md << head.str() << "|\n" << rule.str() << "|\n" << pics.str() << "|\n" << line.str() << "|\n\n";
  md << "*The 2015 paper's Fig. 1 for this mesh: the same three-quarter view of each, ray-traced with ambient "
        "occlusion and soft shadows (`triptych/triptych.png`). Closed IoU: the n-step set after a closing of "
     << figures.value("closing", 2) << " lattice cells on the Quality section's " << figures.value("lattice", 32)
     << "³ lattice, its silhouette against the target; meshes `mesh/julia.ply` and `intricate/julia.ply`.*\n\n";
  return md.str();
}

}  // namespace quijibo::pipeline
