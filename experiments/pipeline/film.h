// The parameter space as a film: the 2015 paper presents each optimized map as "an initial point in
// a parameter space that can subsequently be explored using simple operations such as translation"
// (§1, Fig. 1c). A film moves one setting of the iterated map over `frames` frames, meshes each
// frame's set and renders it alike (one camera, one framing), and writes numbered PNG frames and an
// MP4 (ffmpeg). Finished frames are kept on disk: a rerun of the same film (same settings, same
// map) redoes only the frames that are missing, so an interrupted film resumes where it stopped.
//
// The settings that can move (`vary`), between `from` and `to` linearly over the frames:
//   translate_potential  the root translation by its effect (TranslationForPotential) along
//                        `mesh.translate`'s direction (default z); `from` unset: no translation on
//                        the first frame, then from the potential at the origin or `to` - 4.5,
//                        whichever is higher (a root at the origin makes it -inf)
//   translation          the root translation's length along that direction (iteration frame units)
//   detail               fractal detail (WithDetail)
//   iterations           the map applications n (rounded)
//   root                 the position of root `root` (top roots first, then bottom), from its own
//                        to `to_position` (x, y, z in the map's frame)
//   exponent             the exponent (multiplicity) of root `root`, from its own (or `from`) to `to`
// The map and its iteration frame (IterationMap: frame and detail) are made once when the setting
// does not change them (translate_potential, translation, iterations).
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "experiments/pipeline/mesh.h"
#include "experiments/pipeline/settings.h"
#include "mesh/render.h"

namespace quijibo::pipeline {

inline const std::vector<std::string> kFilmSettings = {"translate_potential", "translation", "detail",
                                                       "iterations",          "root",        "exponent"};

struct FilmOptions {
  std::string name;         // default: the film file's name
  std::string description;
  std::optional<std::string> map;         // map.json; or
  std::optional<std::string> experiment;  // an experiment whose results hold the map (its mesh stage's optimizer)
  std::optional<std::string> results;     // that experiment's results folder (default: as `quijibo run` puts it)
  std::string vary = "translate_potential";
  std::optional<double> from;
  std::optional<double> to;
  std::optional<std::vector<double>> to_position;  // root: x, y, z
  int root = 0;
  int frames = 60;
  int fps = 12;
  double azimuth = 35, elevation = 25;  // the camera (degrees)
  bool video = true;                    // film.mp4 (ffmpeg)
  mesh::RenderOptions render = DefaultRender();
  MeshStageOptions mesh = DefaultMesh();

  static mesh::RenderOptions DefaultRender();
  static MeshStageOptions DefaultMesh();
  std::string Validate() const;
  static const Schema<FilmOptions>& Settings();
  // Reads a film file (its paths relative to it); throws "<file>: <JSON pointer>: <what>".
  static FilmOptions FromFile(const std::string& path);
  static FilmOptions FromJson(const JsonReader& r, const std::filesystem::path& base, const FilmOptions& start);
  nlohmann::json ToJson() const;
  // The map.json the film moves through (from `map`, or the experiment's results).
  std::string MapPath() const;
};

struct FilmFrame {
  int index = 0;
  double value = 0;                 // the setting at this frame
  std::vector<double> translation;  // the root translation used
  long long triangles = 0;
  double seconds = 0, mesh_seconds = 0, render_seconds = 0;
  std::string note;  // why the frame is empty, when it could not be made
  nlohmann::json ToJson() const;
};

struct FilmSummary {
  std::string out;
  int frames = 0, reused = 0, made = 0;
  double seconds = 0;
  double median_frame_seconds = 0;  // of the frames made by this run
  std::string video;                // film.mp4, or "" when not written
  std::string video_note;           // why no video, when none
  std::vector<FilmFrame> frame_list;
  nlohmann::json ToJson() const;
  std::string Report() const;
};

// Makes the film into `out` (created): film.json (the resolved film, its fingerprint and the
// framing), frames/frame-NNNN.png with frame-NNNN.json beside each, frames.json (every frame's
// figures) and film.mp4. Progress (frame, percent, ETA) on stderr unless `quiet`. Throws
// quijibo::Error for bad settings or a map that cannot be read; a frame whose set is empty is
// rendered empty and counted.
FilmSummary MakeFilm(const FilmOptions& options, const std::string& out, bool quiet);

}  // namespace quijibo::pipeline
