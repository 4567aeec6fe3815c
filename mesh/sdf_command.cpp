#include "mesh/sdf_command.h"

#include <cstdio>
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>

#include "util/error.h"
#include "util/io.h"
#include "util/json_reader.h"

namespace quijibo::mesh {

std::string SdfCommandOptions::Validate() const {
  if (input.empty()) return "an input mesh is required";
  if (output.empty()) return "an output .qgrid path is required";
  if (!HasExtension(output, ".qgrid")) return output + ": the output must end in .qgrid (the grid format written)";
  if (!vdb_output.empty() && !HasExtension(vdb_output, ".vdb")) return vdb_output + ": --vdb must end in .vdb";
  if (output == vdb_output || output == FrameJsonPathFor(output) || vdb_output == FrameJsonPathFor(output))
    return "the output files must have different paths";
  return target.Validate();
}

void RunSdfCommand(const SdfCommandOptions& options) {
  if (const std::string why = options.Validate(); !why.empty()) throw Error("sdf: " + why);
  MeshReadReport report;
  const TriangleMesh user_mesh = ReadMesh(options.input, &report);
  const MeshTargetResult t = MeshTarget(user_mesh, options.input, options.target);
  const FractalFrame& frame = t.frame;
  const ScalarGrid& field = t.grid;
  const SdfSummary& summary = t.summary;

  // Write the auxiliary files first and the .qgrid last; undo on failure so a failed run
  // leaves no partial set of outputs.
  std::vector<std::string> written;
  CreateParentFolder(options.output);
  if (!options.vdb_output.empty()) CreateParentFolder(options.vdb_output);
  try {
    const std::string frame_path = FrameJsonPathFor(options.output);
    WriteFrameJson(frame_path, frame, options.input, options.target.resolution);
    written.push_back(frame_path);
    if (!options.vdb_output.empty()) {
      WriteVdb(options.vdb_output, field, "sdf");
      written.push_back(options.vdb_output);
    }
    WriteGrid(options.output, field);
  } catch (...) {
    for (const std::string& p : written) std::remove(p.c_str());
    throw;
  }

  if (!options.quiet) {
    const MeshTopology& t = summary.topology;
    std::printf("%s: %zu vertices, %zu triangles (%lld degenerate dropped, %lld corners welded)\n",
                options.input.c_str(), user_mesh.vertices.size(), user_mesh.triangles.size(),
                (long long)report.degenerate_dropped, (long long)report.corners_welded);
    std::printf("topology: %lld boundary edges, %lld non-manifold, %lld misoriented%s\n",
                (long long)t.boundary_edges, (long long)t.non_manifold_edges,
                (long long)t.misoriented_edges,
                summary.flipped_orientation ? "; faces pointed inwards and were flipped" : "");
    std::printf("frame: scale %.9g, translation (%.9g, %.9g, %.9g), fractal radius %g\n",
                frame.scale, frame.translation[0], frame.translation[1], frame.translation[2],
                frame.fractal_radius);
    std::printf("sdf: %d^3 cells, spacing %.6g, range [%.6g, %.6g], %lld inside, "
                "%lld ambiguous, %.2f s\n",
                options.target.resolution, field.frame.spacing, summary.min_value, summary.max_value,
                (long long)summary.inside_cells, (long long)summary.ambiguous_cells,
                summary.seconds);
    std::printf("wrote %s", options.output.c_str());
    for (const std::string& p : written) std::printf(", %s", p.c_str());
    std::printf("\n");
  }
}

}  // namespace quijibo::mesh
