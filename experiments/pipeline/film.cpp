#include "experiments/pipeline/film.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "experiments/pipeline/experiment.h"
#include "experiments/pipeline/quality.h"
#include "experiments/pipeline/stage_cache.h"
#include "experiments/pipeline/triptych.h"
#include "quijibo/julia_setup.h"
#include "util/child_process.h"
#include "util/error.h"
#include "util/hash.h"
#include "util/io.h"
#include "util/progress.h"

namespace quijibo::pipeline {

using nlohmann::json;
namespace fs = std::filesystem;

mesh::RenderOptions FilmOptions::DefaultRender() {
  mesh::RenderOptions r;
  r.size = 480;
  r.views = 1;
  return r;
}

// The intricate surface's settings (the triptych's (c)) without the translation, which the film sets.
MeshStageOptions FilmOptions::DefaultMesh() {
  MeshStageOptions m = IntricateDefaults(MeshStageOptions());
  m.translate_potential.reset();
  m.vdb = false;
  return m;
}

const Schema<FilmOptions>& FilmOptions::Settings() {
  using O = FilmOptions;
  static const Schema<O> s =
      Schema<O>()
          .String("name", "", "Names the film (default: the film file's name)",
                  [](auto& o) -> std::string& { return o.name; })
          .String("description", "", "What the film shows", [](auto& o) -> std::string& { return o.description; })
          .Path("map", "--map", "The map the film moves through (map.json)",
                [](auto& o) -> std::optional<std::string>& { return o.map; })
          .Path("experiment", "--experiment",
                "Or an experiment whose results hold the map (its mesh stage's optimizer's map.json)",
                [](auto& o) -> std::optional<std::string>& { return o.experiment; })
          .Path(
              "results", "--results", "That experiment's results folder (default: where `quijibo run` puts it)",
              [](auto& o) -> std::optional<std::string>& { return o.results; }, false)
          .Choice("vary", "--vary", "The setting that moves", [](auto& o) -> std::string& { return o.vary; },
                  kFilmSettings)
          .Doc("the setting that moves: `translate_potential`, `translation` (length along `mesh.translate`'s "
               "direction), `detail`, `iterations`, `root` (a root's position), `exponent` (a root's multiplicity)")
          .Number(
              "from", "--from",
              "The setting's value on the first frame (default: the map's own; translate_potential: no translation)",
              [](auto& o) -> std::optional<double>& { return o.from; }, -1e6, 1e6)
          .Number(
              "to", "--to", "The setting's value on the last frame", [](auto& o) -> std::optional<double>& { return o.to; },
              -1e6, 1e6)
          .Numbers(
              "to_position", "--to-position", "vary root: the root's position on the last frame, x,y,z (map's frame)",
              [](auto& o) -> std::optional<std::vector<double>>& { return o.to_position; }, {3}, -1e6, 1e6)
          .Integer(
              "root", "--root", "vary root or exponent: which root (top roots first, then bottom)",
              [](auto& o) -> int& { return o.root; }, 0, 1 << 24)
          .Integer(
              "frames", "--frames", "Frames of the film", [](auto& o) -> int& { return o.frames; }, 2, 100000)
          .Integer(
              "fps", "--fps", "Frames per second of film.mp4", [](auto& o) -> int& { return o.fps; }, 1, 240)
          .Number(
              "azimuth", "--azimuth", "The camera's azimuth, degrees (0: looking along -z)",
              [](auto& o) -> double& { return o.azimuth; }, -360, 360)
          .Number(
              "elevation", "--elevation", "The camera's elevation, degrees", [](auto& o) -> double& { return o.elevation; },
              -90, 90)
          .Boolean("video", "--no-video", "Also write film.mp4 (ffmpeg); --no-video: the frames only",
                   [](auto& o) -> bool& { return o.video; })
          .Integer(
              "render/size", "--size", "Pixels of a frame (square)", [](auto& o) -> int& { return o.render.size; }, 16,
              8192)
          .Choice(
              "render/shading", "--shading", "depth (occlusion, soft shadows, ground) or flat",
              [](auto& o) -> std::string& { return o.render.shading; }, {"depth", "flat"})
          .Integer(
              "render/samples", "--samples", "Camera rays per pixel", [](auto& o) -> int& { return o.render.samples; },
              1, 256)
          .Integer(
              "render/ao_rays", "--ao-rays", "Ambient-occlusion rays per camera ray",
              [](auto& o) -> int& { return o.render.ao_rays; }, 0, 256);
  return s;
}

std::string FilmOptions::Validate() const {
  if (bool(map) == bool(experiment)) return "give the map (\"map\", --map) or an experiment (\"experiment\"), one of them";
  if (std::string why = Settings().Check(*this); !why.empty()) return why;
  if ((vary == "translate_potential" || vary == "translation" || vary == "detail" || vary == "iterations" ||
       vary == "exponent") &&
      !to)
    return "vary " + vary + ": \"to\" (--to) is required";
  if (vary == "root" && !to_position) return "vary root: \"to_position\" (--to-position x,y,z) is required";
  if (vary == "translate_potential") {
    if (!(*to < 0)) return "vary translate_potential: \"to\" must be < 0 (the potential at -t)";
    if (from && !(*from < 0)) return "vary translate_potential: \"from\" must be < 0";
  }
  if (vary == "detail" && (*to < 0 || (from && *from < 0))) return "vary detail: values must be >= 0";
  if (vary == "iterations" && (*to < 1 || (from && *from < 1))) return "vary iterations: values must be >= 1";
  if (vary == "exponent" && (*to < 0 || (from && *from < 0))) return "vary exponent: values must be >= 0";
  if (vary == "translate_potential" || vary == "translation") {
    if (mesh.translate_potential) return "mesh.translate_potential: the film sets the translation (leave it out)";
  }
  if (std::string why = render.Validate(); !why.empty()) return why;
  return mesh.Validate();
}

FilmOptions FilmOptions::FromJson(const JsonReader& r, const fs::path& base, const FilmOptions& start) {
  FilmOptions o = start;
  if (!r.at("").is_object()) r.fail("", "expected a JSON object (a film), found " + JsonReader::describe(r.at("")));
  Settings().Read(r, "", base, o, {"mesh"});
  o.mesh = MeshStageOptions::FromJson(r, "/mesh", base, o.mesh);
  if (std::string why = o.Validate(); !why.empty()) r.fail("", why);
  return o;
}

FilmOptions FilmOptions::FromFile(const std::string& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw Error(path + ": no such file");
  const json doc = ParseJson(ReadFile(path), path);
  FilmOptions start;
  start.name = fs::path(path).stem().string();
  return FromJson(JsonReader(doc, path), fs::absolute(path).parent_path(), start);
}

json FilmOptions::ToJson() const {
  json j;
  Settings().Write(*this, j);
  j["mesh"] = mesh.ToJson();
  return j;
}

std::string FilmOptions::MapPath() const {
  if (map) return *map;
  const Experiment e = Experiment::FromFile(*experiment);
  if (e.method != "quijibo") throw Error(*experiment + ": a film needs a QUIJIBO experiment (method quijibo)");
  const std::string folder = results ? *results : e.outputs.folder ? *e.outputs.folder : "results/" + e.name;
  const std::string path = folder + "/" + e.mesh.optimizer + "/map.json";
  if (!fs::exists(path))
    throw Error(path + ": no map yet: run the experiment first (quijibo run " + *experiment +
                (results ? " --out " + *results : std::string()) + "), or give \"results\"");
  return path;
}

json FilmFrame::ToJson() const {
  return {{"frame", index},      {"value", value},          {"translation", translation},
          {"triangles", triangles}, {"seconds", seconds}, {"mesh_seconds", mesh_seconds},
          {"render_seconds", render_seconds}, {"note", note}};
}

json FilmSummary::ToJson() const {
  json frames_json = json::array();
  for (const FilmFrame& f : frame_list) frames_json.push_back(f.ToJson());
  return {{"out", out},     {"frames", frames},  {"reused", reused},
          {"made", made},   {"seconds", seconds}, {"median_frame_seconds", median_frame_seconds},
          {"video", video}, {"video_note", video_note}, {"frame_list", frames_json}};
}

std::string FilmSummary::Report() const {
  std::ostringstream s;
  s << "film: " << frames << " frames in " << out << "/frames (" << made << " made, " << reused << " reused) in "
    << FormatDuration(seconds);
  if (made > 0) s << ", median " << Fixed(median_frame_seconds, 1) << " s per frame";
  s << "\n";
  if (!video.empty()) s << "film: " << video << "\n";
  if (!video_note.empty()) s << "film: no video: " << video_note << "\n";
  return s.str();
}

namespace {

// The root `index` of the map (top roots first): its position and exponent.
struct RootRef {
  Vec4* position;
  double* exponent;
};
RootRef Root(RationalMap& m, int index) {
  if (index < m.top_count()) return {&m.top_roots[std::size_t(index)], &m.top_exponents[std::size_t(index)]};
  const int b = index - m.top_count();
  return {&m.bottom_roots[std::size_t(b)], &m.bottom_exponents[std::size_t(b)]};
}

std::string FrameName(int k) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "frame-%04d", k + 1);
  return buf;
}

}  // namespace

