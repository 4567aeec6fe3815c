#include "optim/optimizer.h"

#include <algorithm>
#include <cerrno>
#include <csignal>
#include <cstring>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <unistd.h>

#include "optim/ceres_backend.h"
#include "optim/lbfgsb.h"
#include "optim/reweight.h"
#include "quijibo/band_energy.h"
#include "quijibo/cached_energy.h"
#include "quijibo/error.h"
#include "quijibo/io.h"
#include "quijibo/json_reader.h"
#include "quijibo/progress.h"

namespace quijibo {

using nlohmann::json;

std::string StopReasonName(StopReason r) {
  switch (r) {
    case StopReason::kTolerance: return "tolerance";
    case StopReason::kLineSearch: return "line-search";
    case StopReason::kMaxIterations: return "max-iterations";
    case StopReason::kInterrupted: return "interrupted";
    case StopReason::kNonFinite: return "non-finite";
  }
  return "?";
}

OptimizeOptions::LevelStart ParseLevelStart(const std::string& name) {
  if (name == "best") return OptimizeOptions::LevelStart::kBest;
  if (name == "last") return OptimizeOptions::LevelStart::kLast;
  throw Error("unknown level start \"" + name + "\" (expected best or last)");
}

std::string LevelStartName(OptimizeOptions::LevelStart s) {
  return s == OptimizeOptions::LevelStart::kBest ? "best" : "last";
}

std::string ResolveEvaluator(const std::string& name, Precision precision) {
  if (name == "auto") return precision == Precision::kDouble ? "band" : "cached";
  if (name == "loglinear") return "dense";
  if (name == "band" || name == "dense" || name == "cached") return name;
  throw Error("unknown evaluator \"" + name + "\": expected auto, band, dense (loglinear) or cached");
}

std::string OptimizeOptions::validate() const {
  if (auto why = schedule.validate(); !why.empty()) return why;
  if (std::find(kEvaluatorNames.begin(), kEvaluatorNames.end(), evaluator) == kEvaluatorNames.end())
    return "evaluator must be auto, band, dense (loglinear) or cached";
  if (ResolveEvaluator(evaluator, precision) != "cached" && precision != Precision::kDouble)
    return "the loglinear evaluator (band or dense) runs in double only";
  if (backend != "lbfgspp" && backend != "ceres")
    return "unknown back end \"" + backend + "\" (available: lbfgspp, ceres)";
  if (backend == "ceres" && precision != Precision::kDouble) return "the ceres back end runs in double only";
  if (memory < 1 || memory > 100) return "memory must be in [1, 100]";
  if (absolute_every < 1) return "absolute_every must be >= 1";
  if (!(min_level_fidelity >= 0 && min_level_fidelity <= 1))
    return "min_level_fidelity must be in [0, 1], found " + std::to_string(min_level_fidelity);
  if (checkpoint_every < 1) return "checkpoint_every must be >= 1";
  if (out_dir.empty()) return "an output folder is required";
  if (auto why = energy.validate(); !why.empty()) return why;
  return {};
}

json PassSummary::ToJson() const {
  return {{"level", level}, {"level_index", level_index}, {"pass_index", pass_index},
          {"pass", std::string(1, kind)}, {"stop", stop}, {"iterations", iterations},
          {"evaluations", evaluations}, {"seconds", seconds}, {"energy_start", energy_start},
          {"energy_end", energy_end}, {"absolute_end", absolute_end},
          {"overflowed_cells", overflowed_cells}, {"message", message},
          {"line_search_restarts", line_search_restarts}, {"stalled", stalled},
          {"stall_reason", stalled ? StallReason() : std::string()}, {"band", band}};
}

std::string PassSummary::StallReason() const {
  if (stop == "line-search")
    return "the line search failed at the first step" + (message.empty() ? std::string() : " (" + message + ")");
  if (stop == "tolerance") return "the projected gradient was below the tolerance at the start";
  if (stop == "non-finite") return "the energy or its gradient was not finite at the start";
  if (stop == "max-iterations") return "the iteration cap was reached before the pass began";
  return stop;
}

PassSummary PassSummary::FromJson(const json& j) {
  PassSummary p;
  p.level = j.at("level");
  p.level_index = j.at("level_index");
  p.pass_index = j.at("pass_index");
  p.kind = j.at("pass").get<std::string>()[0];
  p.stop = j.at("stop");
  p.iterations = j.at("iterations");
  p.evaluations = j.at("evaluations");
  p.seconds = j.at("seconds");
  p.energy_start = j.at("energy_start");
  p.energy_end = j.at("energy_end");
  p.absolute_end = j.at("absolute_end");
  p.overflowed_cells = j.at("overflowed_cells");
  p.message = j.value("message", "");
  p.line_search_restarts = j.value("line_search_restarts", 0);
  p.stalled = j.value("stalled", p.iterations == 0);
  if (j.contains("band")) p.band = j.at("band");
  return p;
}

json OptimizeSummary::ToJson(const OptimizeOptions& o) const {
  json passes = json::array();
  for (const PassSummary& p : this->passes) passes.push_back(p.ToJson());
  json levels_json = json::array();
  for (const Level& l : levels)
    levels_json.push_back({{"scheduled", l.scheduled}, {"resolution", l.resolution}, {"fidelity", l.fidelity}});
  return {{"schedule", o.schedule.ToJson()}, {"evaluator", o.evaluator},
          {"precision", PrecisionName(o.precision)}, {"backend", o.backend},
          {"weights", WeightFieldName(o.weights)},
          {"level_weights", o.level_weights == LevelWeights::kSampleFinest ? "sample" : "recompute"},
          {"level_start", LevelStartName(o.level_start)}, {"min_level_fidelity", o.min_level_fidelity},
          {"levels", levels_json},
          {"alpha", o.energy.alpha}, {"memory", o.memory}, {"complete", complete},
          {"seconds", seconds}, {"absolute_start", absolute_start}, {"absolute_end", absolute_end},
          {"best_pass", best_pass}, {"passes", passes}};
}

std::string OptimizeSummary::BestPassName() const {
  if (best_pass < 0 || best_pass >= int(passes.size())) return "the start map: no pass improved on it";
  const PassSummary& p = passes[std::size_t(best_pass)];
  return "the map after level " + std::to_string(p.level) + " pass " + std::string(1, p.kind) + " (pass " +
         std::to_string(best_pass + 1) + " of " + std::to_string(passes.size()) + ")";
}

std::string OptimizeSummary::Report() const {
  std::ostringstream s;
  char line[256];
  s << "level pass  stop            iters  evals   seconds   energy start -> end      absolute\n";
  for (std::size_t k = 0; k < passes.size(); ++k) {
    const PassSummary& p = passes[k];
    std::snprintf(line, sizeof line, "%5d  %c    %-14s %6d %6d %9.2f   %+.6f -> %+.6f   %+.6f%s%s\n", p.level,
                  p.kind, p.stop.c_str(), p.iterations, p.evaluations, p.seconds, p.energy_start,
                  p.energy_end, p.absolute_end, int(k) == best_pass ? "  best" : "",
                  p.stalled ? "  STALLED" : "");
    s << line;
  }
  for (const PassSummary& p : passes)
    if (p.band.is_object()) {
      std::snprintf(line, sizeof line,
                    "band: level %d pass %c: %.1f %% of the dense work (%.2f %% of %lld cells per band "
                    "evaluation, %lld anchors), energy error vs dense %.1e\n",
                    p.level, p.kind, 100.0 * p.band.value("work_fraction", 0.0),
                    100.0 * p.band.value("mean_fraction", 0.0), p.band.value("cells", 0LL),
                    p.band.value("anchors", 0LL), p.band.value("energy_error", 0.0));
      s << line;
    }
  for (const Level& l : levels)
    if (l.resolution != l.scheduled) {
      std::snprintf(line, sizeof line,
                    "level %d ran at %d: at %d^3 the target is not represented (level fidelity below the "
                    "minimum); at %d^3 its fidelity is %.3f\n",
                    l.scheduled, l.resolution, l.scheduled, l.resolution, l.fidelity);
      s << line;
    }
  for (const PassSummary& p : passes)
    if (p.stalled)
      s << "stalled: level " << p.level << " pass " << p.kind << " (pass " << p.pass_index + 1
        << " of the level) made no iteration: " << p.StallReason() << "\n";
  std::snprintf(line, sizeof line, "total %.1f s; absolute energy %+.6f -> %+.6f (%s)%s\n", seconds,
                absolute_start, absolute_end, BestPassName().c_str(), complete ? "" : " (interrupted)");
  s << line;
  return s.str();
}

namespace {

// For kill-and-resume tests that do not depend on timing: QUIJIBO_TEST_EXIT_AFTER_STEP=k ends the
// process at once (_exit, as a crash: no summary, no destructors) right after step k is logged and,
// when k is a checkpoint, checkpointed. Steps count iterations over the whole run from 1.
constexpr int kTestExitCode = 86;
long long TestExitStep() {
  static const long long step = [] {
    const char* s = std::getenv("QUIJIBO_TEST_EXIT_AFTER_STEP");
    return s && *s ? std::atoll(s) : -1;
  }();
  return step;
}

volatile std::sig_atomic_t g_interrupted = 0;
extern "C" void OnSignal(int) { g_interrupted = 1; }

// Installs the SIGINT/SIGTERM handlers for the life of the optimization.
class SignalGuard {
 public:
  SignalGuard() {
    g_interrupted = 0;
    struct sigaction sa {};
    sa.sa_handler = OnSignal;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, &old_int_);
    sigaction(SIGTERM, &sa, &old_term_);
  }
  ~SignalGuard() {
    sigaction(SIGINT, &old_int_, nullptr);
    sigaction(SIGTERM, &old_term_, nullptr);
  }

