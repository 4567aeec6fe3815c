#include "mesh/sdf_command.h"

#include <cstdio>
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>

#include "mesh/normalize.h"
#include "util/error.h"
#include "util/io.h"
#include "util/json_reader.h"

namespace quijibo::mesh {

std::string SdfCommandOptions::Validate() const {
  if (input.empty()) return "an input mesh is required";
  if (output.empty()) return "an output .qgrid path is required";
  if (!HasExtension(output, ".qgrid")) return output + ": the output must end in .qgrid (the grid format written)";
  if (!vdb_output.empty() && !HasExtension(vdb_output, ".vdb")) return vdb_output + ": --vdb must end in .vdb";
  if (auto why = CheckRange("resolution", SettingType::kInteger, resolution, kTargetResolutionRange); !why.empty())
    return why;
  if (!(padding >= 0.0 && padding < 0.5)) return "padding must be in [0, 0.5)";
  if (!(fractal_radius > 0.0) || !std::isfinite(fractal_radius))
    return "fractal radius must be a positive finite number";
  if (output == vdb_output || output == FrameJsonPathFor(output) ||
      vdb_output == FrameJsonPathFor(output))
    return "the output files must have different paths";
  return sdf.Validate();
}

std::string FrameJsonPathFor(const std::string& qgrid_path) {
  std::filesystem::path p(qgrid_path);
  p.replace_extension(".frame.json");
  return p.string();
}

void WriteFrameJson(const std::string& path, const FractalFrame& frame,
                    const std::string& source_mesh, int resolution) {
  nlohmann::json j = {{"format", "quijibo-frame"},
                      {"version", 1},
                      {"fractal_radius", frame.fractal_radius},
                      {"padding", frame.padding},
                      {"scale", frame.scale},
                      {"translation", frame.translation},
                      {"source_mesh", source_mesh},
                      {"resolution", resolution}};
  if (!frame.default_origin()) j["origin"] = frame.origin;
  WriteFileAtomically(path, j.dump(2) + "\n");
}

FractalFrame ReadFrameJson(const std::string& path) {
  const nlohmann::json j = ParseJson(ReadFile(path), path);
  const JsonReader r(j, path);
  if (!j.is_object() || j.value("format", "") != "quijibo-frame")
    throw Error(path + ": \"format\" should be \"quijibo-frame\"");
  r.allow_keys("", {"format", "version", "fractal_radius", "padding", "scale", "translation", "origin", "source_mesh",
                    "resolution"});
  auto vec3 = [&](const std::string& p) {
    if (r.array_size(p) != 3) r.fail(p, "expected 3 numbers");
    return Vec3{r.number(p + "/0"), r.number(p + "/1"), r.number(p + "/2")};
  };
  FractalFrame frame;
  frame.fractal_radius = r.number("/fractal_radius");
  frame.padding = r.number("/padding");
  frame.scale = r.number("/scale");
  frame.translation = vec3("/translation");
  if (r.has("/origin")) frame.origin = vec3("/origin");
  if (const std::string why = frame.Validate(); !why.empty()) throw Error(path + ": " + why);
  return frame;
}

void CheckSameFrame(const FractalFrame& map_frame, const std::string& map_path, const std::string& target_path) {
  const std::string frame_path = FrameJsonPathFor(target_path);
  std::error_code ec;
  const bool has_frame = std::filesystem::is_regular_file(frame_path, ec);
  CheckSameFrame(map_frame, map_path, has_frame ? ReadFrameJson(frame_path) : FractalFrame{}, target_path,
                 has_frame ? frame_path : "no frame file: the default");
}

void CheckSameFrame(const FractalFrame& map_frame, const std::string& map_path, const FractalFrame& target_frame,
                    const std::string& target, const std::string& target_frame_source) {
  if (const std::string d = FrameDifference(target_frame, map_frame); !d.empty())
    throw Error(target + ": the target's frame (" + target_frame_source + ") is not the map's (" + map_path + "): " + d +
                " (target vs map); make both from the same mesh with the same origin and frame scale");
}

void RunSdfCommand(const SdfCommandOptions& options) {
  if (const std::string why = options.Validate(); !why.empty()) throw Error("sdf: " + why);
  MeshReadReport report;
  const TriangleMesh user_mesh = ReadMesh(options.input, &report);
  FractalFrame frame = NormalizationFor(user_mesh, options.padding, options.fractal_radius);
  if (options.origin == OriginPlacement::kInside) {
    frame = PlaceOriginInside(user_mesh, frame, options.input);
    if (options.frame_scale == FrameScale::kTrap)
      frame = ScaleToTrap(user_mesh, frame, options.input);
  }
  const TriangleMesh mesh = ToFractalFrame(user_mesh, frame);
  const GridFrame grid = TargetGridFrame(options.resolution, frame, options.box);
  SdfOptions sdf_options = options.sdf;
  sdf_options.name = options.input;
  SdfSummary summary;
  const ScalarGrid field = SignedDistance(mesh, grid, sdf_options, &summary);

  // Write the auxiliary files first and the .qgrid last; undo on failure so a failed run
  // leaves no partial set of outputs.
  std::vector<std::string> written;
  CreateParentFolder(options.output);
  if (!options.vdb_output.empty()) CreateParentFolder(options.vdb_output);
  try {
    const std::string frame_path = FrameJsonPathFor(options.output);
    WriteFrameJson(frame_path, frame, options.input, options.resolution);
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
                options.resolution, grid.spacing, summary.min_value, summary.max_value,
                (long long)summary.inside_cells, (long long)summary.ambiguous_cells,
                summary.seconds);
    std::printf("wrote %s", options.output.c_str());
    for (const std::string& p : written) std::printf(", %s", p.c_str());
    std::printf("\n");
  }
}

}  // namespace quijibo::mesh
