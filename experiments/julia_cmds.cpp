// `quijibo mesh`, `quijibo picture` and `quijibo bench mesh`: meshing and viewing the Julia set of a
// map (docs/meshing.md).
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <sstream>

#include "experiments/cli.h"
#include "mesh/julia_field.h"
#include "mesh/marching_cubes.h"
#include "mesh/pictures.h"
#include "mesh/sdf_command.h"
#include "mesh/triangle_mesh.h"
#include "mesh/vdb.h"
#include "quijibo/error.h"
#include "quijibo/io.h"
#include "quijibo/julia.h"
#include "quijibo/progress.h"
#include "quijibo/rational_map.h"

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

std::string Lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return s;
}
std::string Extension(const std::string& path) { return Lower(std::filesystem::path(path).extension().string()); }

// Fails early (before any long computation) when an output cannot be written.
void CheckOutput(const std::string& path, const std::vector<std::string>& extensions, const std::string& what) {
  if (path.empty()) return;
  if (std::find(extensions.begin(), extensions.end(), Extension(path)) == extensions.end()) {
    std::string list;
    for (const auto& e : extensions) list += (list.empty() ? "" : " or ") + e;
    throw Error(path + ": " + what + " must end in " + list);
  }
  const auto dir = std::filesystem::path(path).parent_path();
  if (!dir.empty() && !std::filesystem::is_directory(dir))
    throw Error(path + ": folder " + dir.string() + " does not exist");
}

// The Julia-set options every command shares.
struct JuliaArgs {
  JuliaOptions julia;
  std::string translate, rotate, precision = "double";
  double iso = 0.0;
  void add(CLI::App* c) {
    c->add_option("-n,--iterations", julia.iterations, "Map applications n (paper: 1 and 4)")->capture_default_str();
    c->add_option("--escape", julia.escape_radius, "Escape radius (reference: 2000)")->capture_default_str();
    c->add_option("--iso", iso, "Iso value of log|q_n| (reference: 0)")->capture_default_str();
    c->add_option("--slice", julia.slice, "k component S of the starting quaternion")->capture_default_str();
    c->add_option("--translate", translate,
                  "Root translation x,y,z[,k] added to every root and sample (changes the set when n > 1)");
    c->add_option("--root-scale", julia.root_scale, "Roots scaled about the origin by this")->capture_default_str();
    c->add_option("--rotate", rotate, "Rotate the sampling box about its centre: ax,ay,az,degrees");
    c->add_option("--precision", precision, "float, double, long-double or float128")->capture_default_str();
  }
  // Completes the options once the box is known.
  void finish(const Vec3& box_center) {
    if (!translate.empty()) {
      const auto t = ParseNumbers(translate, "--translate");
      if (t.size() != 3 && t.size() != 4) throw Error("--translate: expected x,y,z or x,y,z,k");
      for (std::size_t a = 0; a < t.size(); ++a) julia.root_translation[a] = t[a];
    }
    if (!rotate.empty()) {
      const auto r = ParseNumbers(rotate, "--rotate");
      if (r.size() != 4) throw Error("--rotate: expected ax,ay,az,degrees");
      julia.placement = SampleTransform::AxisAngle({r[0], r[1], r[2]}, r[3], box_center);
    }
    if (auto why = julia.validate(); !why.empty()) throw Error(why);
  }
  json to_json() const {
    return {{"iterations", julia.iterations}, {"escape_radius", julia.escape_radius}, {"iso", iso},
            {"slice", julia.slice}, {"root_translation", julia.root_translation}, {"root_scale", julia.root_scale},
            {"rotation", julia.placement.rotation}, {"rotation_center", julia.placement.center},
            {"precision", precision}};
  }
};

// The box: --box x0,y0,z0,x1,y1,z1, else the default.
void ParseBox(const std::string& text, Vec3& lo, Vec3& hi) {
  const auto b = ParseNumbers(text, "--box");
  if (b.size() != 6) throw Error("--box: expected xmin,ymin,zmin,xmax,ymax,zmax");
  for (int a = 0; a < 3; ++a) {
    lo[a] = b[a];
    hi[a] = b[3 + a];
    if (!(hi[a] > lo[a])) throw Error("--box: max must exceed min on every axis");
  }
}