 private:
  struct sigaction old_int_ {}, old_term_ {};
};

template <class Scalar>
std::string Exact(const Scalar& x) {
  std::ostringstream s;
  s.precision(std::numeric_limits<Scalar>::max_digits10);
  s << x;
  return s.str();
}

template <class Scalar>
Scalar ParseScalar(const std::string& s) {
  if constexpr (std::is_same_v<Scalar, float128>) return float128(s);
  else if constexpr (std::is_same_v<Scalar, long double>) return std::strtold(s.c_str(), nullptr);
  else if constexpr (std::is_same_v<Scalar, float>) return std::strtof(s.c_str(), nullptr);
  else return std::strtod(s.c_str(), nullptr);
}

// The energy over all R + 3 variables, whichever evaluator computes it.
template <class Scalar>
class Objective {
 public:
  using Vector = Eigen::Matrix<Scalar, -1, 1>;
  virtual ~Objective() = default;
  virtual Evaluation<Scalar> Evaluate(const Vector& x, EnergyMode mode) = 0;
  virtual void BeginVariablePass(const Vector& x) = 0;
  virtual void SetWeights(const std::vector<double>& w, double eta) = 0;
  virtual void BeginPass() {}
  // What the pass's end adds to its summary (the band's statistics), given x and the energy the
  // pass ended with.
  virtual nlohmann::json PassReport(const Vector&, EnergyMode, Scalar) { return nullptr; }
};

class LogLinearObjective : public Objective<double> {
 public:
  explicit LogLinearObjective(LogLinearEnergy* e) : e_(e) {}
  Evaluation<double> Evaluate(const Eigen::VectorXd& x, EnergyMode mode) override { return e_->Evaluate(x, mode); }
  void BeginVariablePass(const Eigen::VectorXd& x) override { e_->BeginVariablePass(x); }
  void SetWeights(const std::vector<double>& w, double eta) override { e_->SetWeights(w, eta); }

