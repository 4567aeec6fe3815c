#include "mesh/frame_file.h"

#include <filesystem>
#include <nlohmann/json.hpp>

#include "util/error.h"
#include "util/io.h"
#include "util/json_reader.h"

namespace quijibo::mesh {

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

}  // namespace quijibo::mesh
