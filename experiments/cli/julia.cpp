// `quijibo mesh`, `quijibo picture` and `quijibo bench mesh`: meshing and viewing the Julia set of a
// map (docs/meshing.md), bound to the mesh and pictures stages' Options (experiments/pipeline/).
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <map>
#include <random>
#include <sstream>

#include "experiments/cli/bind.h"
#include "experiments/cli/cli.h"
#include "experiments/pipeline/mesh.h"
#include "experiments/pipeline/pictures.h"
#include "mesh/julia_field.h"
#include "mesh/frame_file.h"
#include "util/child_process.h"
#include "util/error.h"
#include "util/io.h"
#include "quijibo/julia_batch.h"

namespace quijibo::cli {

using nlohmann::json;

namespace {

std::vector<double> ParseNumbers(const std::string& text, const std::string& what) {
  std::vector<double> v;
  std::stringstream s(text);
  std::string item;
  while (std::getline(s, item, ',')) {
    char* end = nullptr;
    const double x = std::strtod(item.c_str(), &end);
    if (item.empty() || end == item.c_str() || *end != '\0' || !std::isfinite(x))
      throw Error(what + ": expected comma-separated numbers, found \"" + text + "\"");
    v.push_back(x);
  }
  return v;
}

// --box x0,y0,z0,x1,y1,z1
std::vector<double> ParseBox(const std::string& text) {
  const auto b = ParseNumbers(text, "--box");
  if (b.size() != 6) throw Error("--box: expected xmin,ymin,zmin,xmax,ymax,zmax");
  for (int a = 0; a < 3; ++a)
    if (!(b[3 + a] > b[a])) throw Error("--box: max must exceed min on every axis");
  return b;
}

// Fails early (before any long computation) when the picture's name is wrong; its folder is created
// when it is written.
void CheckPng(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& ch : ext) ch = char(std::tolower(static_cast<unsigned char>(ch)));
  if (ext != ".png") throw Error(path + ": the picture must end in .png");
}

// Fails early when the folder of an output file cannot be made (a file where a folder should be),
// without making it: a long meshing should not end in that error, nor a failed one leave folders.
void CheckFolderCanBeMade(const std::string& path) {
  const std::filesystem::path dir = std::filesystem::path(path).parent_path();
  std::filesystem::path existing = dir;
  while (!existing.empty() && !std::filesystem::exists(existing)) existing = existing.parent_path();
  if (!existing.empty() && !std::filesystem::is_directory(existing))
    throw Error(path + ": cannot create folder " + dir.string() + ": " + existing.string() + " is not a folder");
}

// The Julia-set options of the mesh and picture commands: the mesh stage's settings (`keys`) and
// the transforms only the command line offers.
struct JuliaArgs {
  pipeline::MeshStageOptions o;
  std::string rotate;
  void add(CLI::App* c, std::vector<std::string> keys) {
    keys.push_back("translate");
    BindSettings(c, o, keys);
    c->add_option("--slice", o.julia.slice, "k component S of the starting quaternion")->capture_default_str();
    c->add_option("--root-scale", o.julia.root_scale, "Roots scaled about the origin by this")->capture_default_str();
    c->add_option("--rotate", rotate, "Rotate the sampling box about its centre: ax,ay,az,degrees");
  }
  // Translation and rotation into the options; the rotation's centre is the box's.
  void finish(const RationalMap& map, const Vec3& box_center) {
    o.julia = o.TranslatedJuliaOfIterated(map);  // no frame or detail keys: the map is iterated as given
    if (!rotate.empty()) {
      o.rotation = ParseNumbers(rotate, "--rotate");
      if (o.rotation.size() != 4) throw Error("--rotate: expected ax,ay,az,degrees");
      o.julia.placement = SampleTransform::AxisAngle({o.rotation[0], o.rotation[1], o.rotation[2]}, o.rotation[3],
                                                     box_center);
    }
    if (auto why = o.julia.Validate(); !why.empty()) throw Error(why);
  }
};

void AddMesh(CLI::App& app, const pipeline::Mesher& mesher, const pipeline::StreamMesher& stream_mesher) {
  struct Args {
    std::string map, box, summary;
    pipeline::MeshFiles files;
    JuliaArgs j;
    bool allow_empty = false;
  };
  auto a = std::make_shared<Args>();
  pipeline::MeshStageOptions& o = a->j.o;
  CLI::App* c = app.add_subcommand(
      "mesh", "Mesh the Julia set {log|q_n| < iso} of a map by marching cubes with bisection (PLY/OBJ, .vdb)");
  c->add_option("map", a->map, "map.json")->required();
  c->add_option("-o,--out", a->files.out, "Output mesh (.ply binary, or .obj)")->required();
  c->add_option("--obj", a->files.obj, "Also write the mesh as OBJ here");
  c->add_option("--vdb", a->files.vdb, "Also write volumes as OpenVDB (--vdb-grids)");
  c->add_option("--vdb-grids", o.vdb_grids,
                "Grids of the .vdb: surface (narrow-band level set), density (fog volume), field (raw log|q_n| on "
                "the surface's cells)")
      ->delimiter(',')
      ->check(CLI::IsMember({"surface", "density", "field"}))
      ->capture_default_str();
  c->add_option("--vdb-band", o.vdb_band, "Half-width of the level set's narrow band, voxels")
      ->capture_default_str()
      ->check(CLI::Range(1.0, 1000.0));
  c->add_option("--box", a->box, "Zoom box in the fractal frame: xmin,ymin,zmin,xmax,ymax,zmax (default: the whole "
                                 "normalized cube, its centre +-fractal_radius/2)");
  AddMesherOptions(c, o.meshing);
  c->add_flag("--ply-double", o.ply_double, "PLY coordinates as double (default float)");
  c->add_flag("--allow-empty", a->allow_empty,
              "A surface that does not cross the box is a result, not an error: write the summary (0 "
              "triangles) and no mesh files");
  c->add_option("--summary", a->summary, "Write the run summary (JSON) here instead of stdout");
  a->j.add(c, {"resolution", "iterations", "escape", "capture", "iso", "iteration_frame", "detail", "translate_potential",
               "frame", "precision", "kernel", "stream"});
  c->callback([a, mesher, stream_mesher] {
    pipeline::MeshStageOptions& o = a->j.o;
    // The output names first; their folders are created when the mesh is ready to be written.
    pipeline::MeshFiles names = a->files;
    for (std::string* p : {&names.out, &names.obj, &names.vdb}) *p = std::filesystem::path(*p).filename().string();
    pipeline::CheckMeshFiles(names);
    for (const std::string& p : {a->files.out, a->files.obj, a->files.vdb}) CheckFolderCanBeMade(p);
    const RationalMap map = ReadMap(a->map);
    o.meshing.show_progress = true;
    if (!a->box.empty()) o.box = ParseBox(a->box);
    if (!a->files.vdb.empty() && o.vdb_grids.empty()) throw Error("--vdb-grids: name at least one grid");
    if (!a->j.rotate.empty()) {  // MeshJulia's setup resolves the translation and places the rotation
      o.rotation = ParseNumbers(a->j.rotate, "--rotate");
      if (o.rotation.size() != 4) throw Error("--rotate: expected ax,ay,az,degrees");
    }
    if (o.stream)  // the scratch files are made beside the outputs while meshing
      for (const std::string& p : {a->files.out, a->files.vdb})
        if (!p.empty()) CreateParentFolder(p);
    const JuliaSetup setup = o.Iterated(map);
    const pipeline::MeshStageResult r = o.stream ? pipeline::MeshJuliaStreamed(setup, o, a->files, stream_mesher)
                                                 : pipeline::MeshJulia(setup, o, mesher);
    if (!r.writer) return;
    if (r.empty() && !a->allow_empty)
      throw Error(a->map + ": the surface log|q_n| = " + std::to_string(o.iso) +
                  " does not cross the box (no triangles); nothing written");
    if (r.empty()) std::fprintf(stderr, "quijibo: the surface does not cross the box (no triangles): no mesh written\n");
    for (const std::string& p : {a->files.out, a->files.obj, a->files.vdb})
      if (!p.empty() && !r.empty()) CreateParentFolder(p);
    pipeline::WriteMeshFiles(r, o, a->files);
    WriteOutput(a->summary, pipeline::MeshSummary(r, o, a->map, a->files).dump(2) + "\n");
  });
}

void AddPicture(CLI::App& app) {
  CLI::App* p = app.add_subcommand("picture", "PNG pictures of a Julia set: slice vs target, modulus/versor, mesh render");
  p->require_subcommand(1);

  struct SliceArgs {
    std::string map, target, out, axis = "z", box;
    pipeline::PicturesOptions pics;
    JuliaArgs j;
    double modulus_scale = 0.0;
    // The view: the axis, its box (default `lo`..`hi`) and the pictures' size.
    mesh::SliceView View(const Vec3& lo, const Vec3& hi) const {
      mesh::SliceView v = pics.slice;
      const std::string l = [&] {
        std::string s = axis;
        for (char& ch : s) ch = char(std::tolower(static_cast<unsigned char>(ch)));
        return s;
      }();
      if (l != "x" && l != "y" && l != "z") throw Error("--axis: expected x, y or z, found \"" + axis + "\"");
      v.axis = l == "x" ? 0 : l == "y" ? 1 : 2;
      v.min_corner = lo, v.max_corner = hi;
      if (!box.empty()) {
        const auto b = ParseBox(box);
        v.min_corner = {b[0], b[1], b[2]}, v.max_corner = {b[3], b[4], b[5]};
      }
      if (auto why = v.Validate(); !why.empty()) throw Error("picture: " + why);
      return v;
    }
  };
  auto add_view = [](CLI::App* c, SliceArgs& s) {
    c->add_option("--axis", s.axis, "Normal of the plane: x, y or z")->capture_default_str();
    c->add_option("--at", s.pics.slice.at, "Coordinate of the plane (fractal frame)")->capture_default_str();
  };
  // slice: the run's pictures stage settings (n, size) and the Julia options.
  auto s = std::make_shared<SliceArgs>();
  CLI::App* sc = p->add_subcommand(
      "slice", "The set on a plane against the target SDF: agreement grey (dark inside), orange = Julia set only, "
               "blue = target only");
  sc->add_option("map", s->map, "map.json")->required();
  sc->add_option("--target", s->target, "Target .qgrid (from quijibo sdf / monopoles, fractal frame)")->required();
  sc->add_option("-o,--out", s->out, "Output .png")->required();
  add_view(sc, *s);
  BindSettings(sc, s->pics, {"slice_iterations", "slice_size"});
  sc->add_option("--box", s->box, "Picture box (fractal frame), default the target's grid box");
  s->j.add(sc, {"escape", "capture", "iso", "precision"});
  sc->callback([s] {
    CheckPng(s->out);
    const RationalMap map = ReadMap(s->map);
    mesh::CheckSameFrame(map.frame, s->map, s->target);
    const ScalarGrid target = ReadGrid(s->target);
    const mesh::SliceView base = pipeline::TargetSliceView(target, s->pics);
    const mesh::SliceView view = s->View(base.min_corner, base.max_corner);
    s->j.o.julia.iterations = s->pics.slice_iterations;
    s->j.finish(map, {(view.min_corner[0] + view.max_corner[0]) / 2, (view.min_corner[1] + view.max_corner[1]) / 2,
                 (view.min_corner[2] + view.max_corner[2]) / 2});
    const pipeline::MeshStageOptions& o = s->j.o;
    const pipeline::SlicePicture pic =
        pipeline::SliceAgainstTargetPicture(map, target, s->target, view, o.julia, o.iso, o.precision);
    CreateParentFolder(s->out);
    WritePng(s->out, pic.image);
    WriteOutput("", pipeline::SliceReport(pic, s->out, o.julia, o.iso, o.precision).dump(2) + "\n");
  });

  // field
  auto f = std::make_shared<SliceArgs>();
  CLI::App* fc = p->add_subcommand(
      "field", "Modulus (grey, iso line red) and versor (i, j, k as RGB) of q_n on a plane, side by side");
  fc->add_option("map", f->map, "map.json")->required();
  fc->add_option("-o,--out", f->out, "Output .png")->required();
  add_view(fc, *f);
  BindSettings(fc, f->pics, {"slice_size"});
  fc->add_option("--box", f->box, "Picture box (fractal frame), default the normalized cube, box centre +-fractal_radius/2");
  fc->add_option("--modulus-scale", f->modulus_scale, "Grey = 0.5 + 0.5 tanh((log|q_n| - iso) / scale); 0: automatic")->capture_default_str();
  f->j.add(fc, {"iterations", "escape", "capture", "iso", "precision"});
  fc->callback([f] {
    CheckPng(f->out);
    const RationalMap map = ReadMap(f->map);
    const double h = map.frame.fractal_radius / 2;
    const Vec3 c = map.frame.box_center();
    const mesh::SliceView view = f->View({c[0] - h, c[1] - h, c[2] - h}, {c[0] + h, c[1] + h, c[2] + h});
    f->j.finish(map, {(view.min_corner[0] + view.max_corner[0]) / 2, (view.min_corner[1] + view.max_corner[1]) / 2,
                 (view.min_corner[2] + view.max_corner[2]) / 2});
    CreateParentFolder(f->out);
    WritePng(f->out, mesh::ModulusVersorSlice(map, f->j.o.julia, view, f->modulus_scale, f->j.o.iso));
  });

  // render
  struct RenderArgs {
    std::string mesh, out;
    pipeline::PicturesOptions pics;
  };
  auto r = std::make_shared<RenderArgs>();
  CLI::App* rc = p->add_subcommand("render", "Shaded views of a mesh (front, side, top, three-quarter), ray-traced with ambient occlusion and soft shadows");
  rc->add_option("mesh", r->mesh, "Mesh (PLY, OBJ, STL, OFF)")->required();
  rc->add_option("-o,--out", r->out, "Output .png")->required();
  BindSettings(rc, r->pics, {"render_size", "render_views", "render_shading", "render_samples", "render_ao_rays"});
  rc->callback([r] {
    CheckPng(r->out);
    const Image image = mesh::RenderMesh(mesh::ReadMesh(r->mesh), r->pics.render);
    CreateParentFolder(r->out);
    WritePng(r->out, image);
  });
}

// bench mesh's kernel cases: "KERNEL" or "KERNEL:ISA" (the vector instruction set capped, for A/B
// runs of one kernel on several instruction sets).
struct KernelCase {
  std::string label, kernel;
  VectorIsa max_isa = VectorIsa::kAvx512;
  bool capped = false;
};

KernelCase ParseKernelCase(const std::string& spec) {
  KernelCase k;
  const std::size_t colon = spec.find(':');
  k.kernel = JuliaKernelName(ParseJuliaKernel(spec.substr(0, colon)));
  k.label = k.kernel;
  if (colon != std::string::npos) {
    k.max_isa = ParseVectorIsa(spec.substr(colon + 1));
    k.capped = true;
    k.label += std::string(":") + VectorIsaName(k.max_isa);
  }
  return k;
}

// For each kernel, which of `count` seeded random points of the mesh stage's box are inside the set
// {log|q_n| < iso} the stage meshes (`setup`, its iterated map, and `o`'s settings): the volume IoU
// of the kernels' sets without meshing.
std::vector<std::vector<char>> KernelSetsAtRandomPoints(const JuliaSetup& setup,
                                                        const pipeline::MeshStageOptions& o,
                                                        const std::vector<KernelCase>& kernels, std::size_t count,
                                                        std::uint64_t seed) {
  const RationalMap& map = setup.map;
  const JuliaOptions& julia = setup.julia;
  const Vec3 &lo = setup.box_min, &hi = setup.box_max;
  std::mt19937_64 rng(seed);
  std::vector<Vec3> points(count);
  for (Vec3& p : points)
    for (int a = 0; a < 3; ++a) p[a] = lo[a] + (hi[a] - lo[a]) * (double(rng() >> 11) * 0x1p-53);
  std::vector<std::vector<char>> inside;
  for (const KernelCase& k : kernels) {
    const mesh::BatchField field =
        mesh::MakeJuliaField(map, julia, o.iso, Precision::kDouble, nullptr, ParseJuliaKernel(k.kernel), k.max_isa);
    std::vector<double> v(count);
    const std::int64_t chunk = 4096, chunks = (std::int64_t(count) + chunk - 1) / chunk;
#pragma omp parallel for schedule(dynamic)
    for (std::int64_t b = 0; b < chunks; ++b) {
      const std::size_t i0 = std::size_t(b * chunk), n = std::min<std::size_t>(std::size_t(chunk), count - i0);
      field.evaluate(points.data() + i0, n, v.data() + i0);
    }
    std::vector<char> in(count);
    for (std::size_t i = 0; i < count; ++i) in[i] = v[i] < o.iso;
    inside.push_back(std::move(in));
  }
  return inside;
}

// bench mesh: each resolution and kernel in a child process, so that its peak RSS is its own (wait4).
void AddBenchMesh(CLI::App* bench) {
  struct Args {
    std::string map, resolutions = "256,512", kernels = "scalar,vector,fused", out;
    pipeline::MeshStageOptions o;  // the mesh stage's settings (resolution and kernel: per case)
    int compare_points = 0;
  };
  auto a = std::make_shared<Args>();
  CLI::App* c = bench->add_subcommand(
      "mesh", "Seconds, throughput and peak memory of `quijibo mesh` (sparse, double) at several resolutions, for "
              "each iteration kernel");
  c->add_option("map", a->map, "map.json")->required();
  c->add_option("--resolutions", a->resolutions, "Comma-separated resolutions")->capture_default_str();
  c->add_option("--kernel", a->kernels,
                "Comma-separated iteration kernels: scalar, vector, fused, float; KERNEL:ISA caps the vector "
                "instruction set (sse2, avx2, avx512) for that case")
      ->capture_default_str();
  c->add_option("--markdown", a->out, "Append the Markdown table to this file");
  // The mesh stage's settings that change the set or its cost (intricate sets: --detail,
  // --translate-potential, --iteration-frame), as `quijibo mesh` and `quijibo run` take them.
  BindSettings(c, a->o,
               {"iterations", "escape", "capture", "iso", "translate", "translate_potential", "iteration_frame",
                "detail"});
  AddMesherOptions(c, a->o.meshing);
  c->add_option("--compare-points", a->compare_points,
                "Also the volume IoU of each kernel's set {log|q_n| < iso} against the first kernel's, at this "
                "many seeded random points of the box (0: off)")
      ->check(CLI::Range(0, 100000000))
      ->capture_default_str();
  c->callback([a] {
    const RationalMap map = ReadMap(a->map);
    std::vector<int> res;
    for (double r : ParseNumbers(a->resolutions, "--resolutions")) res.push_back(int(r));
    std::vector<KernelCase> kernels;
    {
      std::stringstream s(a->kernels);
      for (std::string k; std::getline(s, k, ',');) kernels.push_back(ParseKernelCase(k));
      if (kernels.empty()) throw Error("--kernel: name at least one kernel");
    }
    double load[3] = {0, 0, 0};
    if (::getloadavg(load, 3) < 0) load[0] = -1;
    char date[32];
    const std::time_t now = std::time(nullptr);
    std::strftime(date, sizeof date, "%Y-%m-%d", std::localtime(&now));
    const std::string isa = JuliaBatch(map, JuliaOptions{}).isa();
    // Throughput: field evaluations (nodes and bisection) per wall second, and factor evaluations
    // (one root's log, atan2, sin, cos and product) per wall second = map applications x roots.
    std::string md = "| resolution | n | kernel | seconds | CPU s | peak RSS (MB) | vertices | triangles | node evals | "
                     "bisection evals | evals/s | root x iteration evals/s (M) | tiles meshed/total |\n"
                     "|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
    json all = json::array();
    for (int r : res) {
      std::map<std::string, double> rate;
      for (const KernelCase& kc : kernels) {
        const std::string& kernel = kc.label;
        const ChildResult child = ChildProcess([&]() -> std::string {
          try {
            pipeline::MeshStageOptions o = a->o;
            o.meshing.resolution = r;
            o.kernel = kc.kernel;
            // The child's own environment: the kernels it builds take this instruction set.
            if (kc.capped) ::setenv("QUIJIBO_VECTOR_ISA", VectorIsaName(kc.max_isa), 1);
            // Made in the child: the parent runs no OpenMP region before it forks (libgomp's threads
            // do not survive a fork), and a case is its own process.
            const pipeline::MeshStageResult m = pipeline::MeshJulia(o.Iterated(map), o);
            const mesh::MeshingSummary& s = m.summary;
            const Vec4& t = m.julia.root_translation;
            return json({{"seconds", s.seconds}, {"vertices", s.vertices}, {"triangles", s.triangles},
                         {"root_translation", {t[0], t[1], t[2], t[3]}},
                         {"nodes", s.nodes_evaluated}, {"bisection", s.bisection_evaluations},
                         {"search", s.search_evaluations}, {"following", s.follow_evaluations},
                         {"escaped", m.escaped}, {"non_finite", m.non_finite},
                         {"applications", m.applications}, {"factors", m.factors},
                         {"tiles_meshed", s.tiles_meshed}, {"tiles_total", s.tiles_total}})
                .dump();
          } catch (const std::exception& e) {
            return json({{"error", e.what()}}).dump();
          }
        }).Wait();
        if (child.out.empty())
          throw Error("bench mesh: the case at resolution " + std::to_string(r) + ", kernel " + kernel + " died");
        json j = json::parse(child.out);
        if (j.contains("error")) throw Error("bench mesh: " + j["error"].get<std::string>());
        const double seconds = std::max(j["seconds"].get<double>(), 1e-9);
        const double evals = double(j["nodes"].get<std::int64_t>() + j["bisection"].get<std::int64_t>());
        j["resolution"] = r;
        j["kernel"] = kc.kernel;
        j["case"] = kc.label;
        j["vector_isa"] = kc.kernel == "scalar" ? "none" : VectorIsaName(std::min(BestVectorIsa(), kc.max_isa));
        j["peak_rss_mb"] = child.peak_rss_mb;
        j["cpu_seconds"] = child.cpu_seconds;
        j["evaluations_per_second"] = evals / seconds;
        j["factor_evaluations_per_second"] =
            double(j["applications"].get<std::int64_t>()) * double(j["factors"].get<std::size_t>()) / seconds;
        rate[kernel] = j["factor_evaluations_per_second"].get<double>();
        all.push_back(j);
        char row[512];
        std::snprintf(row, sizeof row,
                      "| %d^3 | %d | %s | %.1f | %.1f | %.0f | %lld | %lld | %lld | %lld | %.0f | %.1f | %lld/%lld |\n",
                      r, a->o.julia.iterations, kernel.c_str(), seconds, child.cpu_seconds, j["peak_rss_mb"].get<double>(),
                      (long long)j["vertices"].get<std::int64_t>(), (long long)j["triangles"].get<std::int64_t>(),
                      (long long)j["nodes"].get<std::int64_t>(), (long long)j["bisection"].get<std::int64_t>(),
                      evals / seconds, rate[kernel] / 1e6, (long long)j["tiles_meshed"].get<std::int64_t>(),
                      (long long)j["tiles_total"].get<std::int64_t>());
        md += row;
        std::fprintf(stderr, "%s", row);
      }
      for (const auto& [name, kernel_rate] : rate) {
        if (name == "scalar" || !rate.count("scalar") || rate["scalar"] <= 0) continue;
        char line[160];
        std::snprintf(line, sizeof line, "| %d^3 | | %s / scalar | | | | | | | | | %.2fx | |\n", r, name.c_str(),
                      kernel_rate / rate["scalar"]);
        md += line;
        std::fprintf(stderr, "%s", line);
      }
    }
    json agreement = json::array();
    if (a->compare_points > 0 && kernels.size() > 1) {
      const std::vector<std::vector<char>> inside = KernelSetsAtRandomPoints(
          a->o.Iterated(map), a->o, kernels, std::size_t(a->compare_points), /*seed=*/1);
      for (std::size_t k = 1; k < kernels.size(); ++k) {
        std::int64_t both = 0, either = 0, differ = 0;
        for (std::size_t i = 0; i < inside[0].size(); ++i) {
          both += inside[0][i] && inside[k][i];
          either += inside[0][i] || inside[k][i];
          differ += inside[0][i] != inside[k][i];
        }
        const double iou = either ? double(both) / double(either) : 1.0;
        agreement.push_back({{"kernel", kernels[k].label}, {"against", kernels[0].label}, {"points", a->compare_points},
                             {"inside", either}, {"differing", differ}, {"volume_iou", iou}});
        char line[256];
        std::snprintf(line, sizeof line, "\nVolume IoU of %s's set against %s's: %.6f (%lld of %d random points differ)\n",
                      kernels[k].label.c_str(), kernels[0].label.c_str(), iou, (long long)differ, a->compare_points);
        md += line;
        std::fprintf(stderr, "%s", line);
      }
    }
    const json doc = {{"benchmark", "mesh"}, {"date", date}, {"map", a->map}, {"mesh_settings", a->o.ToJson()},
                      {"cores", int(::sysconf(_SC_NPROCESSORS_ONLN))}, {"load_average_at_start", load[0]},
                      {"vector_isa", isa}, {"results", all}, {"set_agreement", agreement}};
    if (!a->out.empty()) {
      std::string old;
      if (std::filesystem::exists(a->out)) old = ReadFile(a->out);
      WriteFileAtomically(a->out, old + md);
    }
    WriteOutput("", doc.dump(2) + "\n");
  });
}

}  // namespace

void AddMeshCommand(CLI::App& app, const pipeline::Mesher& mesher, const pipeline::StreamMesher& stream_mesher) {
  AddMesh(app, mesher, stream_mesher);
}

void AddJuliaCommands(CLI::App& app, CLI::App& bench) {
  AddMesh(app, pipeline::LocalMesher, pipeline::LocalStreamMesher);
  AddPicture(app);
  AddBenchMesh(&bench);
}

}  // namespace quijibo::cli
