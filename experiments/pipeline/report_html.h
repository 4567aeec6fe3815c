// report.html: report.md as one self-contained page (its pictures embedded as data URIs, no network at
// view time) with a 3D viewer of the run's meshes (three.js with orbit and zoom, one button per mesh),
// the meshes decimated to a browser's budget (mesh/decimate.h) and embedded compactly (positions
// quantized to 16 bits over the mesh's box, indices 16 or 32 bits, base64). Written by `quijibo run`
// right after report.md (`outputs.report_html`) and by `quijibo report-html RESULTS`
// (docs/user-guide.md, "report.html").
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace quijibo::pipeline {

// A mesh the viewer shows: `name` is its button's key, `label` the button's text, `path` a mesh file
// (.ply, .obj, .stl, .off). The viewer opens on the one marked `initial` (else the first).
struct ViewerMesh {
  std::string name;
  std::string label;
  std::string path;
  bool initial = false;
};

struct ReportHtmlOptions {
  // The browser's budget: each mesh is decimated to at most per_mesh triangles and to its share of
  // total (total / number of meshes), so the page stays a few MB and a laptop's browser turns it
  // smoothly.
  std::int64_t max_triangles_per_mesh = 200000;
  std::int64_t max_triangles_total = 500000;
  // The viewer script (web/viewer.js bundled with three.js at build time); empty: the build's
  // (QUIJIBO_VIEWER_SCRIPT, or the environment variable of the same name, which wins).
  std::string viewer_script;
};

struct ReportHtmlSummary {
  std::string path;       // the page written
  std::int64_t bytes = 0;  // its size
  struct Mesh {
    std::string name;
    std::int64_t triangles_in = 0, triangles_out = 0;
  };
  std::vector<Mesh> meshes;  // in the viewer, in order
  bool viewer = false;       // false: no viewer script was found; the page has the report and says why
};

// The meshes of a results folder that exist, in the order the viewer offers them: the target mesh
// (experiment.resolved.json's target.mesh), the Julia set (mesh/julia.ply, initial), the intricate
// surface (intricate/julia.ply), the shape modulus's and the portals' meshes.
std::vector<ViewerMesh> RunMeshes(const std::string& results);

// Writes `<results>/report.html` (atomically) from `<results>/report.md`, the pictures it names
// (embedded) and `meshes` (missing files are an error: RunMeshes lists only files that exist).
// Throws quijibo::Error naming the file when report.md or a mesh cannot be read.
ReportHtmlSummary WriteReportHtml(const std::string& results, const std::vector<ViewerMesh>& meshes,
                                  const ReportHtmlOptions& options = {});

}  // namespace quijibo::pipeline