int ParseAxis(const std::string& s) {
  const std::string l = Lower(s);
  if (l == "x") return 0;
  if (l == "y") return 1;
  if (l == "z") return 2;
  throw Error("--axis: expected x, y or z, found \"" + s + "\"");
}

struct MeshArgs {
  std::string map, out, obj, vdb, frame = "user", box, summary;
  std::vector<std::string> vdb_grids{"surface", "density"};
  double vdb_band = 3.0;
  JuliaArgs j;
  MeshingOptions meshing;
  bool ply_double = false, allow_empty = false;
};

struct MeshRun {
  TriangleMesh mesh;
  MeshingSummary summary;
  FieldBand band;
  std::int64_t escaped = 0, non_finite = 0;
};

bool LocalMesher(const BatchField& field, const MeshingOptions& o, MeshingSummary* summary, FieldBand* band,
                 TriangleMesh* mesh, JuliaFieldStats*) {
  *mesh = MeshField(field, o, summary, band);
  return true;
}

// Everything `quijibo mesh` computes, before writing; false on processes that do not write.
bool RunMesh(MeshArgs& a, const RationalMap& map, bool want_band, const Mesher& mesher, MeshRun& run) {
  MeshingOptions& o = a.meshing;
  const double half = map.frame.fractal_radius / 2;
  const Vec3 c = map.frame.box_center();
  o.min_corner = {c[0] - half, c[1] - half, c[2] - half};
  o.max_corner = {c[0] + half, c[1] + half, c[2] + half};
  if (!a.box.empty()) ParseBox(a.box, o.min_corner, o.max_corner);
  if (auto why = o.validate(); !why.empty()) throw Error("mesh: " + why);
  a.j.finish({(o.min_corner[0] + o.max_corner[0]) / 2, (o.min_corner[1] + o.max_corner[1]) / 2,
              (o.min_corner[2] + o.max_corner[2]) / 2});
  JuliaFieldStats stats;
  const BatchField field = MakeJuliaField(map, a.j.julia, a.j.iso, ParsePrecision(a.j.precision), &stats);
  const bool writer = mesher(field, o, &run.summary, want_band ? &run.band : nullptr, &run.mesh, &stats);
  run.escaped = stats.escaped;
  run.non_finite = stats.non_finite;
  return writer;
}

MeshRun RunMesh(MeshArgs& a, const RationalMap& map, bool want_band) {
  MeshRun run;
  RunMesh(a, map, want_band, LocalMesher, run);
  return run;
}

// From the box coordinates the mesher used to the fractal frame (rotation), then the user frame.
void PlaceVertices(TriangleMesh& mesh, const JuliaOptions& julia, const FractalFrame& frame, bool user) {
  const bool rotate = !julia.placement.is_identity();
  for (Vec3& v : mesh.vertices) {
    if (rotate) v = julia.placement.apply(v);
    if (user) v = frame.fractal_to_user(v);
  }
}

