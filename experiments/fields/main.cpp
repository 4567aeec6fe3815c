// `quijibo-fields`: the numbers behind the gallery's field pictures (docs/gallery.md), for any map a
// portal spec can name — a shape modulus target (no portals: the 2023 map), a QUIJIBO map.json
// ("map"), or either with portals (2024), or the Koch preset (--koch).
//
// Input: points as a .npy of float64, shape (N, 3) (q = [x, y, z, 0]) or (N, 4) (q = [w, x, y, z]),
// in the map's own frame (unit frame for a target, fractal frame for a map.json).
// Output (-o, .npy float64, shape (N, 7)): for each point q0,
//   [log|q_n| (the meshed field, clamped, quaternion_map.h), log|F(q0)| (the modulus r, log),
//    F(q0)/|F(q0)| (the versor d: w, i, j, k), n (applications made before escape or the cap)]
// --seeds S (with --average-out): the fraction of the S versors generated with seeds 1..S (the spec's
// "versor": {"generate": ...} with its seed replaced) for which the point is inside (log|q_n| < 0),
// shape (N,): the 2023 paper's average of random sets (Fig. 8).
// --orbit K (with --orbit-out): the orbit q0, F(q0), ... up to K applications or until |q| reaches
// the escape radius, shape (N, K + 1, 4), NaN after the last iterate.
// --weights-of SDF.qgrid --weights KIND --weights-out W.qgrid (instead of a map and points): the
// energy's weight field W (quijibo/target.h: layer, inverse = the paper's 1/phi, balanced) on the
// SDF's grid, as the optimizer builds it (2015 Fig. 7).
// --alpha / --beta replace the spec's (numbers) before the map is built.
// The map, its iterations and escape radius are the spec's (as `quijibo portal` uses them) unless
// --iterations / --escape are given. A summary (JSON) goes to stdout.
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "experiments/fields/npy.h"
#include "methods/portal_scene.h"
#include "quijibo/grid.h"
#include "quijibo/quaternion_map.h"
#include "quijibo/target.h"
#include "util/error.h"
#include "util/io.h"

