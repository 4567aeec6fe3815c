#include "optim/optimizer.h"

#include <algorithm>
#include <csignal>
#include <cstring>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <sstream>
#include <unistd.h>

#include "optim/ceres_backend.h"
#include "optim/checkpoint.h"
#include "optim/jsonl_log.h"
#include "optim/lbfgsb.h"
#include "optim/pass_weights.h"
#include "optim/progress_line.h"
#include "optim/run_state.h"
#include "quijibo/band_energy.h"
#include "quijibo/cached_energy.h"
#include "quijibo/error.h"
#include "quijibo/io.h"

namespace quijibo::optim {

using nlohmann::json;

json OptimizeSummary::ToJson(const OptimizeOptions& o) const {
  json passes = json::array();
  for (const PassSummary& p : this->passes) passes.push_back(p.ToJson());
  json levels_json = json::array();
  for (const Level& l : levels)
    levels_json.push_back({{"scheduled", l.scheduled}, {"resolution", l.resolution}, {"fidelity", l.fidelity}});
  return {{"schedule", o.schedule.ToJson()}, {"evaluator", o.evaluator},
          {"precision", PrecisionName(o.precision)}, {"backend", o.backend},
          {"weights", WeightFieldName(o.weights)},
          {"level_weights", LevelWeightsName(o.level_weights)},
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
  // Each pass's narrow-band work goes to summary.json ("band") and the log's pass_end lines, not
  // here: the table is read on every run, the band statistics rarely.
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
                absolute_start, absolute_end, BestPassName().c_str(),
                complete ? "" : (" (" + stop_reason + ")").c_str());
  s << line;
  return s.str();
}

namespace {

// QUIJIBO_TEST_EXIT_AFTER_STEP (kTestExitCode, optimizer.h), or -1.
long long TestExitStep() {
  static const long long step = [] {
    const char* s = std::getenv("QUIJIBO_TEST_EXIT_AFTER_STEP");
    return s && *s ? std::atoll(s) : -1;
  }();
  return step;
}

// QUIJIBO_TEST_SIGNAL_AFTER_STEP (optimizer.h), or -1.
long long TestSignalStep() {
  static const long long step = [] {
    const char* s = std::getenv("QUIJIBO_TEST_SIGNAL_AFTER_STEP");
    return s && *s ? std::atoll(s) : -1;
  }();
  return step;
}

volatile std::sig_atomic_t g_interrupted = 0;
extern "C" void OnSignal(int sig) { g_interrupted = sig; }  // the signal: never 0

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
  BandObjective(LogLinearEnergy* e, std::shared_ptr<const BandBlocks> blocks) : dense_(e), band_(e, std::move(blocks)) {}
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
            {"far_sweeps", s.far}, {"block_sweeps", s.block_sweeps}, {"blocks", s.blocks},
            {"saturated_blocks", s.saturated_blocks}, {"cached_row_bytes", dense_->cached_row_bytes()},
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

template <class Scalar>
OptimizeSummary Run(const ScalarGrid& sdf, RationalMap& map, const OptimizeOptions& o) {
  using Vector = Eigen::Matrix<Scalar, -1, 1>;
  using Type = IterationSummary::Type;
  namespace fs = std::filesystem;
  std::error_code ec;
  fs::create_directories(o.out_dir, ec);
  if (ec) throw Error(o.out_dir + ": cannot create the output folder: " + ec.message());

  const std::string evaluator = ResolveEvaluator(o.evaluator, o.precision);
  const bool loglinear = evaluator == "band" || evaluator == "dense";
  const Fingerprint fingerprint(o, sdf, map);
  RunState<Scalar> st;
  st.x = map.variables().cast<Scalar>();
  st.best_x = st.x;
  CheckpointPosition start;
  if (o.resume) {
    start = ReadCheckpoint<Scalar>(o.out_dir + "/checkpoint.json", fingerprint, map.variable_count(), st);
    if (start.complete) {
      map.set_variables(st.best_x.template cast<double>());
      st.summary.complete = true;
      st.summary.seconds = st.elapsed_before;
      st.summary.absolute_end = st.best_absolute;
      return st.summary;
    }
  }

  // The observers: the log first, so the others see a record only once it is logged; the
  // caller's callbacks last.
  JsonlLog log(o.out_dir + "/log.jsonl", o.resume ? start.log_bytes : -1);
  ProgressLine progress(o.schedule);
  CheckpointWriter<Scalar> checkpoints(o.out_dir + "/checkpoint.json", fingerprint, o, st, log);
  std::vector<IterationCallback*> observers = {&log, &progress, &checkpoints};
  observers.insert(observers.end(), o.callbacks.begin(), o.callbacks.end());
  bool abort = false;
  auto notify = [&](IterationSummary s) {
    s.step = st.step;
    s.seconds = st.Elapsed();
    for (IterationCallback* observer : observers)
      if ((*observer)(s) == CallbackReturnType::kAbort) abort = true;
  };

  // Unless the passes evaluate densely, the log-linear evaluators are read through bands (the
  // absolute energy's too, where not stored), which need only the rows near the surface.
  LogLinearOptions loglinear_options = o.loglinear();
  loglinear_options.band = evaluator != "dense";
  PassWeights weights(sdf, o.weights, map, o.energy, loglinear_options);
  // The resolution each level runs at (deterministic, so a resumed run finds the same).
  st.summary.levels.clear();
  for (const LevelSpec& level : o.schedule.levels) {
    OptimizeSummary::Level l;
    l.scheduled = level.resolution;
    l.resolution = ResolvedLevelResolution(sdf, weights.finest_weight(), o.weights, level.resolution,
                                           o.level_weights, o.min_level_fidelity, &l.fidelity);
    st.summary.levels.push_back(l);
  }
  if (!o.resume) {
    st.summary.absolute_start = weights.Absolute(st.x.template cast<double>());
    st.best_absolute = st.summary.absolute_start;
    IterationSummary s;
    s.type = Type::kRun;
    s.absolute = st.summary.absolute_start;
    s.run = {{"schedule", o.schedule.notation()}, {"evaluator", evaluator}, {"precision", PrecisionName(o.precision)},
             {"backend", o.backend}, {"weights", WeightFieldName(o.weights)},
             {"roots", {{"top", map.top_count()}, {"bottom", map.bottom_count()}}}};
    notify(s);
  }

  SignalGuard signals;
  bool stopped = false;  // by a signal or a callback
  // A callback's abort on a record other than an iteration takes effect before the next pass.
  auto stop_before = [&](int li, int pj) {
    if (abort) checkpoints.Write(li, pj, 0, st.x, st.x, false);
    return stopped = abort;
  };
  for (int li = start.level_index; li < int(o.schedule.levels.size()) && !stopped; ++li) {
    const int first_pass = li == start.level_index ? start.pass_index : 0;
    if (stop_before(li, first_pass)) break;
    LevelSpec level = o.schedule.levels[li];
    const OptimizeSummary::Level& resolved = st.summary.levels[std::size_t(li)];
    level.resolution = resolved.resolution;
    if (resolved.resolution != resolved.scheduled && first_pass == 0 &&
        !(li == start.level_index && start.iteration > 0)) {
      IterationSummary s;
      s.type = Type::kLevelRaised;
      s.level = resolved.resolution;
      s.level_index = li;
      s.scheduled = resolved.scheduled;
      s.fidelity = resolved.fidelity;
      notify(s);
    }
    const EnergyGrid grid = weights.Level(level.resolution, o.level_weights);
    // At the finest level the log-linear evaluator shares the absolute one's matrix.
    const bool share = loglinear && grid.frame == weights.finest().frame;
    std::unique_ptr<LogLinearEnergy> level_energy;
    std::unique_ptr<Objective<Scalar>> objective;
    if constexpr (std::is_same_v<Scalar, double>) {
      if (loglinear) {
        if (!share) level_energy = std::make_unique<LogLinearEnergy>(map, grid, o.energy, loglinear_options);
        LogLinearEnergy* e = share ? &weights.absolute_evaluator() : level_energy.get();
        if (evaluator == "band")
          objective = std::make_unique<BandObjective>(e, share ? weights.absolute_blocks() : nullptr);
        else objective = std::make_unique<LogLinearObjective>(e);
      }
    }
    if (!objective) objective = std::make_unique<CachedObjective<Scalar>>(map, grid, o.energy);

    for (int pj = first_pass; pj < int(level.passes.size()); ++pj) {
      if (stop_before(li, pj)) break;
      if (pj == 0 && li > 0 && o.level_start == OptimizeOptions::LevelStart::kBest &&
          st.summary.best_pass + 1 != int(st.summary.passes.size())) {
        st.x = st.best_x;
        IterationSummary s;
        s.type = Type::kLevelStart;
        s.level = level.resolution;
        s.level_index = li;
        s.from_pass = st.summary.best_pass;
        s.absolute = st.best_absolute;
        notify(s);
      }
      const PassSpec& spec = level.passes[pj];
      const bool resumed_mid_pass = li == start.level_index && pj == start.pass_index && start.iteration > 0;
      const int first_iteration = resumed_mid_pass ? start.iteration : 0;
      if (!resumed_mid_pass) st.pass_start_x = st.x;
      const auto pass_t0 = std::chrono::steady_clock::now();
      IterationSummary where;
      where.level = level.resolution;
      where.level_index = li;
      where.pass_index = pj;
      where.kind = char(spec.kind);
      if (!resumed_mid_pass) {
        IterationSummary s = where;
        s.type = Type::kPassStart;
        notify(s);
      }
      weights.BeginPass(spec.kind, level.resolution, grid, st.pass_start_x.template cast<double>(),
                        [&](const std::vector<double>& w, double eta) { objective->SetWeights(w, eta); }, share);
      objective->BeginPass();
      const bool variable = spec.kind == PassKind::kVariable;
      const EnergyMode mode = variable ? EnergyMode::kVariable : EnergyMode::kFull;
      if (variable) objective->BeginVariablePass(st.x);
      const int na = variable ? 3 : int(st.x.size());
      Vector xa = st.x.head(na);
      Vector lb = Vector::Zero(na), ub = Vector::Constant(na, std::numeric_limits<Scalar>::infinity());
      lb[0] = -std::numeric_limits<Scalar>::infinity();
      PassSummary ps;
      ps.level = level.resolution;
      ps.level_index = li;
      ps.pass_index = pj;
      ps.kind = char(spec.kind);
      bool first_eval = true;
      // A resumed pass evaluates its start point once more than the uninterrupted one did.
      const int evaluation_offset = resumed_mid_pass ? st.pass_evaluations - 1 : 0;
      if (resumed_mid_pass) ps.energy_start = st.pass_energy_start, first_eval = false;
      Vector full = st.x;
      st.live = &full;
      st.active = na;
      // Evaluate.
      auto f = [&](const Vector& y, Vector& g) -> Scalar {
        full.head(na) = y;
        const Evaluation<Scalar> ev = objective->Evaluate(full, mode);
        g = ev.gradient.head(na);
        ps.overflowed_cells = std::max<long long>(ps.overflowed_cells, ev.counts.overflowed);
        if (first_eval) ps.energy_start = ToDouble(ev.energy), first_eval = false;
        return ev.energy;
      };
      // Step (the minimizer), then notify.
      auto on_iteration = [&](int it, int evals, const Scalar& fx, const Scalar& pg) {
        ++st.step;
        st.pass_energy_start = ps.energy_start;
        st.pass_evaluations = evals + evaluation_offset;
        IterationSummary s = where;
        s.type = Type::kIteration;
        s.iteration = it;
        s.evaluations = st.pass_evaluations;
        s.energy = ToDouble(fx);
        s.projected_gradient_norm = ToDouble(pg);
        notify(s);
        if (it % o.absolute_every == 0) {
          IterationSummary a = where;
          a.type = Type::kAbsolute;
          a.iteration = it;
          a.energy = weights.Absolute(st.Current().template cast<double>());
          notify(a);
        }
        IterationAction action = IterationAction::kContinue;
        if (st.step == TestSignalStep()) std::raise(SIGINT);  // a Ctrl-C, handled before raise returns
        if (g_interrupted || abort) {
          checkpoints.Write(li, pj, it, st.Current(), st.pass_start_x, false);
          action = IterationAction::kStop;
        } else if (it % o.checkpoint_every == 0) {
          action = IterationAction::kRestartMemory;  // the checkpoint writer wrote this state
        }
        if (st.step == TestExitStep()) _exit(kTestExitCode);  // a crash after this step's log and checkpoint
        return action;
      };
      LbfgsbOptions<Scalar> lo;
      lo.memory = o.memory;
      lo.max_iterations = spec.max_iterations;
      lo.tolerance = Scalar(spec.tolerance);
      LbfgsbResult<Scalar> res;
      if constexpr (std::is_same_v<Scalar, double>) {
        if (o.backend == "ceres")
          res = MinimizeCeres(f, xa, lb, lo, on_iteration, first_iteration);
        else
          res = MinimizeBounded<Scalar>(f, xa, lb, ub, lo, on_iteration, first_iteration);
      } else {
        res = MinimizeBounded<Scalar>(f, xa, lb, ub, lo, on_iteration, first_iteration);
      }
      st.live = nullptr;
      weights.EndPass();
      st.x.head(na) = xa;
      if (res.stop == StopReason::kInterrupted) {
        stopped = true;
        break;
      }
      ps.stop = StopReasonName(res.stop);
      ps.message = res.message;
      ps.line_search_restarts = res.line_search_restarts;
      ps.iterations = res.iterations;
      ps.evaluations = res.evaluations + evaluation_offset;
      ps.energy_end = ToDouble(res.f);
      // Before the absolute energy, which changes a shared evaluator's weights.
      ps.band = objective->PassReport(st.x, mode, res.f);
      ps.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - pass_t0).count();
      ps.absolute_end = weights.Absolute(st.x.template cast<double>());
      ps.stalled = ps.iterations == 0;
      if (ps.absolute_end < st.best_absolute) {
        st.best_absolute = ps.absolute_end;
        st.best_x = st.x;
        st.summary.best_pass = int(st.summary.passes.size());
      }
      st.summary.passes.push_back(ps);
      IterationSummary s = where;
      s.type = Type::kPassEnd;
      s.pass = ps;
      notify(s);  // the checkpoint writer records the next pass as the place to continue
    }
    if (!stopped) {
      RationalMap level_map = map;
      level_map.set_variables(st.x.template cast<double>());
      WriteMap(o.out_dir + "/map_level_" + std::to_string(level.resolution) + ".json", level_map);
    }
  }
  map.set_variables(st.best_x.template cast<double>());
  st.summary.complete = !stopped;
  if (stopped) st.summary.stop_reason = g_interrupted ? "interrupted" : "aborted by a callback";
  if (stopped) st.summary.signal = int(g_interrupted);
  st.summary.seconds = st.Elapsed();
  st.summary.absolute_end = st.best_absolute;
  WriteFileAtomically(o.out_dir + "/summary.json", st.summary.ToJson(o).dump(1) + "\n");
  return st.summary;
}

}  // namespace

OptimizeSummary Optimize(const ScalarGrid& sdf, RationalMap& map, const OptimizeOptions& options) {
  if (auto why = options.Validate(); !why.empty()) throw Error("optimize: " + why);
  if (options.out_dir.empty()) throw Error("optimize: an output folder is required");
  if (auto why = map.validate(); !why.empty()) throw Error("optimize: map: " + why);
  return DispatchPrecision(options.precision, [&]<class Real>() { return Run<Real>(sdf, map, options); });
}

}  // namespace quijibo::optim
