// The frame file beside a grid: how the user's mesh was placed into the fractal frame, so that
// later stages map back to the user's coordinates and refuse a map and a grid made in two frames.
#pragma once

#include <string>

#include "quijibo/frame.h"

namespace quijibo::mesh {

// "<dir>/bunny.qgrid" -> "<dir>/bunny.frame.json" (the extension, if any, is replaced).
std::string FrameJsonPathFor(const std::string& qgrid_path);

// The frame file: {"format":"quijibo-frame","version":1,"fractal_radius":..,"padding":..,
// "scale":..,"translation":[..],"origin":[..] (when not the default),"source_mesh":..,"resolution":..}.
// Written atomically.
void WriteFrameJson(const std::string& path, const FractalFrame& frame,
                    const std::string& source_mesh, int resolution);
// Read strictly (unknown keys refused with suggestions). Throws quijibo::Error naming the file.
FractalFrame ReadFrameJson(const std::string& path);

// The one check of every command that takes a map and a target grid: throws quijibo::Error,
// naming both files and the fields that differ, when the grid's frame (its .frame.json; a grid
// without one, such as an analytic target's, is in the default frame) is not the map's.
void CheckSameFrame(const FractalFrame& map_frame, const std::string& map_path, const std::string& target_path);
// The same with the target's frame at hand (`target_frame_source` names where it comes from).
void CheckSameFrame(const FractalFrame& map_frame, const std::string& map_path, const FractalFrame& target_frame,
                    const std::string& target, const std::string& target_frame_source);

}  // namespace quijibo::mesh