namespace {

using quijibo::Quat;

int Main(int argc, char** argv) {
  CLI::App app{"Modulus, versor, meshed field and orbits of a map at given points (docs/gallery.md)", "quijibo-fields"};
  std::string spec_path, points_path, out_path, orbit_out, average_out, weights_of, weights_out, weights = "inverse";
  bool koch = false, turbulent = false;
  std::optional<double> beta_override;
  int sdf_resolution = 100, iterations = 0, orbit = 0, seeds = 0;
  double escape = 0.0, alpha = 0.0;
  app.add_option("spec", spec_path, "Portal spec (docs/modulus-portals.md): a target or a map.json, portals optional");
  app.add_flag("--koch", koch, "The Koch snowflake preset of `quijibo portal --koch` instead of a spec");
  app.add_flag("--turbulent", turbulent, "With --koch: the turbulent preset (alpha 30, noise versor)");
  app.add_option("--sdf-resolution", sdf_resolution, "Cells of a mesh target's SDF")->capture_default_str()
      ->check(CLI::Range(8, 1024));
  app.add_option("--points", points_path, "Points, .npy float64 (N, 3) or (N, 4)");
  app.add_option("-o,--out", out_path, "Output .npy (N, 7)");
  app.add_option("--iterations", iterations, "Map applications n (default: the spec's)")->check(CLI::Range(1, 10000));
  app.add_option("--escape", escape, "Escape radius (default: the spec's)")->check(CLI::PositiveNumber);
  app.add_option("--alpha", alpha,
                 "Replace the spec's alpha (a shape modulus target): e.g. a tiny alpha draws the versor where "
                 "e^(alpha phi) over- or underflows, alpha 1 with beta 0 gives log r = phi")
      ->check(CLI::PositiveNumber);
  app.add_option("--beta", beta_override, "Replace the spec's beta");
  app.add_option("--orbit", orbit, "Orbit length K (applications) for --orbit-out")->check(CLI::Range(1, 10000));
  app.add_option("--orbit-out", orbit_out, "Output .npy (N, K + 1, 4) of the orbits");
  app.add_option("--seeds", seeds, "Versors generated with seeds 1..S for --average-out")->check(CLI::Range(1, 100000));
  app.add_option("--average-out", average_out, "Output .npy (N,): fraction of the --seeds sets holding each point");
  app.add_option("--weights-of", weights_of, "SDF .qgrid whose weight field to write (--weights-out)");
  app.add_option("--weights", weights, "Weight field: layer, inverse or balanced")->capture_default_str();
  app.add_option("--weights-out", weights_out, "Output .qgrid of the weights");
  CLI11_PARSE(app, argc, argv);
  try {
    if (!weights_of.empty() || !weights_out.empty()) {
      if (weights_of.empty() || weights_out.empty()) throw quijibo::Error("--weights-of and --weights-out go together");
      const quijibo::ScalarGrid sdf = quijibo::ReadGrid(weights_of);
      quijibo::ScalarGrid w = sdf;
      w.values = quijibo::ComputeWeights(sdf, quijibo::ParseWeightField(weights));
      w.quantity = "weight-" + weights;
      quijibo::CreateParentFolder(weights_out);
      quijibo::WriteGrid(weights_out, w);
      std::printf("{\"weights\": \"%s\", \"cells\": %zu}\n", weights.c_str(), w.values.size());
      return 0;
    }
    if (points_path.empty() || out_path.empty()) throw quijibo::Error("--points and -o are required");
    if (koch != spec_path.empty()) throw quijibo::Error("give a spec or --koch (one of them)");
    if (turbulent && !koch) throw quijibo::Error("--turbulent goes with --koch");
    if (!orbit_out.empty() && orbit == 0) throw quijibo::Error("--orbit-out needs --orbit K");
    if (!average_out.empty() && seeds == 0) throw quijibo::Error("--average-out needs --seeds S");
    if (!quijibo::HasExtension(out_path, ".npy") || (!orbit_out.empty() && !quijibo::HasExtension(orbit_out, ".npy")) ||
        (!average_out.empty() && !quijibo::HasExtension(average_out, ".npy")))
      throw quijibo::Error("outputs are .npy files");
    nlohmann::json doc;
    std::string source = spec_path;
    if (koch) {
      // `quijibo portal --koch`'s settings (experiments/cli/modulus.cpp): alpha 3000, or 30 turbulent.
      doc = quijibo::mesh::KochSpec(turbulent ? 30.0 : 3000.0, 0.0, turbulent, 0.005);
      source = "--koch";
    } else {
      try {
        doc = nlohmann::json::parse(quijibo::ReadFile(spec_path));
      } catch (const nlohmann::json::parse_error& e) {
        throw quijibo::Error(spec_path + ": not JSON: " + e.what());
      }
    }
    if (alpha > 0 || beta_override) {
      if (doc.contains("map")) throw quijibo::Error(source + ": --alpha/--beta need a target, not a map.json");
      if (alpha > 0) doc["alpha"] = alpha;
      if (beta_override) doc["beta"] = *beta_override;
    }
    const quijibo::mesh::PortalScene scene = quijibo::mesh::SceneFromSpec(doc, source, sdf_resolution);
    quijibo::IterationOptions io;
    io.iterations = iterations > 0 ? iterations : scene.iterations;
    io.escape_radius = escape > 0 ? escape : scene.escape;
    if (auto why = io.Validate(); !why.empty()) throw quijibo::Error(why);

    const quijibo::fields::NpyArray pts = quijibo::fields::ReadNpy(points_path);
    if (pts.shape.size() != 2 || (pts.shape[1] != 3 && pts.shape[1] != 4))
      throw quijibo::Error(points_path + ": expected shape (N, 3) or (N, 4)");
    const std::size_t n = pts.shape[0], w = pts.shape[1];
    std::vector<double> out(n * 7);
    const std::size_t ko = std::size_t(orbit);
    std::vector<double> orbits(orbit_out.empty() ? 0 : n * (ko + 1) * 4, std::numeric_limits<double>::quiet_NaN());
    const quijibo::QuaternionMap& map = *scene.map;
    const double escape2 = io.escape_radius * io.escape_radius;
    long long nan_points = 0;
#pragma omp parallel for schedule(dynamic, 256) reduction(+ : nan_points)
    for (long long i = 0; i < (long long)n; ++i) {
      const double* p = &pts.data[std::size_t(i) * w];
      const Quat q0 = w == 3 ? Quat(p[0], p[1], p[2], 0.0) : Quat(p[0], p[1], p[2], p[3]);
      double* o = &out[std::size_t(i) * 7];
      int used = 0;
      o[0] = quijibo::IterateField(map, q0, io, &used);
      const Quat q1 = map.Apply(q0);
      const double r = std::sqrt(q1.norm2());
      // |F(q)| beyond double's range (e^(alpha phi) with a large alpha) counts as +inf.
      o[1] = std::isfinite(r) ? std::log(r) : std::numeric_limits<double>::infinity();
      const Quat d = r > 0 && std::isfinite(r) ? q1 * (1.0 / r) : Quat(1.0, 0.0, 0.0, 0.0);
      o[2] = d.w, o[3] = d.x, o[4] = d.y, o[5] = d.z;
      o[6] = used;
      if (!std::isfinite(o[1])) ++nan_points;
      if (!orbits.empty()) {
        double* t = &orbits[std::size_t(i) * (ko + 1) * 4];
        Quat q = q0;
        for (std::size_t k = 0; k <= ko; ++k) {
          t[4 * k] = q.w, t[4 * k + 1] = q.x, t[4 * k + 2] = q.y, t[4 * k + 3] = q.z;
          if (k == ko || !(q.norm2() < escape2)) break;
          q = map.Apply(q);
        }
      }
    }
    std::vector<double> average;
    if (!average_out.empty()) {
      if (doc.contains("map") || (doc.contains("versor") && !doc["versor"].contains("generate")))
        throw quijibo::Error(source + ": --seeds needs a target whose versor is generated (\"versor\": {\"generate\": ...})");
      if (!doc.contains("versor")) doc["versor"] = {{"generate", nlohmann::json::object()}};
      average.assign(n, 0.0);
      for (int seed = 1; seed <= seeds; ++seed) {
        doc["versor"]["generate"]["seed"] = seed;
        const quijibo::mesh::PortalScene s = quijibo::mesh::SceneFromSpec(doc, source, sdf_resolution);
        const quijibo::QuaternionMap& m = *s.map;
#pragma omp parallel for schedule(dynamic, 256)
        for (long long i = 0; i < (long long)n; ++i) {
          const double* p = &pts.data[std::size_t(i) * w];
          const Quat q0 = w == 3 ? Quat(p[0], p[1], p[2], 0.0) : Quat(p[0], p[1], p[2], p[3]);
          if (quijibo::IterateField(m, q0, io) < 0) average[std::size_t(i)] += 1.0;
        }
      }
      for (double& a : average) a /= seeds;
    }
    quijibo::CreateParentFolder(out_path);
    quijibo::fields::WriteNpy(out_path, {n, 7}, out);
    if (!orbit_out.empty()) {
      quijibo::CreateParentFolder(orbit_out);
      quijibo::fields::WriteNpy(orbit_out, {n, ko + 1, 4}, orbits);
    }
    if (!average_out.empty()) {
      quijibo::CreateParentFolder(average_out);
      quijibo::fields::WriteNpy(average_out, {n}, average);
    }
    nlohmann::json summary = {{"points", n},
                              {"iterations", io.iterations},
                              {"escape_radius", io.escape_radius},
                              {"two_d", scene.two_d},
                              {"nonfinite_modulus", nan_points},
                              {"columns", {"field_n", "log_modulus", "versor_w", "versor_i", "versor_j", "versor_k",
                                           "applications"}}};
    if (!scene.box.empty()) summary["box"] = scene.box;
    std::printf("%s\n", summary.dump(2).c_str());
    return 0;
  } catch (const quijibo::Error& e) {
    std::fprintf(stderr, "quijibo-fields: error: %s\n", e.what());
    return 1;
  }
}

}  // namespace

int main(int argc, char** argv) { return Main(argc, argv); }
