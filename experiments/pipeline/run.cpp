#include "experiments/pipeline/run.h"

#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <csignal>
#include <optional>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <map>
#include <mutex>
#include <set>
#include <thread>

#include "experiments/pipeline/plot.h"
#include "experiments/pipeline/quality.h"
#include "experiments/pipeline/report.h"
#include "experiments/pipeline/triptych.h"
#include "experiments/pipeline/report_html.h"
#include "mesh/fidelity.h"
#include "mesh/frame_file.h"
#include "util/error.h"
#include "util/io.h"
#include "util/progress.h"
#include "util/signals.h"

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
    if (j.contains("kind") && j.contains("file") && j["file"].is_string()) out.push_back(ResolvePath(dir, j["file"]));
    for (const char* k : {"target", "map"}) {
      std::error_code ec;
      if (j.contains(k) && j[k].is_string() && fs::is_regular_file(ResolvePath(dir, j[k]), ec))
        out.push_back(ResolvePath(dir, j[k]));
    }
  }
  if (j.is_structured())
    for (const auto& x : j) ReferencedFiles(x, dir, out);
}

// A word for a command line to copy: quoted when the shell would split or expand it.
std::string ShellWord(const std::string& w) {
  if (!w.empty() && w.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789-_./=+:,@") ==
                        std::string::npos)
    return w;
  std::string q = "'";
  for (char c : w) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

class Runner {
 public:
  Runner(const Experiment& e, const std::string& results, const RunOptions& o, bool created)
      : e_(e),
        quiet_(o.quiet),
        results_(results),
        created_(created),
        signals_(o.handle_signals),
        resume_("quijibo run " + (e.path.empty() ? std::string("EXPERIMENT.json") : ShellWord(e.path)) + " --out " +
                ShellWord(results) + " --resume"),
        t0_(std::chrono::steady_clock::now()),
        cache_(
            results, o.resume, [this](const std::string& what) { Announce(what); },
            [this](const std::string& what) {
              if (!quiet_) std::fprintf(stderr, "quijibo:       %s\n", what.c_str());
            },
            [this](const StageRecord& r) {
              if (!quiet_)
                std::fprintf(stderr, "quijibo:       %s %s (%s)\n", r.name.c_str(), r.status.c_str(),
                             FormatDuration(r.seconds).c_str());
              const std::lock_guard<std::mutex> lock(mu_);
              records_.push_back(r);
              computing_.clear();
            },
            [this](const std::string& folder) {
              Computing(folder);
              TestSignal(folder);
            }) {}

  void Quijibo();
  void Modulus();
  void Portal();
  void JuliaSet();
  const std::vector<StageRecord>& records() const { return cache_.records(); }
  double Seconds() const { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count(); }
  const std::string& resume_command() const { return resume_; }

  // The run stopped on an error: report.md and run.json say where and why (as far as the disk
  // lets them: the error may be a full disk), and a results folder this run created goes again
  // when no stage finished. Returns the stage it stopped in.
  std::string Failed(const std::string& reason) {
    const std::lock_guard<std::mutex> lock(mu_);
    try {
      WriteStatus(reason);
    } catch (...) {
    }
    RemoveIfNothingFinished();
    return stage_;
  }

  // SIGINT/SIGTERM outside the optimization (SignalWatcher's thread): the unfinished stage's
  // partial folder goes, report.md says INCOMPLETE, one line on stderr, exit 128 + signal.
  [[noreturn]] void Stop(int signal) {
    mu_.lock();  // held to the end: the main thread writes no more status
    const std::string why = "interrupted (" + SignalName(signal) + ")";
    std::error_code ec;
    if (!computing_.empty() && !in_place_.count(computing_)) fs::remove_all(P(computing_ + ".partial"), ec);
    std::string line;
    if (finished_) {
      line = "quijibo: " + why + " after the run finished\n";
    } else {
      try {
        WriteStatus(why);
      } catch (...) {
      }
      line = "quijibo: " + why + " in stage " + (stage_.empty() ? std::string("(none yet)") : stage_) +
             (RemoveIfNothingFinished() ? "; nothing finished, the results folder is removed"
                                        : (e_.outputs.report ? "; report.md says INCOMPLETE" : "")) +
             "; resume with: " + resume_ + "\n";
    }
    [[maybe_unused]] const ssize_t n = ::write(STDERR_FILENO, line.data(), line.size());
    ::_exit(128 + signal);
  }
  void Finished() {
    const std::lock_guard<std::mutex> lock(mu_);
    finished_ = true;
  }
  // experiment.resolved.json and run.json (`state` null: the run is complete).
  nlohmann::json ResolvedJson() const {
    json j = e_.ToJson();
    j["results"] = fs::absolute(results_).lexically_normal().string();
    return j;
  }
  nlohmann::json RunJson(const std::vector<StageRecord>& records, double seconds, const RunState* state) const {
    json run = {{"experiment", e_.path}, {"name", e_.name}, {"seconds", seconds}, {"stages", json::array()}};
    for (const auto& r : records)
      run["stages"].push_back({{"stage", r.name}, {"status", r.status}, {"seconds", r.seconds}, {"hash", r.hash}});
    run["complete"] = state == nullptr;
    if (json q = RunQuality(e_, results_); !q.is_null()) run["quality"] = q;
    if (state) run["stopped"] = {{"stage", state->stopped_in}, {"reason", state->reason}, {"resume", state->resume}};
    return run;
  }

 private:
  void Announce(const std::string& what) {
    ++index_;
    {
      const std::lock_guard<std::mutex> lock(mu_);
      stage_ = what;
    }
    if (!quiet_) std::fprintf(stderr, "quijibo: [%d/%d] %s\n", index_, total_, what.c_str());
  }
  // A stage is about to compute: its earlier output is not this run's, and what read it no longer
  // matches, so the stage and the stages downstream lose their folders now (the optimization keeps
  // its own, the checkpoint of --resume), and the run says INCOMPLETE until it ends.
  void Computing(const std::string& folder) {
    const std::lock_guard<std::mutex> lock(mu_);
    computing_ = folder;
    std::error_code ec;
    if (!in_place_.count(folder)) fs::remove_all(P(folder), ec);
    for (const std::string& d : downstream_[folder]) {
      fs::remove_all(P(d), ec);
      fs::remove_all(P(d + ".partial"), ec);
    }
    if (!wrote_resolved_) {
      WriteFileAtomically(P("experiment.resolved.json"), ResolvedJson().dump(2) + "\n");
      wrote_resolved_ = true;
    }
    WriteStatus("the run is computing this stage, or was killed or crashed in it");
  }
  // QUIJIBO_TEST_SIGNAL_IN_STAGE=<folder>: a Ctrl-C as that stage starts computing, for the tests
  // (no timing); SignalWatcher's thread then ends the process.
  void TestSignal(const std::string& folder) const {
    static const char* stage = std::getenv("QUIJIBO_TEST_SIGNAL_IN_STAGE");
    if (!signals_ || !stage || folder != stage) return;
    std::raise(SIGINT);
    for (;;) std::this_thread::sleep_for(std::chrono::seconds(1));
  }
  // report.md and run.json of a run that has not finished. Call with mu_ held.
  void WriteStatus(const std::string& reason) {
    const RunState state{stage_, reason, resume_};
    WriteFileAtomically(P("run.json"), RunJson(records_, Seconds(), &state).dump(1) + "\n");
    std::error_code ec;
    fs::remove(P("report.html"), ec);  // written again when the run ends
    if (e_.outputs.report)
      WriteFileAtomically(P("report.md"), RunReport(e_, records_, results_, Seconds(), state));
    else
      fs::remove(P("report.md"), ec);
  }
  // Call with mu_ held.
  bool RemoveIfNothingFinished() {
    std::error_code ec;
    if (!created_ || !records_.empty()) return false;
    fs::remove_all(results_, ec);
    return true;
  }

  std::string P(const std::string& rel) const { return cache_.Path(rel); }
  // The render of a modulus or portal mesh.
  void RenderStage(const std::string& mesh, const std::string& upstream);
  // The QUIJIBO method's stages (Quijibo); each returns its stage hash.
  std::string InitialStage();
  std::vector<std::string> OptimizeStages(const std::string& initial_hash);
  void PlotStage(const std::vector<std::string>& opt_hashes);
  std::string MeshStage(const std::string& folder, const MeshStageOptions& options, const std::string& chosen_hash,
                        const std::string& map_path);
  void TriptychStage(const std::vector<std::string>& upstream, const std::string& map_path);
  void FidelityStage(const std::string& initial_hash, const std::string& chosen_hash, const std::string& map_path);
  // The map at `map_path` as iterated with `options` (MeshStageOptions::Iterated), made once per run: the mesh
  // stage, the fidelity stage and the triptych share it (the translation by potential is a search).
  std::shared_ptr<const JuliaSetup> IteratedMap(const std::string& map_path, const MeshStageOptions& options);

  const Experiment& e_;
  bool quiet_;
  std::string results_;
  bool created_, signals_;
  std::string resume_;
  std::chrono::steady_clock::time_point t0_;
  // The folders of the stages that read each stage's output (by folder), and the stages that
  // compute in their folder rather than in "<folder>.partial".
  std::map<std::string, std::vector<std::string>> downstream_;
  std::set<std::string> in_place_;
  std::map<std::string, std::shared_ptr<const JuliaSetup>> iterated_;  // IteratedMap's, by map and settings
  // What the run has done, guarded by mu_ for SignalWatcher's thread.
  std::mutex mu_;
  std::string stage_, computing_;
  std::vector<StageRecord> records_;
  bool finished_ = false, wrote_resolved_ = false;
  StageCache cache_;
  int index_ = 0, total_ = 0;
};

// SIGINT/SIGTERM for the life of a run. The handler only writes the signal to a pipe; a thread
// reads it and, as ordinary code, calls `stop` (which ends the process). The optimization installs
// its own handlers while it runs (it checkpoints and returns), and puts these back.
int g_signal_pipe[2] = {-1, -1};
extern "C" void OnRunSignal(int signal) {
  const unsigned char b = static_cast<unsigned char>(signal);
  [[maybe_unused]] const ssize_t n = ::write(g_signal_pipe[1], &b, 1);
}

class SignalWatcher {
 public:
  explicit SignalWatcher(std::function<void(int)> stop) {
    if (::pipe(g_signal_pipe) != 0) throw Error(std::string("cannot watch for signals: ") + std::strerror(errno));
    thread_ = std::thread([stop = std::move(stop)] {
      unsigned char b = 0;
      while (::read(g_signal_pipe[0], &b, 1) < 0 && errno == EINTR) {
      }
      if (b != 0) stop(b);
    });
    guard_.emplace(OnRunSignal);
  }
  ~SignalWatcher() {
    guard_.reset();
    const unsigned char done = 0;
    [[maybe_unused]] const ssize_t n = ::write(g_signal_pipe[1], &done, 1);
    thread_.join();
    ::close(g_signal_pipe[0]);
    ::close(g_signal_pipe[1]);
  }
  SignalWatcher(const SignalWatcher&) = delete;
  SignalWatcher& operator=(const SignalWatcher&) = delete;

 private:
  std::thread thread_;
  std::optional<InterruptGuard> guard_;
};

void Runner::Quijibo() {
  const bool plot = e_.outputs.plot;
  const bool intricate = e_.intricate.enabled, triptych = e_.pictures.enabled && e_.pictures.triptych;
  total_ = 2 + int(e_.optimizers.size()) + (plot ? 1 : 0) + (e_.mesh.enabled ? 1 : 0) + (e_.pictures.enabled ? 1 : 0) +
           (intricate ? 1 : 0) + (triptych ? 1 : 0);
  downstream_["initial"] = {"plot", "mesh", "pictures", "fidelity", "intricate", "triptych"};
  for (const OptimizeStageOptions& o : e_.optimizers) {
    downstream_["initial"].push_back(o.name);
    downstream_[o.name] = {"plot"};
    if (o.name == e_.chosen_optimizer().name)
      downstream_[o.name].insert(downstream_[o.name].end(), {"mesh", "pictures", "fidelity", "triptych"});
    if (o.name == e_.intricate.optimizer) downstream_[o.name].push_back("intricate");
    in_place_.insert(o.name);
  }
  downstream_["mesh"] = {"pictures", "triptych"};
  downstream_["intricate"] = {"triptych"};

  const std::string initial_hash = InitialStage();
  const std::vector<std::string> opt_hashes = OptimizeStages(initial_hash);
  if (plot) PlotStage(opt_hashes);
  const OptimizeStageOptions& chosen = e_.chosen_optimizer();
  const std::string chosen_hash = opt_hashes[std::size_t(&chosen - e_.optimizers.data())];
  const std::string map_path = P(chosen.name + "/map.json");
  const std::string mesh_hash = e_.mesh.enabled ? MeshStage("mesh", e_.mesh, chosen_hash, map_path) : std::string();
  std::string intricate_hash;
  std::error_code ec;
  // Switched off: an earlier run's surface or triptych is not this run's result.
  if (!intricate) fs::remove_all(P("intricate"), ec);
  if (!triptych) fs::remove_all(P("triptych"), ec);
  if (intricate) {
    const auto& io = *std::find_if(e_.optimizers.begin(), e_.optimizers.end(),
                                   [&](const OptimizeStageOptions& o) { return o.name == e_.intricate.optimizer; });
    intricate_hash = MeshStage("intricate", e_.intricate, opt_hashes[std::size_t(&io - e_.optimizers.data())],
                               P(io.name + "/map.json"));
  }
  // The optimized set against the target, and the mesh rendered.
  if (e_.pictures.enabled)
    cache_.Run("pictures", "pictures", e_.pictures.ToJson(), {}, {initial_hash, chosen_hash, mesh_hash},
               [&](const std::string& dir) {
                 const bool has_mesh = !mesh_hash.empty() && fs::exists(P("mesh/julia.ply"));
                 Pictures(e_.pictures, ReadMap(P("initial/map.json")), ReadMap(map_path), P("initial/target.qgrid"),
                          has_mesh ? P("mesh/julia.ply") : "", dir);
               });
  FidelityStage(initial_hash, chosen_hash, map_path);
  if (triptych) TriptychStage({initial_hash, chosen_hash, mesh_hash, intricate_hash}, map_path);
}

// The target grid and the initial map.
std::string Runner::InitialStage() {
  const TargetOptions& t = *e_.target;
  const InitialGuessStageOptions& in = e_.initial;
  std::vector<std::string> files;
  if (!t.mesh.empty()) files.push_back(t.mesh);
  if (!t.qgrid.empty()) {
    files.push_back(t.qgrid);
    if (fs::exists(mesh::FrameJsonPathFor(t.qgrid))) files.push_back(mesh::FrameJsonPathFor(t.qgrid));
  }
  if (in.kind == "map") files.push_back(in.map);
  const json initial_inputs = {{"target", t.ToJson()}, {"initial", in.ToJson()}};
  return cache_.Run("initial", "initial", initial_inputs, files, {}, [&](const std::string& dir) {
    const TargetResult target = Target(t);
    const InitialGuessResult guess = InitialGuess(target, in);
    WriteTarget(target, t, dir);
    WriteInitialGuess(guess, dir);
    if (!guess.summary.is_null()) WriteFileAtomically(dir + "/monopoles.out", guess.summary.dump(1) + "\n");
  });
}

// The optimization, once per optimizer entry, in place (its checkpoint survives a kill).
std::vector<std::string> Runner::OptimizeStages(const std::string& initial_hash) {
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
  return opt_hashes;
}

// The convergence plot of every optimizer's log.
void Runner::PlotStage(const std::vector<std::string>& opt_hashes) {
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

std::shared_ptr<const JuliaSetup> Runner::IteratedMap(const std::string& map_path, const MeshStageOptions& options) {
  // The settings the setup reads, as the stage hashes write them.
  json key = options.ToJson();
  key["map"] = map_path;
  auto& made = iterated_[key.dump()];
  if (!made) made = std::make_shared<const JuliaSetup>(options.Iterated(ReadMap(map_path)));
  return made;
}

// The chosen optimizer's map meshed (`folder` "mesh" with the mesh stage's settings, "intricate"
// with the intricate surface's), with its detail against the target mesh.
std::string Runner::MeshStage(const std::string& folder, const MeshStageOptions& options,
                              const std::string& chosen_hash, const std::string& map_path) {
  const std::string title = folder == "mesh" ? "mesh" : "mesh (" + folder + " surface)";
  return cache_.Run(title, folder, options.ToJson(), {}, {chosen_hash}, [&, folder](const std::string& dir) {
    MeshStageOptions mo = options;
    mo.meshing.show_progress = true;
    const MeshFiles f{dir + "/julia.ply", mo.obj ? dir + "/julia.obj" : "", mo.vdb ? dir + "/julia.vdb" : ""};
    const RationalMap map = ReadMap(map_path);
    MeshStageResult r;
    try {
      const auto setup = IteratedMap(map_path, options);
      r = mo.stream ? MeshJuliaStreamed(*setup, mo, f) : MeshJulia(*setup, mo);
    } catch (const Error& x) {
      // The intricate surface is an extra: a map it cannot be made of (no inside deep enough for the
      // translation by potential) is reported, and the run goes on.
      if (folder == "mesh") throw;
      if (!quiet_) std::fprintf(stderr, "quijibo: no %s surface: %s\n", folder.c_str(), x.what());
      WriteFileAtomically(dir + "/summary.json", json({{"skipped", x.what()}, {"triangles", 0}}).dump(2) + "\n");
      return;
    }
    // A set without surface in the box is a result: the summary says 0 triangles, the report why.
    if (r.empty() && !quiet_)
      std::fprintf(stderr, "quijibo: the %s surface does not cross the box (no triangles): no mesh written\n",
                   folder == "mesh" ? "" : (folder + " ").c_str());
    WriteMeshFiles(r, mo, f);
    json summary = MeshSummary(r, mo, map_path, f);
    // How much fractal detail the set has, against the target mesh (mesh/fidelity.h); not of a
    // streamed mesh, which is not held.
    const TargetOptions& t = *e_.target;
    if (!r.empty() && !r.streamed && !t.mesh.empty() && mo.frame == "user") {
      const mesh::TriangleMesh shape = mesh::ReadMesh(t.mesh);
      summary["detail"] = mesh::MeasureMeshDetail(r.mesh, &shape, (1.0 - 2.0 * map.frame.padding) / map.frame.scale).ToJson();
    }
    WriteFileAtomically(dir + "/summary.json", summary.dump(2) + "\n");
  });
}

// The figures and the start check behind report.md's Quality section (quality.h), at the n and
// iso of the mesh.
void Runner::FidelityStage(const std::string& initial_hash, const std::string& chosen_hash,
                           const std::string& map_path) {
  const double alpha = e_.chosen_optimizer().optimizer.energy.alpha;
  // The set the mesh shows, without its placement and root transforms (they move it off the target).
  JuliaOptions set;
  set.iterations = e_.mesh.julia.iterations;
  set.escape_radius = e_.mesh.julia.escape_radius;
  set.slice = e_.mesh.julia.slice;
  const std::shared_ptr<const JuliaSetup> setup = IteratedMap(map_path, e_.mesh);
  set.root_translation = setup->julia.root_translation;
  QualityOptions qo;
  qo.iterated = std::shared_ptr<const RationalMap>(setup, &setup->map);
  cache_.Run("fidelity", "fidelity",
             {{"julia", JuliaJson(set, e_.mesh.iso, Precision::kDouble)}, {"alpha", alpha},
              {"lattice", qo.lattice}, {"detail", e_.mesh.detail}, {"iteration_frame", IterationFrameName(e_.mesh.iteration_frame)}},
             {}, {initial_hash, chosen_hash}, [&](const std::string& dir) {
               // The start check of the fits is in monopoles.json already (same map, grid and alpha
               // only when the energy's alpha is the guess's: else it is made again).
               const json monopoles = ReadStageFile(P("initial/monopoles.json"));
               const bool same_alpha = e_.initial.guess.alpha == alpha;
               const json q = MeasureQuality(ReadMap(P("initial/map.json")), ReadMap(map_path),
                                             ReadGrid(P("initial/target.qgrid")), set, e_.mesh.iso, alpha,
                                             monopoles.is_object() && same_alpha ? monopoles.value("start", json())
                                                                                 : json(),
                                             qo);
               WriteFileAtomically(dir + "/fidelity.json", q.dump(1) + "\n");
             });
}

// The triptych: the target, the Julia set and the intricate surface rendered alike, with their figures.
void Runner::TriptychStage(const std::vector<std::string>& upstream, const std::string& map_path) {
  const TargetOptions& t = *e_.target;
  // The target mesh is in the user's frame: the panels are comparable when the meshes are too.
  const bool with_target = !t.mesh.empty() && e_.mesh.frame == "user" && e_.intricate.frame == "user";
  std::vector<std::string> files;
  if (with_target) files.push_back(t.mesh);
  const json inputs = {{"pictures", e_.pictures.ToJson()}, {"target", with_target}};
  cache_.Run("triptych", "triptych", inputs, files, upstream, [&](const std::string& dir) {
    const std::string set = P("mesh/julia.ply"), intricate = P("intricate/julia.ply");
    if (!fs::exists(set) && !fs::exists(intricate)) {
      WriteFileAtomically(dir + "/no-triptych.txt", "no triptych: neither the set nor the intricate surface has a mesh\n");
      return;
    }
    json out = RenderTriptych(with_target ? t.mesh : "", fs::exists(set) ? set : "",
                              fs::exists(intricate) ? intricate : "", e_.pictures.render, e_.pictures.triptych_size,
                              dir);
    // The target's own detail, and the intricate surface's fidelity on the lattice the fidelity
    // stage measures the set on (report.md takes the set's and the meshes' detail from their stages).
    const QualityOptions quality;
    json figures = {{"lattice", quality.lattice}, {"closing", mesh::FidelityOptions().closing}};
    const RationalMap map = ReadMap(map_path);
    if (with_target) {
      const mesh::TriangleMesh shape = mesh::ReadMesh(t.mesh);
      figures["target"] = {
          {"triangles", shape.triangles.size()},
          {"detail",
           mesh::MeasureMeshDetail(shape, &shape, (1.0 - 2.0 * map.frame.padding) / map.frame.scale).ToJson()}};
    }
    if (fs::exists(intricate))
      figures["intricate"] = {
          {"fidelity", SetFidelity(map, *IteratedMap(map_path, e_.intricate),
                                   ReadGrid(P("initial/target.qgrid")), e_.intricate, quality.lattice)}};
    out["figures"] = figures;
    WriteFileAtomically(dir + "/triptych.json", out.dump(1) + "\n");
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
  downstream_["modulus"] = {"pictures"};
  std::vector<std::string> files;
  const std::string spec = t.mesh.empty() ? (t.qgrid.empty() ? t.analytic : t.qgrid) : t.mesh;
  if (t.analytic.empty()) files.push_back(spec);
  if (m.versor.poly) files.push_back(*m.versor.poly);
  if (m.params) {
    files.push_back(*m.params);
    ReferencedFiles(ParseJson(ReadFile(*m.params), *m.params), fs::path(*m.params).parent_path(), files);
  }
  const std::string out = "julia." + m.output.format;
  // "report": modulus.json records the map it drew ("map", for `quijibo julia` and the kind
  // `modulus`); a stage cached before it did is made again rather than reused without it.
  const json inputs = {{"target", t.ToJson()}, {"modulus", m.ToJson()}, {"report", "with map"}};
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
  downstream_["portal"] = {"pictures"};
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

void Runner::JuliaSet() {
  const JuliaSetStageOptions& j = e_.julia;
  const bool render = e_.pictures.enabled && j.output.format == "ply";
  total_ = 1 + (render ? 1 : 0);
  downstream_["julia"] = {"pictures"};
  std::vector<std::string> files;
  if (!j.map_file.empty()) {
    files.push_back(j.map_file);
    ReferencedFiles(ParseJson(ReadFile(j.map_file), j.map_file), fs::path(j.map_file).parent_path(), files);
  } else {
    ReferencedFiles(j.map_inline, fs::path(e_.path).parent_path(), files);
  }
  const std::string out = "julia." + j.output.format;
  const std::string hash = cache_.Run("julia", "julia", j.ToJson(), files, {}, [&](const std::string& dir) {
    const JuliaSetStageResult r = pipeline::JuliaSet(j);
    WriteProduct(r.product, dir + "/" + out);
    WriteFileAtomically(dir + "/julia.json", r.report.dump(1) + "\n");
  });
  if (render) RenderStage("julia/julia.ply", hash);
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
  Runner runner(e, out, o, created);
  {
    std::unique_ptr<SignalWatcher> watcher;
    if (o.handle_signals) watcher = std::make_unique<SignalWatcher>([&runner](int signal) { runner.Stop(signal); });
    try {
      if (e.method == "quijibo")
        runner.Quijibo();
      else if (e.method == "modulus")
        runner.Modulus();
      else if (e.method == "portal")
        runner.Portal();
      else
        runner.JuliaSet();
    } catch (const Interrupted& x) {
      const std::string stage = runner.Failed(x.what());
      throw Interrupted("interrupted (" + SignalName(x.signal) + ") in stage " + stage +
                            ": the checkpoint is kept; resume with: " + runner.resume_command(),
                        x.signal);
    } catch (const Error& x) {
      runner.Failed(x.what());
      throw;
    } catch (const std::exception& x) {
      runner.Failed(x.what());
      throw;
    }
    runner.Finished();
  }
  summary.stages = runner.records();
  summary.seconds = runner.Seconds();
  WriteFileAtomically(out + "/experiment.resolved.json", summary.resolved.dump(2) + "\n");
  const json run = runner.RunJson(summary.stages, summary.seconds, nullptr);
  WriteFileAtomically(out + "/run.json", run.dump(1) + "\n");
  if (e.outputs.report) WriteFileAtomically(out + "/report.md", RunReport(e, summary.stages, out, summary.seconds));
  if (e.outputs.report && e.outputs.report_html) try {
      WriteReportHtml(out, RunMeshes(out));
    } catch (const Error& x) {  // the results stand without it
      std::fprintf(stderr, "quijibo: report.html not written: %s\n", x.what());
    }
  // The Quality section's warnings last, where a user reads (with --quiet too: they are warnings).
  if (run.contains("quality"))
    for (const json& w : run["quality"]["warnings"])
      std::fprintf(stderr, "quijibo: quality warning: %s\n", w.get<std::string>().c_str());
  if (!o.quiet) {
    std::fprintf(stderr, "quijibo: done in %s. Results in %s/\n", FormatDuration(summary.seconds).c_str(), out.c_str());
    if (e.outputs.report) std::fprintf(stderr, "quijibo: start with %s/report.md\n", out.c_str());
  }
  return summary;
}

}  // namespace quijibo::pipeline