void AddMesh(CLI::App& app, const Mesher& mesher) {
  auto a = std::make_shared<MeshArgs>();
  CLI::App* c = app.add_subcommand(
      "mesh", "Mesh the Julia set {log|q_n| < iso} of a map by marching cubes with bisection (PLY/OBJ, .vdb)");
  c->add_option("map", a->map, "map.json")->required();
  c->add_option("-o,--out", a->out, "Output mesh (.ply binary, or .obj)")->required();
  c->add_option("--obj", a->obj, "Also write the mesh as OBJ here");
  c->add_option("--vdb", a->vdb, "Also write volumes as OpenVDB (--vdb-grids)");
  c->add_option("--vdb-grids", a->vdb_grids,
                "Grids of the .vdb: surface (narrow-band level set), density (fog volume), field (raw log|q_n| on "
                "the surface's cells)")
      ->delimiter(',')
      ->check(CLI::IsMember({"surface", "density", "field"}))
      ->capture_default_str();
  c->add_option("--vdb-band", a->vdb_band, "Half-width of the level set's narrow band, voxels")
      ->capture_default_str()
      ->check(CLI::Range(1.0, 1000.0));
  c->add_option("-r,--resolution", a->meshing.resolution, "Cells along the longest side of the box")
      ->capture_default_str()
      ->check(CLI::Range(2, 65536));
  c->add_option("--frame", a->frame, "Coordinates of the output: user (the input mesh's) or fractal")
      ->capture_default_str()
      ->check(CLI::IsMember({"user", "fractal"}));
  c->add_option("--box", a->box, "Zoom box in the fractal frame: xmin,ymin,zmin,xmax,ymax,zmax (default: the whole "
                                 "normalized cube, its centre +-fractal_radius/2)");
  AddMesherOptions(c, a->meshing);
  c->add_flag("--ply-double", a->ply_double, "PLY coordinates as double (default float)");
  c->add_flag("--allow-empty", a->allow_empty,
              "A surface that does not cross the box is a result, not an error: write the summary (0 "
              "triangles) and no mesh files");
  c->add_option("--summary", a->summary, "Write the run summary (JSON) here instead of stdout");
  a->j.add(c);
  c->callback([a, mesher] {
    CheckOutput(a->out, {".ply", ".obj"}, "the mesh");
    CheckOutput(a->obj, {".obj"}, "--obj");
    CheckOutput(a->vdb, {".vdb"}, "--vdb");
    const RationalMap map = ReadMap(a->map);
    a->meshing.show_progress = true;
    MeshRun run;
    auto wants = [&](const char* grid) { return std::find(a->vdb_grids.begin(), a->vdb_grids.end(), grid) != a->vdb_grids.end(); };
    if (!a->vdb.empty() && a->vdb_grids.empty()) throw Error("--vdb-grids: name at least one grid");
    if (!RunMesh(*a, map, !a->vdb.empty() && wants("field"), mesher, run)) return;
    const bool empty = run.mesh.triangles.empty();
    if (empty && !a->allow_empty)
      throw Error(a->map + ": the surface log|q_n| = " + std::to_string(a->j.iso) +
                  " does not cross the box (no triangles); nothing written");
    const bool user = a->frame == "user";
    PlaceVertices(run.mesh, a->j.julia, map.frame, user);
    // Write.
    if (empty) {
      std::fprintf(stderr, "quijibo: the surface does not cross the box (no triangles): no mesh written\n");
    } else if (Extension(a->out) == ".obj") {
      WriteObj(a->out, run.mesh);
    } else {
      WritePly(a->out, run.mesh, a->ply_double ? PlyPrecision::kFloat64 : PlyPrecision::kFloat32);
    }
    if (!a->obj.empty() && !empty) WriteObj(a->obj, run.mesh);
    if (!a->vdb.empty() && !empty) {
      const MeshLattice& l = run.band.lattice;
      const double spacing = run.summary.spacing / (user ? map.frame.user_to_fractal_scale() : 1.0);
      VdbVolumeOptions vo;
      vo.voxel_size = spacing;
      vo.half_width = a->vdb_band;
      vo.surface = wants("surface");
      vo.density = wants("density");
      vo.coordinates = user ? "user" : "fractal";
      VdbRawField raw;
      if (wants("field")) {
        raw.origin = user ? map.frame.fractal_to_user(l.origin) : l.origin;
        raw.spacing = spacing;
        raw.voxels = &run.band.nodes;
        raw.values = &run.band.values;
        raw.background = std::numeric_limits<float>::max();
        raw.iso = a->j.iso;
        raw.name = "julia";
        raw.quantity = "log-modulus";
      }
      WriteVdbVolumes(a->vdb, run.mesh, vo, wants("field") ? &raw : nullptr);
    }
    const MeshTopology topo = AnalyzeTopology(run.mesh);
    const MeshingSummary& s = run.summary;
    json summary = {
        {"map", a->map}, {"out", empty ? json(nullptr) : json(a->out)}, {"frame", a->frame}, {"julia", a->j.to_json()},
        {"box", {{"min", a->meshing.min_corner}, {"max", a->meshing.max_corner}}},
        {"resolution", a->meshing.resolution}, {"cells", s.cells}, {"spacing", s.spacing},
        {"band_nodes", run.band.nodes.size()}};
    summary.update(MesherSummaryJson(s, a->meshing));
    summary["boundary_edges"] = topo.boundary_edges;  // = open_edges (kept for older readers)
    summary["non_manifold_edges"] = topo.non_manifold_edges;
    summary["evaluations"]["escaped"] = run.escaped;
    WriteOutput(a->summary, summary.dump(2) + "\n");
  });
}

