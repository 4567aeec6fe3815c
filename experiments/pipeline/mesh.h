// The mesh stage: the Julia set {log|q_n| < iso} of a map, meshed by marching cubes with bisection
// (mesh/marching_cubes.h, docs/meshing.md), as PLY/OBJ and OpenVDB volumes.
#pragma once

#include <functional>
#include <optional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "experiments/pipeline/settings.h"
#include "mesh/julia_field.h"
#include "mesh/marching_cubes.h"
#include "mesh/mesh_stream.h"
#include "mesh/triangle_mesh.h"
#include "quijibo/julia.h"
#include "quijibo/julia_setup.h"
#include "quijibo/rational_map.h"

namespace quijibo::pipeline {


struct MeshStageOptions {
  mesh::MeshingOptions meshing;  // resolution and the mesher's settings (box: see `box`)
  JuliaOptions julia;            // n, escape radius, slice, root translation and scale, placement
  double iso = 0.0;              // the surface log|q_n| = iso
  std::string frame = "user";    // coordinates of the output: "user" (the input mesh's) or "fractal"
  Precision precision = Precision::kDouble;
  std::string kernel = JuliaKernelName(kDefaultJuliaKernel);  // double precision (julia_batch.h)
  // The box in the fractal frame, xmin,ymin,zmin,xmax,ymax,zmax; empty: the whole normalized cube
  // (the map's box centre +- fractal_radius / 2).
  std::vector<double> box;
  // Rotate the sampling box about its centre: ax, ay, az, degrees; empty: none.
  std::vector<double> rotation;
  // Root translation x, y, z[, k] in the iteration frame (julia.root_translation; the reference's
  // "root translation"); none: julia.root_translation as it is.
  std::optional<std::vector<double>> translate;
  // The root translation by its effect (TranslationForPotential, rational_map.h): along
  // `translate`'s direction (default z), the length at which the iterated map's L is this at -t.
  std::optional<double> translate_potential;
  // How the map is iterated (the one conversion of these settings; MakeJuliaSetup makes the
  // iterated map from it): `julia`, iteration_frame, detail, translate(_potential), box, rotation.
  JuliaSetupOptions Setup() const;
  // `input_map` as iterated with these settings (MakeJuliaSetup of Setup(); the translation by
  // potential is a search): the one place outside quijibo/ where a face makes it. A run, a command,
  // MPI and Python make it once and hand it to the mesh, the fidelity, the triptych and the bench.
  // Throws quijibo::Error on invalid options.
  JuliaSetup Iterated(const RationalMap& input_map) const;
  // `julia` with its root translation on `iterated`, a map as it is iterated (its frame and detail
  // applied): from `translate_potential`, else `translate` when set.
  JuliaOptions TranslatedJuliaOfIterated(const RationalMap& iterated) const;
  // The frame the map is iterated in: "map" (the frame it was optimized in) or "reference" (the
  // reference code's world frame, ReferenceFrame in rational_map.h, where the paper's translations
  // 1.41 / 0.54 / 1.07 are given). The one-step set is the same in both; the box and `translate`
  // are in this frame.
  IterationFrame iteration_frame = IterationFrame::kMap;
  // Fractal detail (WithDetail, rational_map.h): the width of the band |L| < 1 about the one-step
  // surface, percent of the shape's size; the one-step set stays. 0: the map as optimized.
  double detail = kSmoothDetail;
  std::vector<std::string> vdb_grids{"surface", "density"};  // of the .vdb: surface, density, field
  double vdb_band = 3.0;                                     // half-width of the level set's narrow band, voxels
  bool ply_double = false;                                   // PLY coordinates as double
  // Write the PLY (and the .vdb's field grid) as the tiles finish, with memory bounded by the front of
  // tiles, not the mesh (MeshJuliaStreamed; docs/meshing.md "Streaming to disk").
  bool stream = false;
  // `quijibo run` only.
  bool enabled = true;
  bool vdb = true, obj = false;  // also julia.vdb, julia.obj
  std::string optimizer;         // which optimizer's map (Experiment: the first)

