#include "experiments/pipeline/run.h"

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>

#include "experiments/pipeline/plot.h"
#include "mesh/fidelity.h"
#include "mesh/sdf_command.h"
#include "quijibo/error.h"
#include "quijibo/io.h"
#include "quijibo/progress.h"

namespace quijibo::pipeline {

using nlohmann::json;
namespace fs = std::filesystem;

namespace {

// The files a params file or portal spec reads besides itself (target or map, SDF masks' files, a
// versor polynomial), resolved against `dir`: they join the stage's hash, so editing one reruns it.
void ReferencedFiles(const json& j, const fs::path& dir, std::vector<std::string>& out) {
  if (j.is_object()) {
    if (j.value("type", "") == "sdf" && j.contains("file") && j["file"].is_string())
      out.push_back(ResolvePath(dir, j["file"]));
    if (j.contains("polynomial") && j["polynomial"].is_string()) out.push_back(ResolvePath(dir, j["polynomial"]));
    for (const char* k : {"target", "map"}) {
      std::error_code ec;
      if (j.contains(k) && j[k].is_string() && fs::is_regular_file(ResolvePath(dir, j[k]), ec))
        out.push_back(ResolvePath(dir, j[k]));
    }
  }
  if (j.is_structured())
    for (const auto& x : j) ReferencedFiles(x, dir, out);
}

class Runner {
 public:
  Runner(const Experiment& e, const std::string& results, const RunOptions& o)
      : e_(e),
        quiet_(o.quiet),
        cache_(
            results, o.resume, [this](const std::string& what) { Announce(what); },
            [this](const std::string& what) {
              if (!quiet_) std::fprintf(stderr, "quijibo:       %s\n", what.c_str());
            },
            [this](const StageRecord& r) {
              if (!quiet_)
                std::fprintf(stderr, "quijibo:       %s %s (%s)\n", r.name.c_str(), r.status.c_str(),
                             FormatDuration(r.seconds).c_str());
            }) {}

  void Quijibo();
  void Modulus();
  void Portal();
  const std::vector<StageRecord>& records() const { return cache_.records(); }

 private:
  void Announce(const std::string& what) {
    ++index_;
    if (!quiet_) std::fprintf(stderr, "quijibo: [%d/%d] %s\n", index_, total_, what.c_str());
  }
  std::string P(const std::string& rel) const { return cache_.Path(rel); }
  // The render of a modulus or portal mesh.
  void RenderStage(const std::string& mesh, const std::string& upstream);