 private:
  LogLinearEnergy* e_;
};

// The narrow band (band_energy.h) over a dense evaluator's matrix; at every pass's end the
// energy is compared with the dense one.
class BandObjective : public Objective<double> {
 public:
  explicit BandObjective(LogLinearEnergy* e) : dense_(e), band_(e) {}
  Evaluation<double> Evaluate(const Eigen::VectorXd& x, EnergyMode mode) override { return band_.Evaluate(x, mode); }
  void BeginVariablePass(const Eigen::VectorXd& x) override { dense_->BeginVariablePass(x); }
  void SetWeights(const std::vector<double>& w, double eta) override { dense_->SetWeights(w, eta); }
  void BeginPass() override {
    band_.Invalidate();
    band_.ResetStats();
  }
  json PassReport(const Eigen::VectorXd& x, EnergyMode mode, double energy) override {
    const double dense = dense_->Evaluate(x, mode, false).energy;
    const BandStats& s = band_.stats();
    return {{"cells", s.cells}, {"band_cells", s.band_cells}, {"mean_fraction", s.mean_fraction()},
            {"work_fraction", s.work_fraction()}, {"max_cells", s.max_exact}, {"evaluations", s.evaluations},
            {"anchors", s.anchors}, {"anchors_reach", s.anchors_reach}, {"anchors_work", s.anchors_work},
            {"far_sweeps", s.far},
            {"dense_fallbacks", s.dense_fallbacks}, {"energy_dense", dense},
            {"energy_error", std::fabs(energy - dense) / std::max(1e-300, std::fabs(dense))}};
  }