SliceView MakeView(const std::string& axis, double at, int size, const std::string& box, const Vec3& lo,
                   const Vec3& hi) {
  SliceView v;
  v.axis = ParseAxis(axis);
  v.at = at;
  v.size = size;
  v.min_corner = lo;
  v.max_corner = hi;
  if (!box.empty()) ParseBox(box, v.min_corner, v.max_corner);
  if (auto why = v.validate(); !why.empty()) throw Error("picture: " + why);
  return v;
}

void AddPicture(CLI::App& app) {
  CLI::App* p = app.add_subcommand("picture", "PNG pictures of a Julia set: slice vs target, modulus/versor, mesh render");
  p->require_subcommand(1);

  struct SliceArgs {
    std::string map, target, out, axis = "z", box;
    double at = 0.0;
    int size = 512;
    JuliaArgs j;
    double modulus_scale = 0.0;
  };
  // slice
  auto s = std::make_shared<SliceArgs>();
  CLI::App* sc = p->add_subcommand(
      "slice", "The set on a plane against the target SDF: agreement grey (dark inside), orange = Julia set only, "
               "blue = target only");
  sc->add_option("map", s->map, "map.json")->required();
  sc->add_option("--target", s->target, "Target .qgrid (from quijibo sdf / monopoles, fractal frame)")->required();
  sc->add_option("-o,--out", s->out, "Output .png")->required();
  sc->add_option("--axis", s->axis, "Normal of the plane: x, y or z")->capture_default_str();
  sc->add_option("--at", s->at, "Coordinate of the plane (fractal frame)")->capture_default_str();
  sc->add_option("--size", s->size, "Pixels along the longer side")->capture_default_str();
  sc->add_option("--box", s->box, "Picture box (fractal frame), default the target's grid box");
  s->j.add(sc);
  sc->callback([s] {
    CheckOutput(s->out, {".png"}, "the picture");
    const RationalMap map = ReadMap(s->map);
    const ScalarGrid target = ReadGrid(s->target);
    if (target.coordinates != "fractal")
      throw Error(s->target + ": expected a grid in fractal coordinates, found \"" + target.coordinates + "\"");
    const std::string frame_path = FrameJsonPathFor(s->target);
    if (std::filesystem::exists(frame_path)) {
      const FractalFrame f = ReadFrameJson(frame_path);
      const auto same = [](double x, double y) { return std::abs(x - y) <= 1e-9 * std::max(1.0, std::abs(x)); };
      if (!same(f.scale, map.frame.scale) || !same(f.fractal_radius, map.frame.fractal_radius) ||
          !same(f.translation[0], map.frame.translation[0]) || !same(f.translation[1], map.frame.translation[1]) ||
          !same(f.translation[2], map.frame.translation[2]))
        throw Error(s->target + ": its frame (" + frame_path + ") differs from the map's: not the same mesh");
    }
    const Vec3 lo = target.frame.min_corner, ext = target.frame.extent();
    const SliceView view =
        MakeView(s->axis, s->at, s->size, s->box, lo, {lo[0] + ext[0], lo[1] + ext[1], lo[2] + ext[2]});
    s->j.finish({(view.min_corner[0] + view.max_corner[0]) / 2, (view.min_corner[1] + view.max_corner[1]) / 2,
                 (view.min_corner[2] + view.max_corner[2]) / 2});
    const BatchField field = MakeJuliaField(map, s->j.julia, s->j.iso, ParsePrecision(s->j.precision));
    SliceAgreement agree;
    const Image img = SliceAgainstTarget(field, target, view, &agree);
    WritePng(s->out, img);
    WriteOutput("", json({{"out", s->out}, {"agreement", agree.agreement()}, {"both_inside", agree.both_inside},
                          {"both_outside", agree.both_outside}, {"julia_only", agree.julia_only},
                          {"target_only", agree.target_only}, {"julia", s->j.to_json()}})
                            .dump(2) +
                        "\n");
  });

  // field
  auto f = std::make_shared<SliceArgs>();
  CLI::App* fc = p->add_subcommand(
      "field", "Modulus (grey, iso line red) and versor (i, j, k as RGB) of q_n on a plane, side by side");
  fc->add_option("map", f->map, "map.json")->required();
  fc->add_option("-o,--out", f->out, "Output .png")->required();
  fc->add_option("--axis", f->axis, "Normal of the plane: x, y or z")->capture_default_str();
  fc->add_option("--at", f->at, "Coordinate of the plane (fractal frame)")->capture_default_str();
  fc->add_option("--size", f->size, "Pixels along the longer side of each panel")->capture_default_str();
  fc->add_option("--box", f->box, "Picture box (fractal frame), default the normalized cube, box centre +-fractal_radius/2");
  fc->add_option("--modulus-scale", f->modulus_scale, "Grey = 0.5 + 0.5 tanh((log|q_n| - iso) / scale); 0: automatic")->capture_default_str();
  f->j.add(fc);
  fc->callback([f] {
    CheckOutput(f->out, {".png"}, "the picture");
    const RationalMap map = ReadMap(f->map);
    const double h = map.frame.fractal_radius / 2;
    const Vec3 c = map.frame.box_center();
    const SliceView view =
        MakeView(f->axis, f->at, f->size, f->box, {c[0] - h, c[1] - h, c[2] - h}, {c[0] + h, c[1] + h, c[2] + h});
    f->j.finish({(view.min_corner[0] + view.max_corner[0]) / 2, (view.min_corner[1] + view.max_corner[1]) / 2,
                 (view.min_corner[2] + view.max_corner[2]) / 2});
    WritePng(f->out, ModulusVersorSlice(map, f->j.julia, view, f->modulus_scale, f->j.iso));
  });

  // render
  struct RenderArgs {
    std::string mesh, out;
    int size = 400, views = 4;
  };
  auto r = std::make_shared<RenderArgs>();
  CLI::App* rc = p->add_subcommand("render", "Shaded views of a mesh (front, side, top, three-quarter)");
  rc->add_option("mesh", r->mesh, "Mesh (PLY, OBJ, STL, OFF)")->required();
  rc->add_option("-o,--out", r->out, "Output .png")->required();
  rc->add_option("--size", r->size, "Pixels per view")->capture_default_str()->check(CLI::Range(16, 8192));
  rc->add_option("--views", r->views, "Number of views, 1 to 4")->capture_default_str()->check(CLI::Range(1, 4));
  rc->callback([r] {
    CheckOutput(r->out, {".png"}, "the picture");
    const TriangleMesh mesh = ReadMesh(r->mesh);
    WritePng(r->out, RenderMesh(mesh, r->size, r->views));
  });
}