  std::string Validate() const;
  static const Schema<MeshStageOptions>& Settings();
  static MeshStageOptions FromJson(const JsonReader& r, const std::string& pointer, const std::filesystem::path& base,
                                   const MeshStageOptions& start);
  static MeshStageOptions FromJson(const JsonReader& r, const std::string& pointer, const std::filesystem::path& base) {
    return FromJson(r, pointer, base, MeshStageOptions());
  }
  nlohmann::json ToJson() const;
};

// A mesher meshes exactly like MeshField (mesh, summary, band when not null) and returns false on
// processes that must not write (MPI workers); it may add other processes' counts into `stats`
// (quijibo-mpi, docs/mpi.md).
using Mesher = std::function<bool(const mesh::BatchField& field, const mesh::MeshingOptions& options,
                                  mesh::MeshingSummary* summary, mesh::FieldBand* band, mesh::TriangleMesh* mesh,
                                  mesh::JuliaFieldStats* stats)>;
// MeshField on this process.
bool LocalMesher(const mesh::BatchField& field, const mesh::MeshingOptions& options, mesh::MeshingSummary* summary,
                 mesh::FieldBand* band, mesh::TriangleMesh* mesh, mesh::JuliaFieldStats* stats);

// Where the files go: `out` (.ply or .obj), and when not empty an extra OBJ and a .vdb.
struct MeshFiles {
  std::string out, obj, vdb;
};

// A streaming mesher meshes like MeshFieldStreamed (mesh/mesh_stream.h: the PLY written as tiles
// finish, the summary filled); it returns the report on the process that wrote, nothing elsewhere
// (MPI workers), and may add other processes' counts into `stats`.
using StreamMesher = std::function<std::optional<mesh::MeshStreamReport>(
    const mesh::BatchField& field, const mesh::MeshingOptions& options, const mesh::MeshStreamOptions& stream,
    mesh::MeshingSummary* summary, mesh::JuliaFieldStats* stats)>;
// MeshFieldStreamed on this process.
std::optional<mesh::MeshStreamReport> LocalStreamMesher(const mesh::BatchField& field,
                                                        const mesh::MeshingOptions& options,
                                                        const mesh::MeshStreamOptions& stream,
                                                        mesh::MeshingSummary* summary, mesh::JuliaFieldStats* stats);

struct MeshStageResult {
  bool writer = true;       // false on processes that do not write (the mesher's answer)
  mesh::TriangleMesh mesh;  // in the output frame (user or fractal, rotation applied)
  mesh::MeshingSummary summary;
  mesh::MeshingOptions meshing;  // as used (the box filled in)
  FractalFrame frame;            // the iteration frame (IterationMap): of the box and the fractal output
  double lambda = 1.0;           // the factor of ln C, tau and beta for `detail` (WithDetail)
  JuliaOptions julia;            // as used (the placement's centre filled in)
  mesh::FieldBand band;          // with vdb grid "field"
  std::int64_t escaped = 0, non_finite = 0;
  std::int64_t applications = 0;  // map applications done, all field evaluations together
  std::size_t factors = 0;        // roots with a non-zero exponent (one factor each per application)
  // Streamed (MeshJuliaStreamed): the files are written and `mesh` and `band` stay empty.
  std::optional<mesh::MeshStreamReport> streamed;
  bool empty() const { return streamed ? summary.triangles == 0 : mesh.triangles.empty(); }
};

// Meshes the Julia set of the iterated map `setup` (options.Iterated(map)). Throws quijibo::Error on
// invalid options.
MeshStageResult MeshJulia(const JuliaSetup& setup, const MeshStageOptions& options, const Mesher& mesher = LocalMesher);

// Meshes the Julia set of `setup` streamed to files.out (a .ply; no OBJ) and files.vdb (only the grid
// "field": the others are built from the whole mesh), written as the tiles finish; the PLY is the one
// MeshJulia + WriteMeshFiles write, byte for byte. Throws quijibo::Error; nothing is left on failure.
MeshStageResult MeshJuliaStreamed(const JuliaSetup& setup, const MeshStageOptions& options, const MeshFiles& files,
                                  const StreamMesher& mesher = LocalStreamMesher);
// Fails early (before meshing) when a path has the wrong extension or its folder does not exist.
void CheckMeshFiles(const MeshFiles& files);
// Writes the mesh files (nothing for an empty set).
void WriteMeshFiles(const MeshStageResult& result, const MeshStageOptions& options, const MeshFiles& files);
// The summary (summary.json of the run's mesh stage, the standard output of `quijibo mesh`).
nlohmann::json MeshSummary(const MeshStageResult& result, const MeshStageOptions& options, const std::string& map_path,
                           const MeshFiles& files);
// The mesher's part of a summary: sizes, components, open edges (all, and away from the box
// faces), specks, surface following, evaluations, tiles, blocks, seconds.
nlohmann::json MesherSummaryJson(const mesh::MeshingSummary& summary, const mesh::MeshingOptions& options);
// The Julia options as the summaries record them.
nlohmann::json JuliaJson(const JuliaOptions& julia, double iso, Precision precision);

}  // namespace quijibo::pipeline
