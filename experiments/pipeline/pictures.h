// The pictures stage: the set against the target on a slice (the initial and the optimized map),
// and the mesh rendered (mesh/pictures.h).
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "experiments/pipeline/settings.h"
#include "mesh/pictures.h"
#include "quijibo/grid.h"
#include "quijibo/julia.h"
#include "quijibo/rational_map.h"

namespace quijibo::pipeline {

struct PicturesOptions {
  bool enabled = true;         // quijibo run
  int slice_iterations = 1;    // n of the slices against the target: the one-step set the energy fits
  mesh::SliceView slice;       // size (the run: axis z at 0 over the target's box)
  mesh::RenderOptions render;  // size, views and shading of the renders
  bool triptych = true;        // quijibo run: the triptych (experiments/pipeline/triptych.h)
  int triptych_size = 480;     // pixels per panel of the triptych

  std::string Validate() const;
  static const Schema<PicturesOptions>& Settings();
  static PicturesOptions FromJson(const JsonReader& r, const std::string& pointer, const std::filesystem::path& base,
                                  const PicturesOptions& start);
  static PicturesOptions FromJson(const JsonReader& r, const std::string& pointer, const std::filesystem::path& base) {
    return FromJson(r, pointer, base, PicturesOptions());
  }
  nlohmann::json ToJson() const;
};

struct SlicePicture {
  Image image{1, 1};
  mesh::SliceAgreement agreement;
};

// The set {log|q_n| < iso} of `map` against {target < 0} on `view` (mesh/pictures.h). `target`
// must be in the fractal frame, and its frame file (`target_path`'s .frame.json, when present)
// the map's. Throws quijibo::Error otherwise.
SlicePicture SliceAgainstTargetPicture(const RationalMap& map, const ScalarGrid& target, const std::string& target_path,
                                       const mesh::SliceView& view, const JuliaOptions& julia, double iso,
                                       Precision precision);
// The report of a slice (the standard output of `quijibo picture slice`).
nlohmann::json SliceReport(const SlicePicture& picture, const std::string& out, const JuliaOptions& julia, double iso,
                           Precision precision);

// The view the run's slices use: the plane z = 0 across the target grid's box.
mesh::SliceView TargetSliceView(const ScalarGrid& target, const PicturesOptions& options);

// The run's pictures into `dir`: slice-n<N>.png of `optimized`, initial-slice-n<N>.png of
// `initial` (N = slice_iterations; their reports as slice.out and initial-slice.out), and
// render.png of the mesh at `mesh_path` when it is not empty.
void Pictures(const PicturesOptions& options, const RationalMap& initial, const RationalMap& optimized,
              const std::string& target_path, const std::string& mesh_path, const std::string& dir);

}  // namespace quijibo::pipeline