 private:
  LogLinearEnergy* dense_;
  BandEnergy band_;
};

template <class Scalar>
class CachedObjective : public Objective<Scalar> {
 public:
  using Vector = Eigen::Matrix<Scalar, -1, 1>;
  CachedObjective(const RationalMap& map, const EnergyGrid& grid, const EnergyOptions& o) : e_(map, grid, o) {}
  Evaluation<Scalar> Evaluate(const Vector& x, EnergyMode mode) override { return e_.Evaluate(x, mode); }
  void BeginVariablePass(const Vector&) override {}
  void SetWeights(const std::vector<double>& w, double eta) override { e_.SetWeights(w, eta); }

 private:
  CachedEnergy<Scalar> e_;
};

struct Paths {
  std::string dir, log, checkpoint, summary, map;
};

template <class Scalar>
OptimizeSummary Run(const ScalarGrid& sdf, RationalMap& map, const OptimizeOptions& o) {
  using Vector = Eigen::Matrix<Scalar, -1, 1>;
  const auto t0 = std::chrono::steady_clock::now();
  namespace fs = std::filesystem;
  Paths paths{o.out_dir, o.out_dir + "/log.jsonl", o.out_dir + "/checkpoint.json", o.out_dir + "/summary.json",
              o.out_dir + "/map.json"};
  std::error_code ec;
  fs::create_directories(o.out_dir, ec);
  if (ec) throw Error(o.out_dir + ": cannot create the output folder: " + ec.message());

  const std::string evaluator = ResolveEvaluator(o.evaluator, o.precision);
  const bool loglinear = evaluator == "band" || evaluator == "dense";
  const std::string fingerprint = o.schedule.notation() + "|" + o.evaluator + "|" + PrecisionName(o.precision) +
                                  "|" + WeightFieldName(o.weights) + "|" + std::to_string(map.top_count()) + "/" +
                                  std::to_string(map.bottom_count());
  // State: where we are and x.
  OptimizeSummary summary;
  int start_level = 0, start_pass = 0, start_iteration = 0;
  long long step = 0;
  double elapsed_before = 0;
  Vector x = map.variables().cast<Scalar>();
  Vector pass_start_x;
  // The result: the lowest absolute energy seen at the start and at pass ends.
  Vector best_x = x;
  double best_absolute = 0;
  // The pass in progress at a checkpoint: its start energy and evaluations so far, so that a
  // resumed pass reports what the uninterrupted one does.
  double pass_energy_start = 0;
  int pass_evaluations = 0;
  if (o.resume) {
    const std::string text = ReadFile(paths.checkpoint);
    const json c = ParseJson(text, paths.checkpoint);
    JsonReader r(c, paths.checkpoint);
    if (r.string("/format") != "quijibo-checkpoint") r.fail("/format", "not a quijibo checkpoint");
    if (r.string("/fingerprint") != fingerprint)
      r.fail("/fingerprint", "the checkpoint was made by a different run (" + r.string("/fingerprint") +
                                 "; this run is " + fingerprint + ")");
    start_level = int(r.integer("/level_index"));
    start_pass = int(r.integer("/pass_index"));
    start_iteration = int(r.integer("/iteration"));
    step = r.integer("/step");
    elapsed_before = r.number("/elapsed_seconds");
    summary.absolute_start = r.number("/absolute_start");
    pass_energy_start = c.value("pass_energy_start", 0.0);
    pass_evaluations = c.value("pass_evaluations", 0);
    auto read_vec = [&](const char* key) {
      const json& a = c.at(key);
      Vector v(Eigen::Index(a.size()));
      for (std::size_t k = 0; k < a.size(); ++k) v[Eigen::Index(k)] = ParseScalar<Scalar>(a[k].get<std::string>());
      return v;
    };
    x = read_vec("x");
    pass_start_x = read_vec("pass_start_x");
    if (x.size() != map.variable_count()) r.fail("/x", "does not match the map's variable count");
    for (const json& p : c.at("passes")) summary.passes.push_back(PassSummary::FromJson(p));
    // A checkpoint without the best map (an older version) counts only the start map, which is
    // `map` on resume.
    best_absolute = summary.absolute_start;
    if (c.contains("best_x")) {
      best_x = read_vec("best_x");
      if (best_x.size() != x.size()) r.fail("/best_x", "does not match the map's variable count");
      best_absolute = r.number("/best_absolute");
      summary.best_pass = int(r.integer("/best_pass"));
    }
    if (c.value("complete", false)) {
      map.set_variables(best_x.template cast<double>());
      summary.complete = true;
      summary.seconds = elapsed_before;
      summary.absolute_end = best_absolute;
      return summary;
    }
    // Drop log lines written after the checkpoint: the resumed run writes them again.
    const long long log_bytes = r.integer("/log_bytes");
    if (fs::exists(paths.log) && std::int64_t(fs::file_size(paths.log)) > log_bytes)
      fs::resize_file(paths.log, std::uintmax_t(log_bytes));
  } else {
    WriteFileAtomically(paths.log, "");
  }
  std::ofstream log(paths.log, std::ios::app);
  if (!log) throw Error(paths.log + ": cannot write");
  auto elapsed = [&] {
    return elapsed_before + std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  };
  auto emit = [&](json line) {
    line["seconds"] = elapsed();
    errno = 0;
    log << line.dump() << "\n";
    log.flush();
    if (!log) throw Error(paths.log + ": cannot write: " + (errno ? std::strerror(errno) : "disk full?"));
  };

  // The finest grid with the original weights: the absolute energy and the reweighting.
  const std::vector<double> finest_w = ComputeWeights(sdf, o.weights);
  EnergyGrid finest = MakeEnergyGrid(sdf, finest_w, o.weights, 0, LevelWeights::kSampleFinest, 0.0);
  // The resolution each level runs at (deterministic, so a resumed run finds the same).
  summary.levels.clear();
  for (const LevelSpec& level : o.schedule.levels) {
    OptimizeSummary::Level l;
    l.scheduled = level.resolution;
    l.resolution = ResolvedLevelResolution(sdf, finest_w, o.weights, level.resolution, o.level_weights,
                                           o.min_level_fidelity, &l.fidelity);
    summary.levels.push_back(l);
  }
  LogLinearEnergy absolute(map, finest, o.energy, o.loglinear);
  auto absolute_energy = [&](const Vector& xs) {
    absolute.SetWeights(finest.weight, finest.eta);
    return absolute.Evaluate(xs.template cast<double>(), EnergyMode::kFull, false).energy;
  };
  if (!o.resume) {
    summary.absolute_start = absolute_energy(x);
    best_absolute = summary.absolute_start;
    emit({{"type", "run"}, {"schedule", o.schedule.notation()}, {"evaluator", evaluator},
          {"precision", PrecisionName(o.precision)}, {"backend", o.backend}, {"weights", WeightFieldName(o.weights)},
          {"roots", {{"top", map.top_count()}, {"bottom", map.bottom_count()}}}, {"step", 0},
          {"absolute_energy", summary.absolute_start}});
  }

  auto write_checkpoint = [&](int level_index, int pass_index, int iteration, const Vector& xs,
                              const Vector& pass_start, bool complete) {
    log.flush();
    json c;
    c["format"] = "quijibo-checkpoint";
    c["version"] = 2;
    c["fingerprint"] = fingerprint;
    c["complete"] = complete;
    c["level_index"] = level_index;
    c["pass_index"] = pass_index;
    c["iteration"] = iteration;
    c["step"] = step;
    c["log_bytes"] = (long long)fs::file_size(paths.log);
    c["elapsed_seconds"] = elapsed();
    c["absolute_start"] = summary.absolute_start;
    c["pass_energy_start"] = pass_energy_start;
    c["pass_evaluations"] = pass_evaluations;
    json xv = json::array(), pv = json::array();
    for (Eigen::Index k = 0; k < xs.size(); ++k) xv.push_back(Exact(xs[k]));
    for (Eigen::Index k = 0; k < pass_start.size(); ++k) pv.push_back(Exact(pass_start[k]));
    c["x"] = xv;
    c["pass_start_x"] = pv;
    json bv = json::array();
    for (Eigen::Index k = 0; k < best_x.size(); ++k) bv.push_back(Exact(best_x[k]));
    c["best_x"] = bv;
    c["best_absolute"] = best_absolute;
    c["best_pass"] = summary.best_pass;
    json passes = json::array();
    for (const PassSummary& p : summary.passes) passes.push_back(p.ToJson());
    c["passes"] = passes;
    WriteFileAtomically(paths.checkpoint, c.dump() + "\n");
  };

  SignalGuard signals;
  bool interrupted = false;
  for (int li = start_level; li < int(o.schedule.levels.size()) && !interrupted; ++li) {
    LevelSpec level = o.schedule.levels[li];
    level.resolution = summary.levels[std::size_t(li)].resolution;
    const EnergyGrid grid = MakeEnergyGrid(sdf, finest_w, o.weights, level.resolution, o.level_weights, 0.0);
    // At the finest level the log-linear evaluator shares the absolute one's matrix.
    const bool share = loglinear && grid.frame == finest.frame;
    std::unique_ptr<LogLinearEnergy> level_energy;
    std::unique_ptr<Objective<Scalar>> objective;
    if constexpr (std::is_same_v<Scalar, double>) {
      if (loglinear) {
        if (!share) level_energy = std::make_unique<LogLinearEnergy>(map, grid, o.energy, o.loglinear);
        LogLinearEnergy* e = share ? &absolute : level_energy.get();
        if (evaluator == "band") objective = std::make_unique<BandObjective>(e);
        else objective = std::make_unique<LogLinearObjective>(e);
      }
    }
    if (!objective) objective = std::make_unique<CachedObjective<Scalar>>(map, grid, o.energy);

    const int first_pass = li == start_level ? start_pass : 0;
    const OptimizeSummary::Level& raised = summary.levels[std::size_t(li)];
    if (raised.resolution != raised.scheduled && !(li == start_level && (start_pass > 0 || start_iteration > 0)))
      emit({{"type", "level_raised"}, {"level_index", li}, {"scheduled", raised.scheduled},
            {"level", raised.resolution}, {"fidelity", raised.fidelity}, {"step", step}});
    if (o.level_start == OptimizeOptions::LevelStart::kBest && li > 0 && first_pass == 0 &&
        summary.best_pass + 1 != int(summary.passes.size())) {
      x = best_x;
      emit({{"type", "level_start"}, {"level", level.resolution}, {"level_index", li}, {"step", step},
            {"from_pass", summary.best_pass}, {"absolute", best_absolute}});
    }
    for (int pj = first_pass; pj < int(level.passes.size()); ++pj) {
      const PassSpec& spec = level.passes[pj];
      const bool resumed_mid_pass = li == start_level && pj == start_pass && start_iteration > 0;
      const int first_iteration = resumed_mid_pass ? start_iteration : 0;
      if (!resumed_mid_pass) pass_start_x = x;
      const auto pass_t0 = std::chrono::steady_clock::now();
      const json where = {{"level", level.resolution}, {"level_index", li}, {"pass", std::string(1, char(spec.kind))},
                          {"pass_index", pj}};
      if (!resumed_mid_pass) {
        json line = where;
        line["type"] = "pass_start";
        line["step"] = step;
        emit(line);
      }
      // Weights of this pass: the level's, or for R the reweighted field of the pass's start map.
      EnergyGrid rgrid;
      if (spec.kind == PassKind::kReweighted) {
        const std::vector<double> rw =
            ReweightedWeights(sdf, finest_w, absolute.LogModulus(pass_start_x.template cast<double>()));
        rgrid = MakeEnergyGrid(sdf, rw, o.weights, level.resolution, LevelWeights::kSampleFinest, 0.0);
      }
      const EnergyGrid& pass_grid = spec.kind == PassKind::kReweighted ? rgrid : grid;
      objective->SetWeights(pass_grid.weight, pass_grid.eta);
      objective->BeginPass();
      const bool variable = spec.kind == PassKind::kVariable;
      const EnergyMode mode = variable ? EnergyMode::kVariable : EnergyMode::kFull;
      if (variable) objective->BeginVariablePass(x);
      const int na = variable ? 3 : int(x.size());
      Vector xa = x.head(na);
      Vector lb = Vector::Zero(na), ub = Vector::Constant(na, std::numeric_limits<Scalar>::infinity());
      lb[0] = -std::numeric_limits<Scalar>::infinity();
      PassSummary ps;
      ps.level = level.resolution;
      ps.level_index = li;
      ps.pass_index = pj;
      ps.kind = char(spec.kind);
      bool first_eval = true;
      // A resumed pass evaluates its start point once more than the uninterrupted one did.
      const int evaluation_offset = resumed_mid_pass ? pass_evaluations - 1 : 0;
      if (resumed_mid_pass) ps.energy_start = pass_energy_start, first_eval = false;
      Vector full = x;
      auto f = [&](const Vector& y, Vector& g) -> Scalar {
        full.head(na) = y;
        const Evaluation<Scalar> ev = objective->Evaluate(full, mode);
        g = ev.gradient.head(na);
        ps.overflowed_cells = std::max<long long>(ps.overflowed_cells, ev.counts.overflowed);
        if (first_eval) ps.energy_start = ToDouble(ev.energy), first_eval = false;
        return ev.energy;
      };
      Progress progress("level " + std::to_string(level.resolution) + " pass " + std::string(1, char(spec.kind)),
                        spec.max_iterations, false);
      auto iterate = [&](int it, int evals, const Scalar& fx, const Scalar& pg) {
        ++step;
        pass_energy_start = ps.energy_start;
        pass_evaluations = evals + evaluation_offset;
        json line = where;
        line["type"] = "iteration";
        line["step"] = step;
        line["iteration"] = it;
        line["evaluations"] = pass_evaluations;
        line["energy"] = ToDouble(fx);
        line["projected_gradient"] = ToDouble(pg);
        emit(line);
        progress.update(it, "psi " + std::to_string(ToDouble(fx)));
        if (it % o.absolute_every == 0) {
          Vector cur = x;
          cur.head(na) = full.head(na);
          json a = where;
          a["type"] = "absolute";
          a["step"] = step;
          a["iteration"] = it;
          a["energy"] = absolute_energy(cur);
          emit(a);
          // The shared evaluator now holds the original weights: give it this pass's back.
          if (share) objective->SetWeights(pass_grid.weight, pass_grid.eta);
        }
        if (g_interrupted) {
          Vector cur = x;
          cur.head(na) = full.head(na);
          write_checkpoint(li, pj, it, cur, pass_start_x, false);
          return IterationAction::kStop;
        }
        if (it % o.checkpoint_every == 0) {
          Vector cur = x;
          cur.head(na) = full.head(na);
          write_checkpoint(li, pj, it, cur, pass_start_x, false);
          return IterationAction::kRestartMemory;
        }
        return IterationAction::kContinue;
      };
      auto callback = [&](int it, int evals, const Scalar& fx, const Scalar& pg) {
        const IterationAction a = iterate(it, evals, fx, pg);
        if (step == TestExitStep()) _exit(kTestExitCode);  // a crash after this step's log and checkpoint
        return a;
      };
      LbfgsbOptions<Scalar> lo;
      lo.memory = o.memory;
      lo.max_iterations = spec.max_iterations;
      lo.tolerance = Scalar(spec.tolerance);
      LbfgsbResult<Scalar> res;
      if constexpr (std::is_same_v<Scalar, double>) {
        if (o.backend == "ceres")
          res = MinimizeCeres(f, xa, lb, lo, callback, first_iteration);
        else
          res = MinimizeBounded<Scalar>(f, xa, lb, ub, lo, callback, first_iteration);
      } else {
        res = MinimizeBounded<Scalar>(f, xa, lb, ub, lo, callback, first_iteration);
      }
      progress.finish();
      x.head(na) = xa;
      if (res.stop == StopReason::kInterrupted) {
        interrupted = true;
        break;
      }
      ps.stop = StopReasonName(res.stop);
      ps.message = res.message;
      ps.line_search_restarts = res.line_search_restarts;
      ps.iterations = res.iterations;
      ps.evaluations = res.evaluations + evaluation_offset;
      ps.energy_end = ToDouble(res.f);
      // Before absolute_energy, which changes a shared evaluator's weights.
      ps.band = objective->PassReport(x, mode, res.f);
      ps.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - pass_t0).count();
      ps.absolute_end = absolute_energy(x);
      ps.stalled = ps.iterations == 0;
      if (ps.absolute_end < best_absolute) {
        best_absolute = ps.absolute_end;
        best_x = x;
        summary.best_pass = int(summary.passes.size());
      }
      summary.passes.push_back(ps);
      json line = ps.ToJson();
      line["type"] = "pass_end";
      line["step"] = step;
      emit(line);
      const bool last = li + 1 == int(o.schedule.levels.size()) && pj + 1 == int(level.passes.size());
      const bool next_level = pj + 1 == int(level.passes.size());
      write_checkpoint(next_level ? li + 1 : li, next_level ? 0 : pj + 1, 0, x, x, last);
    }
    if (!interrupted) {
      RationalMap level_map = map;
      level_map.set_variables(x.template cast<double>());
      WriteMap(o.out_dir + "/map_level_" + std::to_string(level.resolution) + ".json", level_map);
    }
  }
  map.set_variables(best_x.template cast<double>());
  summary.complete = !interrupted;
  summary.seconds = elapsed();
  summary.absolute_end = best_absolute;
  WriteFileAtomically(paths.summary, summary.ToJson(o).dump(1) + "\n");
  return summary;
}

}  // namespace

OptimizeSummary Optimize(const ScalarGrid& sdf, RationalMap& map, const OptimizeOptions& options) {
  if (auto why = options.validate(); !why.empty()) throw Error("optimize: " + why);
  if (auto why = map.validate(); !why.empty()) throw Error("optimize: map: " + why);
  return DispatchPrecision(options.precision, [&]<class Real>() { return Run<Real>(sdf, map, options); });
}

}  // namespace quijibo
