#include "experiments/pipeline/mesh.h"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <limits>

#include "mesh/vdb.h"
#include "util/error.h"

namespace quijibo::pipeline {

using nlohmann::json;
namespace fs = std::filesystem;

namespace {

std::string Extension(const std::string& path) {
  std::string e = fs::path(path).extension().string();
  std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return e;
}

void CheckOutput(const std::string& path, const std::vector<std::string>& extensions, const std::string& what) {
  if (path.empty()) return;
  if (std::find(extensions.begin(), extensions.end(), Extension(path)) == extensions.end()) {
    std::string list;
    for (const auto& e : extensions) list += (list.empty() ? "" : " or ") + e;
    throw Error(path + ": " + what + " must end in " + list);
  }
  const auto dir = fs::path(path).parent_path();
  if (!dir.empty() && !fs::is_directory(dir)) throw Error(path + ": folder " + dir.string() + " does not exist");
}

bool Wants(const MeshStageOptions& o, const char* grid) {
  return std::find(o.vdb_grids.begin(), o.vdb_grids.end(), grid) != o.vdb_grids.end();
}

// From the box coordinates the mesher used to the fractal frame (rotation), then the user frame.
std::function<Vec3(const Vec3&)> OutputTransform(const MeshStageResult& r, const MeshStageOptions& o) {
  const bool rotate = !r.julia.placement.is_identity(), user = o.frame == "user";
  return [rotate, user, placement = r.julia.placement, frame = r.frame](const Vec3& x) {
    Vec3 v = x;
    if (rotate) v = placement.apply(v);
    if (user) v = frame.fractal_to_user(v);
    return v;
  };
}

}  // namespace

const Schema<MeshStageOptions>& MeshStageOptions::Settings() {
  using O = MeshStageOptions;
  static const Schema<O> s =
      Schema<O>()
          .Boolean("enabled", "", "Mesh the Julia set", [](auto& o) -> bool& { return o.enabled; })
          .Integer(
              "resolution", "-r,--resolution", "Cells along the longest side of the box",
              [](auto& o) -> int& { return o.meshing.resolution; }, mesh::MeshingOptions::kResolutionRange)
          .Doc("marching-cubes cells along the box's longest side (`MeshingOptions`, as `quijibo mesh -r`)")
          .Integer(
              "iterations", "-n,--iterations", "Map applications n (paper: 1 and 4)",
              [](auto& o) -> int& { return o.julia.iterations; }, 1, 1000)
          .Number(
              "escape", "--escape", "Escape radius (reference: 2000)",
              [](auto& o) -> double& { return o.julia.escape_radius; }, 1.0, 1e300, true)
          .Number(
              "capture", "--capture",
              "Capture radius: an iterate with |q| below it stops and counts as inside (reference: 1.2e-37, "
              "10 FLT_MIN; 0: off); matters only with --translate",
              [](auto& o) -> double& { return o.julia.capture_radius; }, 0.0, 1.0, false)
          .Doc("capture radius: an iterate with |q| below it stops and counts as inside (the reference's "
               "bail-out, 10 FLT_MIN = 1.2e-37; 0 off); changes only translated sets ([meshing.md](meshing.md) "
               "\"Root translation\")")
          .Number(
              "iso", "--iso", "Iso value of log|q_n| (reference: 0)", [](auto& o) -> double& { return o.iso; }, -1e6,
              1e6)
          .Doc("the surface log|q_n| = iso")
          .Numbers(
              "translate", "--translate",
              "Root translation x,y,z[,k] added to every root and sample, in the iteration frame (changes the set "
              "when n > 1; the paper's Fig. 1c: 0,0,1.41 with iteration_frame reference)",
              [](auto& o) -> std::optional<std::vector<double>>& { return o.translate; }, {3, 4}, -1e6, 1e6)
          .Doc("root translation x, y, z[, k] in the iteration frame (as `quijibo mesh --translate`; changes the set "
               "when n > 1)")
          .Number(
              "translate_potential", "--translate-potential",
              "Root translation chosen by the potential L = log|R| it leaves at -t, where the map sends the inside "
              "of the set: along --translate's direction (default z), -3 rough, -2 intricate, -1.5 breaks up "
              "(docs/meshing.md)",
              [](auto& o) -> std::optional<double>& { return o.translate_potential; }, kTranslatePotentialRange)
          .Doc("root translation by its effect: t along `translate`'s direction (default z; its length is ignored) "
               "such that the iterated map's potential L = log|R| is this at −t, the point the inside of the "
               "set is sent to: −3 rough, −2 intricate, −1.5 breaks up, 0 the surface; the translation found is "
               "reported ([meshing.md](meshing.md) \"Root translation\")")
          .Enum("iteration_frame", "--iteration-frame",
                "Frame the map is iterated in (and --translate, --box given in): map (as optimized) or reference "
                "(the reference code's: origin at the box centre, longest side 3)",
                kIterationFrameNames, [](const MeshStageOptions& o) { return IterationFrameName(o.iteration_frame); },
                [](MeshStageOptions& o, const std::string& v) { o.iteration_frame = ParseIterationFrame(v); })
          .Doc("the frame the map is iterated in and `translate` is given in: the map's own, or the reference "
               "code's (origin at the mesh's bounding-box centre, longest side 3), where the paper's translations "
               "are given ([meshing.md](meshing.md) \"Root translation\")")
          .Number(
              "detail", "--detail",
              "Fractal detail: the width of the band |L| < 1 about the surface, percent of the shape's size; the "
              "one-step set stays (0.25: smooth; 0: as optimized; 2: rough; 8: intricate; docs/meshing.md)",
              [](auto& o) -> double& { return o.detail; }, 0.0, 100.0)
          .Doc("fractal detail: the band |L| < 1 about the surface made this percent of the shape's size wide; "
               "the one-step set stays (0.25 smooth, whatever the optimizer left; 0 the map as optimized; 2 rough; "
               "8 intricate; 16 loses the shape; [meshing.md](meshing.md) \"Detail\")")
          .Choice("frame", "--frame", "Coordinates of the output: user (the input mesh's) or fractal",
                  [](auto& o) -> std::string& { return o.frame; }, {"user", "fractal"})
          .Boolean("vdb", "", "Also write julia.vdb", [](auto& o) -> bool& { return o.vdb; })
          .Boolean("obj", "", "Also write julia.obj", [](auto& o) -> bool& { return o.obj; })
          .Boolean("stream", "--stream",
                   "Write the PLY (and the .vdb's field grid) as the tiles finish: memory bounded by the front of "
                   "tiles, not by the mesh; the same bytes as without it. Face indices int up to 2^31 vertices, uint "
                   "up to 2^32, uint64 beyond; no OBJ, and the .vdb holds only the grid field (docs/meshing.md)",
                   [](auto& o) -> bool& { return o.stream; })
          .Doc("write julia.ply as the mesher's tiles finish, memory bounded by the front of tiles rather than by "
               "the mesh; the file is the same, byte for byte; needs `vdb` and `obj` false (the .vdb's grids and the "
               "OBJ are made from the whole mesh) and leaves out the summary's `detail` ([meshing.md](meshing.md) "
               "\"Streaming to disk\")")
          .Enum(
              "precision", "--precision", "Iteration precision: float, double, long-double or float128", kPrecisionNames,
              [](const MeshStageOptions& o) { return PrecisionName(o.precision); },
              [](MeshStageOptions& o, const std::string& v) { o.precision = ParsePrecision(v); })
          .Choice(
              "kernel", "--kernel",
              "Iteration kernel in double precision: fused (SIMD, quijibo's own log, atan2 and sincos; the default), "
              "vector (SIMD, glibc libmvec), float (float functions per factor) or scalar (the reference); other "
              "precisions are scalar",
              [](auto& o) -> std::string& { return o.kernel; }, kJuliaKernelNames)
          .Doc("iteration kernel in double: SIMD with quijibo's own functions (`fused`, `quijibo/vector_math.h`; the "
               "same meshes as `vector`, faster with AVX-512) or with libmvec (`vector`), float functions per factor "
               "(`float`), or the scalar reference ([meshing.md](meshing.md))")
          .String("optimizer", "", "Which optimizer's map to mesh",
                  [](auto& o) -> std::string& { return o.optimizer; })
          .Doc("which optimized map to mesh (unset: the first optimizer's)");
  return s;
}

JuliaSetupOptions MeshStageOptions::Setup() const {
  JuliaSetupOptions s;
  s.julia = julia;
  s.frame = iteration_frame;
  s.detail = detail;
  s.translate = translate;
  s.translate_potential = translate_potential;
  s.box = box;
  s.rotation = rotation;
  return s;
}

JuliaSetup MeshStageOptions::Iterated(const RationalMap& input_map) const {
  if (auto why = Validate(); !why.empty()) throw Error("mesh: " + why);
  return MakeJuliaSetup(input_map, Setup());
}

JuliaOptions MeshStageOptions::TranslatedJuliaOfIterated(const RationalMap& iterated) const {
  JuliaOptions j = julia;
  j.root_translation = ResolveRootTranslation(iterated, Setup());
  return j;
}

std::string MeshStageOptions::Validate() const {
  if (std::string why = Settings().Check(*this); !why.empty()) return why;
  for (const auto& g : vdb_grids)
    if (g != "surface" && g != "density" && g != "field")
      return "vdb grids: expected surface, density or field, found " + g;
  if (!(vdb_band >= 1 && vdb_band <= 1000)) return "vdb band: expected a number in [1, 1000]";
  return Setup().Validate();
}

MeshStageOptions MeshStageOptions::FromJson(const JsonReader& r, const std::string& p, const fs::path& base,
                                            const MeshStageOptions& start) {
  return Settings().FromJson(r, p, base, start);
}

json MeshStageOptions::ToJson() const {
  json j = Settings().ToJson(*this);
  // Off is left out, so that the stage caches of runs made before the key existed stay valid.
  if (!stream) j.erase("stream");
  return j;
}

bool LocalMesher(const mesh::BatchField& field, const mesh::MeshingOptions& o, mesh::MeshingSummary* summary,
                 mesh::FieldBand* band, mesh::TriangleMesh* mesh, mesh::JuliaFieldStats*) {
  *mesh = mesh::MeshField(field, o, summary, band);
  return true;
}

namespace {

// The result's settings as used: the box, the frame, the detail's factor and the placement.
MeshStageResult StartResult(const JuliaSetup& setup, const MeshStageOptions& o) {
  if (auto why = o.Validate(); !why.empty()) throw Error("mesh: " + why);
  MeshStageResult r;
  r.lambda = setup.lambda;
  r.frame = setup.map.frame;
  r.meshing = o.meshing;
  r.meshing.min_corner = setup.box_min;
  r.meshing.max_corner = setup.box_max;
  if (auto why = r.meshing.Validate(); !why.empty()) throw Error("mesh: " + why);
  r.julia = setup.julia;
  return r;
}

}  // namespace

MeshStageResult MeshJulia(const JuliaSetup& setup, const MeshStageOptions& o, const Mesher& mesher) {
  MeshStageResult r = StartResult(setup, o);
  const RationalMap& map = setup.map;
  mesh::MeshingOptions& m = r.meshing;
  mesh::JuliaFieldStats stats;
  const mesh::BatchField field = mesh::MakeJuliaField(map, r.julia, o.iso, o.precision, &stats,
                                                       ParseJuliaKernel(o.kernel));
  const bool want_band = Wants(o, "field");
  r.writer = mesher(field, m, &r.summary, want_band ? &r.band : nullptr, &r.mesh, &stats);
  r.escaped = stats.escaped;
  r.non_finite = stats.non_finite;
  r.applications = stats.applications;
  r.factors = JuliaMap<double>(map, r.julia).Factors().size();
  const auto to_output = OutputTransform(r, o);
  for (Vec3& v : r.mesh.vertices) v = to_output(v);
  return r;
}

std::optional<mesh::MeshStreamReport> LocalStreamMesher(const mesh::BatchField& field, const mesh::MeshingOptions& o,
                                                        const mesh::MeshStreamOptions& stream,
                                                        mesh::MeshingSummary* summary, mesh::JuliaFieldStats*) {
  return mesh::MeshFieldStreamed(field, o, stream, summary);
}

MeshStageResult MeshJuliaStreamed(const JuliaSetup& setup, const MeshStageOptions& o, const MeshFiles& f,
                                  const StreamMesher& mesher) {
  if (auto why = o.Validate(); !why.empty()) throw Error("mesh: " + why);
  if (Extension(f.out) != ".ply") throw Error(f.out + ": a streamed mesh is written as PLY (.ply)");
  if (!f.obj.empty()) throw Error(f.obj + ": no OBJ when streaming (it would need the whole mesh)");
  const bool field_grid = Wants(o, "field");
  if (!f.vdb.empty() && (Wants(o, "surface") || Wants(o, "density") || !field_grid))
    throw Error(f.vdb + ": when streaming, the .vdb holds only the grid \"field\" (--vdb-grids field): the "
                "surface and density grids are built from the whole mesh");
  MeshStageResult r = StartResult(setup, o);
  const RationalMap& map = setup.map;
  mesh::MeshingOptions& m = r.meshing;
  mesh::JuliaFieldStats stats;
  const mesh::BatchField field = mesh::MakeJuliaField(map, r.julia, o.iso, o.precision, &stats,
                                                       ParseJuliaKernel(o.kernel));
  mesh::MeshStreamOptions so;
  so.path = f.out;
  so.precision = o.ply_double ? mesh::PlyPrecision::kFloat64 : mesh::PlyPrecision::kFloat32;
  so.transform = OutputTransform(r, o);
  // The .vdb's field grid, filled as the pieces pass (as WriteMeshFiles' raw grid).
  std::unique_ptr<mesh::SparseVdbBuilder> vdb;
  if (!f.vdb.empty() && field_grid) {
    const bool user = o.frame == "user";
    const mesh::MeshLattice l = mesh::LatticeFor(m);
    vdb = std::make_unique<mesh::SparseVdbBuilder>(user ? r.frame.fractal_to_user(l.origin) : l.origin,
                                                   l.spacing / (user ? r.frame.user_to_fractal_scale() : 1.0),
                                                   std::numeric_limits<float>::max(), o.iso, "julia", "log-modulus",
                                                   user ? "user" : "fractal");
    so.band = [&vdb](const mesh::TilePiece& p) { vdb->Add(p.band_nodes, p.band_values); };
  }
  r.streamed = mesher(field, m, so, &r.summary, &stats);
  r.writer = r.streamed.has_value();
  r.escaped = stats.escaped;
  r.non_finite = stats.non_finite;
  r.applications = stats.applications;
  r.factors = JuliaMap<double>(map, r.julia).Factors().size();
  if (r.writer && vdb && !r.empty()) vdb->Write(f.vdb);
  return r;
}

void CheckMeshFiles(const MeshFiles& f) {
  CheckOutput(f.out, {".ply", ".obj"}, "the mesh");
  CheckOutput(f.obj, {".obj"}, "--obj");
  CheckOutput(f.vdb, {".vdb"}, "--vdb");
}

void WriteMeshFiles(const MeshStageResult& r, const MeshStageOptions& o, const MeshFiles& f) {
  if (r.empty() || r.streamed) return;  // streamed: written as the tiles finished
  if (Extension(f.out) == ".obj")
    mesh::WriteObj(f.out, r.mesh);
  else
    mesh::WritePly(f.out, r.mesh, o.ply_double ? mesh::PlyPrecision::kFloat64 : mesh::PlyPrecision::kFloat32);
  if (!f.obj.empty()) mesh::WriteObj(f.obj, r.mesh);
  if (f.vdb.empty()) return;
  const bool user = o.frame == "user";
  const mesh::MeshLattice& l = r.band.lattice;
  const double spacing = r.summary.spacing / (user ? r.frame.user_to_fractal_scale() : 1.0);
  mesh::VdbVolumeOptions vo;
  vo.voxel_size = spacing;
  vo.half_width = o.vdb_band;
  vo.surface = Wants(o, "surface");
  vo.density = Wants(o, "density");
  vo.coordinates = user ? "user" : "fractal";
  mesh::VdbRawField raw;
  if (Wants(o, "field")) {
    raw.origin = user ? r.frame.fractal_to_user(l.origin) : l.origin;
    raw.spacing = spacing;
    raw.voxels = &r.band.nodes;
    raw.values = &r.band.values;
    raw.background = std::numeric_limits<float>::max();
    raw.iso = o.iso;
    raw.name = "julia";
    raw.quantity = "log-modulus";
  }
  mesh::WriteVdbVolumes(f.vdb, r.mesh, vo, Wants(o, "field") ? &raw : nullptr);
}

json JuliaJson(const JuliaOptions& j, double iso, Precision precision) {
  return {{"iterations", j.iterations},
          {"escape_radius", j.escape_radius},
          {"iso", iso},
          {"slice", j.slice},
          {"root_translation", j.root_translation},
          {"root_scale", j.root_scale},
          {"rotation", j.placement.rotation},
          {"rotation_center", j.placement.center},
          {"precision", PrecisionName(precision)}};
}

json MeshSummary(const MeshStageResult& r, const MeshStageOptions& o, const std::string& map_path, const MeshFiles& f) {
  mesh::MeshTopology topo;
  if (r.streamed) {  // counted on the front as the triangles were written
    topo.boundary_edges = r.summary.open_edges;
    topo.non_manifold_edges = r.streamed->non_manifold_edges;
  } else {
    topo = mesh::AnalyzeTopology(r.mesh);
  }
  const mesh::MeshingSummary& s = r.summary;
  json summary = {{"map", map_path},
                  {"out", r.empty() ? json(nullptr) : json(f.out)},
                  {"frame", o.frame},
                  {"julia", JuliaJson(r.julia, o.iso, o.precision)},
                  {"iteration_frame",
                   {{"name", IterationFrameName(o.iteration_frame)},
                    {"detail", o.detail},
                    {"lambda", r.lambda},
                    {"translate_potential", o.translate_potential ? json(*o.translate_potential) : json(nullptr)},
                    {"fractal_radius", r.frame.fractal_radius},
                    {"origin", r.frame.origin}}},
                  {"kernel", o.precision == Precision::kDouble ? o.kernel : std::string("scalar")},
                  {"box", {{"min", r.meshing.min_corner}, {"max", r.meshing.max_corner}}},
                  // "frame" is the output's; the box is where the map was sampled, in its iteration frame.
                  {"box_frame", o.iteration_frame == IterationFrame::kReference ? "reference" : "fractal"},
                  {"resolution", r.meshing.resolution},
                  {"cells", s.cells},
                  {"spacing", s.spacing},
                  {"band_nodes", r.streamed ? std::size_t(r.streamed->band_samples) : r.band.nodes.size()}};
  summary.update(MesherSummaryJson(s, r.meshing));
  summary["boundary_edges"] = topo.boundary_edges;  // = open_edges (kept for older readers)
  summary["non_manifold_edges"] = topo.non_manifold_edges;
  summary["evaluations"]["escaped"] = r.escaped;
  summary["evaluations"]["applications"] = r.applications;
  if (r.streamed)
    summary["streamed"] = {{"index_type", r.streamed->index_type},
                           {"bytes", r.streamed->bytes},
                           {"peak_front_tiles", r.streamed->peak_front_tiles},
                           {"peak_front_triangles", r.streamed->peak_front_triangles}};
  return summary;
}

json MesherSummaryJson(const mesh::MeshingSummary& s, const mesh::MeshingOptions& o) {
  return {{"sparse", s.search_stride > 0},
          {"vertices", s.vertices},
          {"triangles", s.triangles},
          {"components", s.components},
          {"open_edges", s.open_edges},
          {"open_edges_inside", s.open_edges_inside},
          {"speck_removal", o.remove_specks},
          {"specks_removed", s.specks_removed},
          {"surface_following", o.follow_surface},
          {"blocks_followed", s.blocks_followed},
          {"evaluations",
           {{"nodes", s.nodes_evaluated},
            {"search", s.search_evaluations},
            {"following", s.follow_evaluations},
            {"bisection", s.bisection_evaluations},
            {"non_finite", s.non_finite_values}}},
          {"tiles", {{"meshed", s.tiles_meshed}, {"total", s.tiles_total}}},
          {"blocks", {{"active", s.blocks_active}, {"total", s.blocks_total}}},
          {"seconds", s.seconds}};
}

}  // namespace quijibo::pipeline