  const Experiment& e_;
  bool quiet_;
  StageCache cache_;
  int index_ = 0, total_ = 0;
};

void Runner::Quijibo() {
  const TargetOptions& t = *e_.target;
  const InitialGuessStageOptions& in = e_.initial;
  const bool plot = e_.outputs.plot;
  total_ = 1 + int(e_.optimizers.size()) + (plot ? 1 : 0) + (e_.mesh.enabled ? 1 : 0) + (e_.pictures.enabled ? 1 : 0);

  // 1. initial: the target grid and the initial map.
  std::vector<std::string> files;
  if (!t.mesh.empty()) files.push_back(t.mesh);
  if (!t.qgrid.empty()) {
    files.push_back(t.qgrid);
    if (fs::exists(mesh::FrameJsonPathFor(t.qgrid))) files.push_back(mesh::FrameJsonPathFor(t.qgrid));
  }
  if (in.kind == "map") files.push_back(in.map);
  const json initial_inputs = {{"target", t.ToJson()}, {"initial", in.ToJson()}};
  const std::string initial_hash =
      cache_.Run("initial", "initial", initial_inputs, files, {}, [&](const std::string& dir) {
        const TargetResult target = Target(t);
        const InitialGuessResult guess = InitialGuess(target, in);
        WriteTarget(target, t, dir);
        WriteInitialGuess(guess, dir);
        if (!guess.summary.is_null()) WriteFileAtomically(dir + "/monopoles.out", guess.summary.dump(1) + "\n");
      });

  // 2. optimize, once per optimizer entry, in place (its checkpoint survives a kill).
  std::vector<std::string> opt_hashes;
  for (const OptimizeStageOptions& o : e_.optimizers) {
    const std::string title = "optimize (" + o.name + ", schedule " + o.optimizer.schedule.notation() + ")";
    opt_hashes.push_back(cache_.RunInPlace("optimize", "optimize " + o.name, title, o.name, o.ToJson(), {initial_hash},
                                           [&](const std::string& dir, bool resume) {
                                             const ScalarGrid target = ReadGrid(P("initial/target.qgrid"));
                                             const OptimizeStageResult r = OptimizeStage(
                                                 target, resume ? RationalMap{} : ReadMap(P("initial/map.json")), o,
                                                 dir, resume);
                                             if (!quiet_) std::fprintf(stderr, "%s", r.summary.Report().c_str());
                                           }));
  }

  // 3. convergence plot
  if (plot) {
    PlotOptions po;
    for (const OptimizeStageOptions& o : e_.optimizers) {
      po.logs.push_back(P(o.name + "/log.jsonl"));
      po.labels.push_back(o.name + " (" + o.ToJson()["evaluator"].get<std::string>() + ", " +
                          o.ToJson()["precision"].get<std::string>() + ")");
    }
    cache_.Run("plot", "plot", {{"labels", po.labels}}, po.logs, opt_hashes, [&](const std::string& dir) {
      // Nothing to draw is a result of the optimization, not a failure of the run.
      const auto drawable = [](const std::string& l) { return HasEnergies(ReadConvergenceLog(l)); };
      if (std::none_of(po.logs.begin(), po.logs.end(), drawable)) {
        WriteFileAtomically(dir + "/no-plot.txt", "no plot: no iterations and no absolute energies in the logs\n");
        if (!quiet_) std::fprintf(stderr, "quijibo:       no plot: no iterations\n");
        return;
      }
      PlotOptions p = po;
      p.out = dir + "/convergence";
      if (e_.optimizers.size() == 1) p.labels.clear();
      Plot(p);
    });
  }

  // 4. mesh
  const OptimizeStageOptions& chosen = e_.chosen_optimizer();
  const std::string chosen_hash = opt_hashes[std::size_t(&chosen - e_.optimizers.data())];
  const std::string map_path = P(chosen.name + "/map.json");
  std::string mesh_hash;
  if (e_.mesh.enabled)
    mesh_hash = cache_.Run("mesh", "mesh", e_.mesh.ToJson(), {}, {chosen_hash}, [&](const std::string& dir) {
      MeshStageOptions mo = e_.mesh;
      mo.meshing.show_progress = true;
      const MeshFiles f{dir + "/julia.ply", mo.obj ? dir + "/julia.obj" : "", mo.vdb ? dir + "/julia.vdb" : ""};
      const RationalMap map = ReadMap(map_path);
      const MeshStageResult r = MeshJulia(map, mo);
      // A set without surface in the box is a result: the summary says 0 triangles, the report why.
      if (r.empty() && !quiet_)
        std::fprintf(stderr, "quijibo: the surface does not cross the box (no triangles): no mesh written\n");
      WriteMeshFiles(r, mo, f);
      json summary = MeshSummary(r, mo, map_path, f);
      // How much fractal detail the set has, against the target mesh (mesh/fidelity.h).
      const TargetOptions& t = *e_.target;
      if (!r.empty() && !t.mesh.empty() && mo.frame == "user") {
        const mesh::TriangleMesh shape = mesh::ReadMesh(t.mesh);
        summary["detail"] = mesh::MeasureMeshDetail(r.mesh, &shape, (1.0 - 2.0 * map.frame.padding) / map.frame.scale).ToJson();
      }
      WriteFileAtomically(dir + "/summary.json", summary.dump(2) + "\n");
    });

  // 5. pictures: the optimized set against the target, and the mesh rendered.
  if (e_.pictures.enabled)
    cache_.Run("pictures", "pictures", e_.pictures.ToJson(), {}, {initial_hash, chosen_hash, mesh_hash},
               [&](const std::string& dir) {
                 const bool has_mesh = !mesh_hash.empty() && fs::exists(P("mesh/julia.ply"));
                 Pictures(e_.pictures, ReadMap(P("initial/map.json")), ReadMap(map_path), P("initial/target.qgrid"),
                          has_mesh ? P("mesh/julia.ply") : "", dir);
               });
}

void Runner::RenderStage(const std::string& mesh, const std::string& upstream) {
  cache_.Run("pictures", "pictures", e_.pictures.ToJson(), {}, {upstream}, [&](const std::string& dir) {
    WritePng(dir + "/render.png", mesh::RenderMesh(mesh::ReadMesh(P(mesh)), e_.pictures.render));
  });
}

void Runner::Modulus() {
  const TargetOptions& t = *e_.target;
  const ModulusStageOptions& m = e_.modulus;
  const bool render = e_.pictures.enabled && m.output.format == "ply";
  total_ = 1 + (render ? 1 : 0);
  std::vector<std::string> files;
  const std::string spec = t.mesh.empty() ? (t.qgrid.empty() ? t.analytic : t.qgrid) : t.mesh;
  if (t.analytic.empty()) files.push_back(spec);
  if (m.versor.poly) files.push_back(*m.versor.poly);
  if (m.params) {
    files.push_back(*m.params);
    ReferencedFiles(ParseJson(ReadFile(*m.params), *m.params), fs::path(*m.params).parent_path(), files);
  }
  const std::string out = "julia." + m.output.format;
  const json inputs = {{"target", t.ToJson()}, {"modulus", m.ToJson()}};
  const std::string hash = cache_.Run("modulus", "modulus", inputs, files, {}, [&](const std::string& dir) {
    const ModulusStageResult r = pipeline::Modulus(spec, m, dir + "/" + out);
    WriteModulus(r, dir + "/" + out, m.versor.poly ? "" : dir + "/versor.json");
    WriteFileAtomically(dir + "/modulus.json", r.report.dump(1) + "\n");
  });
  if (render) RenderStage("modulus/julia.ply", hash);
}

void Runner::Portal() {
  const PortalStageOptions& p = e_.portal;
  const bool render = e_.pictures.enabled && p.output.format == "ply";
  total_ = 1 + (render ? 1 : 0);
  std::vector<std::string> files;
  if (!p.spec_file.empty()) {
    files.push_back(p.spec_file);
    ReferencedFiles(ParseJson(ReadFile(p.spec_file), p.spec_file), fs::path(p.spec_file).parent_path(), files);
  } else if (!p.spec_inline.is_null()) {
    ReferencedFiles(p.spec_inline, fs::path(e_.path).parent_path(), files);
  }
  const std::string out = "julia." + p.output.format;
  const std::string hash = cache_.Run("portal", "portal", p.ToJson(), files, {}, [&](const std::string& dir) {
    const PortalStageResult r = pipeline::Portal(p, dir + "/" + out);
    WritePortal(r, dir + "/" + out, dir + "/spec.json", "");
    WriteFileAtomically(dir + "/portal.json", r.report.dump(1) + "\n");
  });
  if (render) RenderStage("portal/julia.ply", hash);
}

// The results folder, created if need be; throws when it cannot be written. `created` tells
// whether this run made it.
std::string PrepareResults(const std::string& out, bool* created) {
  if (out.empty()) throw Error("--out: expected a folder, found an empty string");
  std::error_code ec;
  if (fs::exists(out, ec) && !fs::is_directory(out, ec)) throw Error(out + ": exists and is not a folder");
  *created = !fs::exists(out, ec);
  if (*created) {
    fs::path parent = fs::absolute(out).parent_path();
    while (!parent.empty() && !fs::exists(parent, ec) && parent != parent.parent_path()) parent = parent.parent_path();
    if (::access(parent.c_str(), W_OK) != 0)
      throw Error(out + ": cannot create the results folder: " + parent.string() + " is not writable (" +
                  std::strerror(errno) + ")");
    fs::create_directories(out, ec);
    if (ec) throw Error(out + ": cannot create the results folder: " + ec.message());
  } else if (::access(out.c_str(), W_OK) != 0) {
    throw Error(out + ": the results folder is not writable (" + std::strerror(errno) + ")");
  }
  return fs::absolute(out).lexically_normal().string();
}

}  // namespace

RunSummary RunExperiment(const Experiment& e, const RunOptions& o) {
  if (o.quiet) Progress::globally_quiet() = true;
  RunSummary summary;
  summary.resolved = e.ToJson();
  if (o.check_only) return summary;
  const std::string out = !o.out_dir.empty() ? o.out_dir : e.outputs.folder ? *e.outputs.folder : "results/" + e.name;
  bool created = false;
  summary.results = PrepareResults(out, &created);
  summary.resolved["results"] = summary.results;
  const auto t0 = std::chrono::steady_clock::now();
  Runner runner(e, out, o);
  try {
    if (e.method == "quijibo")
      runner.Quijibo();
    else if (e.method == "modulus")
      runner.Modulus();
    else
      runner.Portal();
  } catch (...) {
    // A folder this run created and left empty goes again.
    std::error_code ec;
    if (created && fs::is_empty(out, ec)) fs::remove(out, ec);
    throw;
  }
  summary.stages = runner.records();
  summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  json run = {{"experiment", e.path}, {"name", e.name}, {"seconds", summary.seconds}, {"stages", json::array()}};
  for (const auto& r : summary.stages)
    run["stages"].push_back({{"stage", r.name}, {"status", r.status}, {"seconds", r.seconds}, {"hash", r.hash}});
  WriteFileAtomically(out + "/experiment.resolved.json", summary.resolved.dump(2) + "\n");
  WriteFileAtomically(out + "/run.json", run.dump(1) + "\n");
  if (e.outputs.report) WriteFileAtomically(out + "/report.md", RunReport(e, summary.stages, out, summary.seconds));
  if (!o.quiet) {
    std::fprintf(stderr, "quijibo: done in %s. Results in %s/\n", FormatDuration(summary.seconds).c_str(), out.c_str());
    if (e.outputs.report) std::fprintf(stderr, "quijibo: start with %s/report.md\n", out.c_str());
  }
  return summary;
}

}  // namespace quijibo::pipeline