// bench mesh: each resolution in a child process, so that its peak RSS is its own (wait4).
void AddBenchMesh(CLI::App& app) {
  CLI::App* bench = app.get_subcommand("bench");
  struct Args {
    std::string map, resolutions = "256,512", out;
    int iterations = 4;
  };
  auto a = std::make_shared<Args>();
  CLI::App* c = bench->add_subcommand(
      "mesh", "Seconds and peak memory of `quijibo mesh` (sparse, double) at several resolutions");
  c->add_option("map", a->map, "map.json")->required();
  c->add_option("--resolutions", a->resolutions, "Comma-separated resolutions")->capture_default_str();
  c->add_option("-n,--iterations", a->iterations, "Map applications n")->capture_default_str();
  c->add_option("--markdown", a->out, "Append the Markdown table to this file");
  c->callback([a] {
    const RationalMap map = ReadMap(a->map);
    std::vector<int> res;
    for (double r : ParseNumbers(a->resolutions, "--resolutions")) res.push_back(int(r));
    double load[3] = {0, 0, 0};
    if (::getloadavg(load, 3) < 0) load[0] = -1;
    char date[32];
    const std::time_t now = std::time(nullptr);
    std::strftime(date, sizeof date, "%Y-%m-%d", std::localtime(&now));
    std::string md = "| resolution | n | seconds | peak RSS (MB) | vertices | triangles | node evals | bisection evals | "
                     "tiles meshed/total |\n|---|---|---|---|---|---|---|---|---|\n";
    json all = json::array();
    for (int r : res) {
      int fd[2];
      if (::pipe(fd) != 0) throw Error("bench mesh: cannot create a pipe");
      std::fflush(nullptr);
      const pid_t pid = ::fork();
      if (pid < 0) throw Error("bench mesh: cannot fork");
      if (pid == 0) {
        ::close(fd[0]);
        std::string line;
        try {
          MeshArgs m;
          m.map = a->map;
          m.meshing.resolution = r;
          m.j.julia.iterations = a->iterations;
          MeshRun run = RunMesh(m, map, false);
          const MeshingSummary& s = run.summary;
          line = json({{"seconds", s.seconds}, {"vertices", s.vertices}, {"triangles", s.triangles},
                       {"nodes", s.nodes_evaluated}, {"bisection", s.bisection_evaluations},
                       {"tiles_meshed", s.tiles_meshed}, {"tiles_total", s.tiles_total}})
                     .dump();
        } catch (const std::exception& e) {
          line = json({{"error", e.what()}}).dump();
        }
        if (::write(fd[1], line.data(), line.size()) < 0) _exit(2);
        _exit(0);
      }
      ::close(fd[1]);
      std::string text;
      char buf[4096];
      for (ssize_t n; (n = ::read(fd[0], buf, sizeof buf)) > 0;) text.append(buf, std::size_t(n));
      ::close(fd[0]);
      int status = 0;
      struct rusage usage {};
      ::wait4(pid, &status, 0, &usage);
      if (text.empty()) throw Error("bench mesh: the case at resolution " + std::to_string(r) + " died");
      json j = json::parse(text);
      if (j.contains("error")) throw Error("bench mesh: " + j["error"].get<std::string>());
      j["resolution"] = r;
      j["peak_rss_mb"] = double(usage.ru_maxrss) / 1024.0;
      j["cpu_seconds"] = double(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
                         1e-6 * double(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
      all.push_back(j);
      char row[512];
      std::snprintf(row, sizeof row, "| %d^3 | %d | %.1f | %.0f | %lld | %lld | %lld | %lld | %lld/%lld |\n", r,
                    a->iterations, j["seconds"].get<double>(), j["peak_rss_mb"].get<double>(),
                    (long long)j["vertices"].get<std::int64_t>(), (long long)j["triangles"].get<std::int64_t>(),
                    (long long)j["nodes"].get<std::int64_t>(), (long long)j["bisection"].get<std::int64_t>(),
                    (long long)j["tiles_meshed"].get<std::int64_t>(), (long long)j["tiles_total"].get<std::int64_t>());
      md += row;
      std::fprintf(stderr, "%s", row);
    }
    const json doc = {{"benchmark", "mesh"}, {"date", date}, {"map", a->map},
                      {"cores", int(::sysconf(_SC_NPROCESSORS_ONLN))}, {"load_average_at_start", load[0]},
                      {"results", all}};
    if (!a->out.empty()) {
      std::string old;
      if (std::filesystem::exists(a->out)) old = ReadFile(a->out);
      WriteFileAtomically(a->out, old + md);
    }
    WriteOutput("", doc.dump(2) + "\n");
  });
}

}  // namespace

void AddMeshCommand(CLI::App& app, const Mesher& mesher) { AddMesh(app, mesher); }

void AddJuliaCommands(CLI::App& app) {
  AddMesh(app, LocalMesher);
  AddPicture(app);
  AddBenchMesh(app);
}

}  // namespace quijibo::cli