FilmSummary MakeFilm(const FilmOptions& o, const std::string& out, bool quiet) {
  if (std::string why = o.Validate(); !why.empty()) throw Error("film: " + why);
  const auto t0 = std::chrono::steady_clock::now();
  const std::string map_path = o.MapPath();
  const RationalMap input = ReadMap(map_path);
  if (o.vary == "root" || o.vary == "exponent")
    if (o.root >= input.root_count())
      throw Error("film: root " + std::to_string(o.root) + ": the map has " + std::to_string(input.root_count()) +
                  " roots (0 to " + std::to_string(input.root_count() - 1) + ")");
  // The fingerprint: the film's settings and the map's bytes. Frames of another fingerprint are stale.
  Fnv1a h;
  json spec = o.ToJson();
  spec.erase("name"), spec.erase("description"), spec.erase("video"), spec.erase("fps");
  h.add(spec.dump());
  h.add(ReadFile(map_path));
  const std::string fingerprint = h.hex();

  std::error_code ec;
  fs::create_directories(out + "/frames", ec);
  if (ec) throw Error(out + ": cannot create the film's folder: " + ec.message());
  const std::string film_json = out + "/film.json";
  const json previous = ReadStageFile(film_json);
  if (previous.is_object() && previous.value("fingerprint", "") != fingerprint) {
    if (!quiet) std::fprintf(stderr, "quijibo: film: the settings or the map changed: the earlier frames are removed\n");
    fs::remove_all(out + "/frames", ec);
    fs::remove(out + "/film.mp4", ec);
    fs::create_directories(out + "/frames", ec);
  }

  // What the frames share: the iterated map and the framing.
  const bool fixed_map = o.vary == "translate_potential" || o.vary == "translation" || o.vary == "iterations";
  MeshStageOptions frame_only = o.mesh;
  frame_only.translate.reset(), frame_only.translate_potential.reset();
  const RationalMap iterated = frame_only.Iterated(input).map;
  Vec3 direction{0.0, 0.0, 1.0};
  if (o.mesh.translate) direction = {(*o.mesh.translate)[0], (*o.mesh.translate)[1], (*o.mesh.translate)[2]};
  const double dn = std::hypot(direction[0], direction[1], direction[2]);
  if (!(dn > 0)) throw Error("film: mesh.translate: the direction must not be zero");
  // The shape box in the user's frame, for a framing every frame shares.
  const double side = (1.0 - 2.0 * input.frame.padding) / input.frame.scale;
  const Vec3 centre = input.frame.fractal_to_user(input.frame.box_center());
  const std::array<double, 4> framing{centre[0], centre[1], centre[2], 0.8 * side};

  double from = o.from.value_or(0.0);
  bool untranslated_first = false;
  if (!o.from) {
    if (o.vary == "translate_potential") {
      // The first frame untranslated; the others from the potential at the origin, or 4.5 below
      // `to` when the origin is deeper (a root there: -inf), where a translation barely shows.
      const double origin = OneStepLogModulus(iterated, {0.0, 0.0, 0.0});
      untranslated_first = true;
      if (!(origin < *o.to))
        throw Error("film: the potential at the origin (" + Fixed(origin, 3) + ") is not below \"to\" (" +
                    Fixed(*o.to, 3) + "): no translation reaches it");
      from = std::max(origin, *o.to - 4.5);
    } else if (o.vary == "detail") {
      from = o.mesh.detail;
    } else if (o.vary == "iterations") {
      from = o.mesh.julia.iterations;
    } else if (o.vary == "exponent") {
      RationalMap m = input;
      from = *Root(m, o.root).exponent;
    }
  }
  std::vector<double> values(std::size_t(o.frames));
  for (int k = 0; k < o.frames; ++k) {
    const double s = double(k) / (o.frames - 1);
    values[std::size_t(k)] = o.vary == "root" ? s : from + (o.to.value_or(0.0) - from) * s;
  }

  json film = {{"format", "quijibo-film"},
               {"version", 1},
               {"fingerprint", fingerprint},
               {"map", map_path},
               {"film", o.ToJson()},
               {"framing", framing},
               {"values", values}};
  WriteFileAtomically(film_json, film.dump(1) + "\n");

  FilmSummary summary;
  summary.out = out;
  summary.frames = o.frames;
  mesh::RenderOptions render = o.render;
  render.views = 1;
  render.framing = framing;
  std::vector<double> made_seconds;
  Progress progress("film", o.frames, quiet);
  for (int k = 0; k < o.frames; ++k) {
    const std::string base = out + "/frames/" + FrameName(k);
    const json done = ReadStageFile(base + ".json");
    if (fs::exists(base + ".png") && done.is_object()) {
      FilmFrame f;
      f.index = k + 1;
      f.value = done.value("value", 0.0);
      f.translation = done.value("translation", std::vector<double>());
      f.triangles = done.value("triangles", 0LL);
      f.seconds = done.value("seconds", 0.0);
      f.mesh_seconds = done.value("mesh_seconds", 0.0);
      f.render_seconds = done.value("render_seconds", 0.0);
      f.note = done.value("note", "");
      summary.frame_list.push_back(f);
      ++summary.reused;
      progress.update(k + 1, FrameName(k) + " reused");
      continue;
    }
    const auto f0 = std::chrono::steady_clock::now();
    const double v = values[std::size_t(k)];
    MeshStageOptions mo = o.mesh;
    mo.meshing.show_progress = false;
    mo.vdb_grids.clear();
    RationalMap frame_map;
    const RationalMap* map = &iterated;
    if (fixed_map) {
      // The map is iterated as made above: no frame change or detail again.
      mo.iteration_frame = IterationFrame::kMap;
      mo.detail = 0;
      mo.translate.reset();
      if (o.vary == "translate_potential") {
        if (!(untranslated_first && k == 0)) {
          const Vec4 t = TranslationForPotential(iterated, direction, v);
          mo.translate = std::vector<double>{t[0], t[1], t[2]};
        }
      } else if (o.vary == "translation") {
        mo.translate = std::vector<double>{v * direction[0] / dn, v * direction[1] / dn, v * direction[2] / dn};
      } else {
        mo.julia.iterations = std::max(1, int(std::lround(v)));
        if (o.mesh.translate_potential) {
          const Vec4 t = TranslationForPotential(iterated, direction, *o.mesh.translate_potential);
          mo.translate = std::vector<double>{t[0], t[1], t[2]};
        } else if (o.mesh.translate) {
          mo.translate = o.mesh.translate;
        }
        mo.translate_potential.reset();
      }
    } else {
      frame_map = input;
      if (o.vary == "detail") {
        mo.detail = v;
      } else if (o.vary == "exponent") {
        *Root(frame_map, o.root).exponent = v;
      } else {  // root
        RationalMap start = input;
        const Vec4 p0 = *Root(start, o.root).position;
        Vec4& p = *Root(frame_map, o.root).position;
        for (int a = 0; a < 3; ++a) p[a] = p0[a] + v * ((*o.to_position)[a] - p0[a]);
      }
      map = &frame_map;
    }
    FilmFrame f;
    f.index = k + 1;
    f.value = v;
    MeshStageResult r;
    try {
      r = MeshJulia(mo.Iterated(*map), mo);  // each frame is its own map or setting
    } catch (const Error& x) {
      // A frame the setting makes impossible (no translation reaches the potential) is drawn empty
      // and said so; the film goes on.
      f.note = x.what();
      if (!quiet) std::fprintf(stderr, "\nquijibo: film: %s: %s\n", FrameName(k).c_str(), x.what());
    }
    f.translation = {r.julia.root_translation[0], r.julia.root_translation[1], r.julia.root_translation[2]};
    f.triangles = (long long)r.mesh.triangles.size();
    f.mesh_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - f0).count();
    Image image(render.size, render.size, Rgb{245, 245, 245});
    mesh::RenderSummary rs;
    if (!r.empty()) image = mesh::RenderView(r.mesh, o.azimuth, o.elevation, render, &rs);
    f.render_seconds = rs.seconds;
    WritePng(base + ".png", image);
    f.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - f0).count();
    WriteFileAtomically(base + ".json", f.ToJson().dump(1) + "\n");
    summary.frame_list.push_back(f);
    made_seconds.push_back(f.seconds);
    ++summary.made;
    progress.update(k + 1, FrameName(k) + ", " + std::to_string(f.triangles) + " triangles");
  }
  progress.finish();
  if (!made_seconds.empty()) {
    std::sort(made_seconds.begin(), made_seconds.end());
    const std::size_t n = made_seconds.size();
    summary.median_frame_seconds = n % 2 ? made_seconds[n / 2] : 0.5 * (made_seconds[n / 2 - 1] + made_seconds[n / 2]);
  }
  json frames_json = json::array();
  for (const FilmFrame& f : summary.frame_list) frames_json.push_back(f.ToJson());
  WriteFileAtomically(out + "/frames.json", frames_json.dump(1) + "\n");

  if (o.video) {
    const std::string mp4 = out + "/film.mp4", partial = out + "/film.partial.mp4";
    ChildOptions c;
    c.program = "ffmpeg";
    c.search_path = true;
    c.args = {"-y",   "-loglevel", "error", "-framerate", std::to_string(o.fps), "-i", out + "/frames/frame-%04d.png",
              "-c:v", "libx264",   "-pix_fmt", "yuv420p", "-crf", "18", "-vf", "pad=ceil(iw/2)*2:ceil(ih/2)*2",
              partial};
    c.stderr_path = out + "/ffmpeg.log";
    try {
      const ChildResult cr = RunChild(c);
      if (cr.ok()) {
        fs::rename(partial, mp4, ec);
        if (ec) throw Error(mp4 + ": " + ec.message());
        fs::remove(out + "/ffmpeg.log", ec);
        summary.video = mp4;
      } else {
        fs::remove(partial, ec);
        summary.video_note = "ffmpeg failed (" + cr.Describe() + "; see " + out + "/ffmpeg.log)";
      }
    } catch (const Error& x) {
      summary.video_note = std::string("ffmpeg could not start (") + x.what() +
                           "); the frames are written: install ffmpeg (apt-get install ffmpeg) and rerun";
    }
  }
  summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  WriteFileAtomically(out + "/summary.json", summary.ToJson().dump(1) + "\n");
  return summary;
}

}  // namespace quijibo::pipeline
