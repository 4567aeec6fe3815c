#include "optim/optimizer.h"

#include <algorithm>
#include <csignal>
#include <cstring>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <optional>
#include <sstream>
#include <unistd.h>

#include "optim/ceres_backend.h"
#include "optim/checkpoint.h"
#include "optim/jsonl_log.h"
#include "optim/level_objective.h"
#include "optim/lbfgsb.h"
#include "optim/pass_weights.h"
#include "optim/progress_line.h"
#include "optim/run_state.h"
#include "util/error.h"
#include "util/io.h"
#include "util/signals.h"

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
          {"between_nodes", AutoSwitchName(o.between_nodes)}, {"between_nodes_on", between_nodes},
          {"keep", KeepName(o.keep)}, {"iou_tolerance", o.iou_tolerance}, {"iou_start", iou_start},
          {"iou_end", iou_end}, {"lowest_psi_pass", lowest_psi_pass}, {"lowest_psi", lowest_psi},
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
  s << "level pass  stop            iters  evals   seconds   energy start -> end      absolute   IoU start -> end\n";
  for (std::size_t k = 0; k < passes.size(); ++k) {
    const PassSummary& p = passes[k];
    std::snprintf(line, sizeof line, "%5d  %c    %-14s %6d %6d %9.2f   %+.6f -> %+.6f   %+.6f   %.4f -> %.4f%s%s%s\n",
                  p.level, p.kind, p.stop.c_str(), p.iterations, p.evaluations, p.seconds, p.energy_start,
                  p.energy_end, p.absolute_end, p.iou_start, p.iou_end, int(k) == best_pass ? "  best" : "",
                  p.stalled ? "  STALLED" : "", p.iou_loss ? "  SET WORSE" : "");
    s << line;
  }
  for (const PassSummary& p : passes)
    if (p.iou_loss) {
      std::snprintf(line, sizeof line,
                    "set worse: level %d pass %c (pass %d of the level) lowered the one-step IoU on the target grid "
                    "from %.4f to %.4f%s\n",
                    p.level, p.kind, p.pass_index + 1, p.iou_start, p.iou_end,
                    p.eligible ? "" : "; its map is worse than the start's and is not kept");
      s << line;
    }
  if (lowest_psi_pass >= 0 && lowest_psi_pass < int(passes.size())) {
    const PassSummary& p = passes[std::size_t(lowest_psi_pass)];
    std::snprintf(line, sizeof line,
                  "not kept: the lowest absolute energy, %+.6f after level %d pass %c (pass %d of %zu), has one-step "
                  "IoU %.4f on the target grid, below the start's %.4f (keep: lowest-psi returns it)\n",
                  lowest_psi, p.level, p.kind, lowest_psi_pass + 1, passes.size(), p.iou_end, iou_start);
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
  std::snprintf(line, sizeof line,
                "total %.1f s; absolute energy %+.6f -> %+.6f, one-step IoU on the target grid %.4f -> %.4f (%s)%s\n",
                seconds, absolute_start, absolute_end, iou_start, iou_end, BestPassName().c_str(),
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

// The SIGINT/SIGTERM handlers for the life of the optimization.
class SignalGuard {
 public:
  SignalGuard() : guard_((g_interrupted = 0, OnSignal)) {}

 private:
  InterruptGuard guard_;
};

// One optimization run (optimizer.h): Run walks the schedule, RunLevel one level, RunPass one
// pass's minimization, OnIteration what follows each iteration. Without an output folder there
// is no log, no checkpoint and no file; the records still go to the progress line and the
// callbacks.
template <class Scalar>
class Runner {
 public:
  using Vector = Eigen::Matrix<Scalar, -1, 1>;
  using Type = IterationSummary::Type;

  Runner(const ScalarGrid& sdf, RationalMap& map, const OptimizeOptions& o)
      : sdf_(sdf), map_(map), o_(o), folder_(!o.out_dir.empty()), progress_(o.schedule) {}

  OptimizeSummary Run() {
    if (folder_) CreateFolder();
    evaluator_ = ResolveEvaluator(o_.evaluator, o_.precision);
    st_.x = map_.variables().template cast<Scalar>();
    st_.best_x = st_.x;
    if (folder_) fingerprint_.emplace(o_, sdf_, map_);
    if (o_.resume) {
      start_ = ReadCheckpoint<Scalar>(Path("checkpoint.json"), *fingerprint_, map_.variable_count(), st_);
      if (start_.complete) return Completed();
    }
    AddObservers();
    // Unless the passes evaluate densely, the log-linear evaluators are read through bands (the
    // absolute energy's too, where not stored), which need only the rows near the surface.
    st_.summary.between_nodes = ThinWallsOn(o_.between_nodes, sdf_);
    weights_.emplace(sdf_, o_.weights, map_, o_.energy, o_.loglinear(evaluator_), st_.summary.between_nodes);
    ResolveLevels();
    // The start's one-step IoU: map_ is the start map on a resume too (the checkpoint must match it).
    st_.summary.iou_start = weights_->TargetIou(map_.variables());
    if (!o_.resume) st_.summary.iou_end = st_.summary.iou_start;
    if (!o_.resume) NotifyRunStart();

    SignalGuard signals;
    for (int li = start_.level_index; li < int(o_.schedule.levels.size()) && !stopped_; ++li) RunLevel(li);
    return Finish();
  }

 private:
  std::string Path(const std::string& name) const { return o_.out_dir + "/" + name; }

  void CreateFolder() const {
    std::error_code ec;
    std::filesystem::create_directories(o_.out_dir, ec);
    if (ec) throw Error(o_.out_dir + ": cannot create the output folder: " + ec.message());
  }

  // A resume of a run that had finished: its result, nothing run again.
  OptimizeSummary Completed() {
    map_.set_variables(st_.best_x.template cast<double>());
    st_.summary.complete = true;
    st_.summary.seconds = st_.elapsed_before;
    st_.summary.absolute_end = st_.best_absolute;
    return st_.summary;
  }

  // The log first, so the others see a record only once it is logged; the caller's callbacks last.
  void AddObservers() {
    if (folder_) {
      log_.emplace(Path("log.jsonl"), o_.resume ? start_.log_bytes : -1);
      checkpoints_.emplace(Path("checkpoint.json"), *fingerprint_, o_, st_, *log_);
      observers_ = {&*log_, &progress_, &*checkpoints_};
    } else {
      observers_ = {&progress_};
    }
    observers_.insert(observers_.end(), o_.callbacks.begin(), o_.callbacks.end());
  }

  void Notify(IterationSummary s) {
    s.step = st_.step;
    s.seconds = st_.Elapsed();
    for (IterationCallback* observer : observers_)
      if ((*observer)(s) == CallbackReturnType::kAbort) abort_ = true;
  }

  void WriteCheckpoint(int li, int pj, int iteration, const Vector& x, const Vector& pass_start) {
    if (checkpoints_) checkpoints_->Write(li, pj, iteration, x, pass_start, false);
  }

  // The resolution each level runs at (deterministic, so a resumed run finds the same).
  void ResolveLevels() {
    st_.summary.levels.clear();
    for (const LevelSpec& level : o_.schedule.levels) {
      OptimizeSummary::Level l;
      l.scheduled = level.resolution;
      l.resolution = ResolvedLevelResolution(sdf_, weights_->finest_weight(), o_.weights, level.resolution,
                                             o_.level_weights, o_.min_level_fidelity, &l.fidelity);
      st_.summary.levels.push_back(l);
    }
  }

  void NotifyRunStart() {
    st_.summary.absolute_start = weights_->Absolute(st_.x.template cast<double>());
    st_.best_absolute = st_.summary.absolute_start;
    IterationSummary s;
    s.type = Type::kRun;
    s.absolute = st_.summary.absolute_start;
    s.run = {{"schedule", o_.schedule.notation()}, {"evaluator", evaluator_}, {"precision", PrecisionName(o_.precision)},
             {"backend", o_.backend}, {"weights", WeightFieldName(o_.weights)},
             {"roots", {{"top", map_.top_count()}, {"bottom", map_.bottom_count()}}}};
    Notify(s);
  }

  // A callback's abort on a record other than an iteration takes effect before the next pass.
  bool StopBefore(int li, int pj) {
    if (abort_) WriteCheckpoint(li, pj, 0, st_.x, st_.x);
    return stopped_ = abort_;
  }

  void RunLevel(int li) {
    const int first_pass = li == start_.level_index ? start_.pass_index : 0;
    if (StopBefore(li, first_pass)) return;
    const LevelSpec& level = o_.schedule.levels[std::size_t(li)];
    const OptimizeSummary::Level& resolved = st_.summary.levels[std::size_t(li)];
    if (resolved.resolution != resolved.scheduled && first_pass == 0 &&
        !(li == start_.level_index && start_.iteration > 0)) {
      IterationSummary s;
      s.type = Type::kLevelRaised;
      s.level = resolved.resolution;
      s.level_index = li;
      s.scheduled = resolved.scheduled;
      s.fidelity = resolved.fidelity;
      Notify(s);
    }
    LevelObjective<Scalar> objective(*weights_, map_, resolved.resolution, o_.level_weights, evaluator_, o_.energy);
    for (int pj = first_pass; pj < int(level.passes.size()); ++pj) {
      if (StopBefore(li, pj)) break;
      if (pj == 0 && li > 0 && o_.level_start == OptimizeOptions::LevelStart::kBest &&
          st_.summary.best_pass + 1 != int(st_.summary.passes.size())) {
        st_.x = st_.best_x;
        IterationSummary s;
        s.type = Type::kLevelStart;
        s.level = resolved.resolution;
        s.level_index = li;
        s.from_pass = st_.summary.best_pass;
        s.absolute = st_.best_absolute;
        Notify(s);
      }
      if (!RunPass(li, pj, level.passes[std::size_t(pj)], objective)) {
        stopped_ = true;
        break;
      }
    }
    if (!stopped_ && folder_) {
      RationalMap level_map = map_;
      level_map.set_variables(st_.x.template cast<double>());
      WriteMap(Path("map_level_" + std::to_string(resolved.resolution) + ".json"), level_map);
    }
  }

  // One pass's minimization; false when a signal or a callback stopped it.
  bool RunPass(int li, int pj, const PassSpec& spec, LevelObjective<Scalar>& objective) {
    const bool resumed_mid_pass = li == start_.level_index && pj == start_.pass_index && start_.iteration > 0;
    const bool balanced = !resumed_mid_pass && o_.balance_scales && BalanceScales(st_.x, map_.top_count());
    if (!resumed_mid_pass) st_.pass_start_x = st_.x;
    const auto pass_t0 = std::chrono::steady_clock::now();
    IterationSummary where;
    where.level = objective.resolution();
    where.level_index = li;
    where.pass_index = pj;
    where.kind = char(spec.kind);
    if (!resumed_mid_pass) {
      IterationSummary s = where;
      s.type = Type::kPassStart;
      s.tau = ToDouble(st_.x[VariableIndex::kTau]);
      s.beta = ToDouble(st_.x[VariableIndex::kBeta]);
      s.balanced = balanced;
      Notify(s);
    }
    objective.BeginPass(spec.kind, st_.pass_start_x, st_.x);
    const int na = objective.mode() == EnergyMode::kVariable ? 3 : int(st_.x.size());
    Vector xa = st_.x.head(na);
    PassSummary ps;
    ps.level = objective.resolution();
    ps.level_index = li;
    ps.pass_index = pj;
    ps.kind = char(spec.kind);
    bool first_eval = true;
    // A resumed pass evaluates its start point once more than the uninterrupted one did.
    const int evaluation_offset = resumed_mid_pass ? st_.pass_evaluations - 1 : 0;
    if (resumed_mid_pass) ps.energy_start = st_.pass_energy_start, first_eval = false;
    Vector full = st_.x;
    st_.live = &full;
    st_.active = na;
    const BoundedObjective<Scalar> f = [&](const Vector& y, Vector& g) -> Scalar {
      full.head(na) = y;
      const Evaluation<Scalar> ev = objective.Evaluate(full);
      g = ev.gradient.head(na);
      ps.overflowed_cells = std::max<long long>(ps.overflowed_cells, ev.counts.overflowed);
      if (first_eval) ps.energy_start = ToDouble(ev.energy), first_eval = false;
      return ev.energy;
    };
    const LbfgsbCallback<Scalar> on_iteration = [&](int it, int evals, const Scalar& fx, const Scalar& pg) {
      return OnIteration(where, it, evals + evaluation_offset, ps.energy_start, fx, pg);
    };
    const LbfgsbResult<Scalar> res = Minimize(f, xa, spec, on_iteration, resumed_mid_pass ? start_.iteration : 0);
    st_.live = nullptr;
    objective.EndPass();
    st_.x.head(na) = xa;
    if (res.stop == StopReason::kInterrupted) return false;
    ps.stop = StopReasonName(res.stop);
    ps.message = res.message;
    ps.line_search_restarts = res.line_search_restarts;
    ps.iterations = res.iterations;
    ps.evaluations = res.evaluations + evaluation_offset;
    ps.energy_end = ToDouble(res.f);
    // Before the absolute energy, which changes a shared evaluator's weights.
    ps.band = objective.PassReport(st_.x, res.f);
    ps.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - pass_t0).count();
    EndPass(where, ps);
    return true;
  }

  // The minimizer: L-BFGS-B, or Ceres in double; the variables are bounded below by 0 but ln C.
  LbfgsbResult<Scalar> Minimize(const BoundedObjective<Scalar>& f, Vector& xa, const PassSpec& spec,
                                const LbfgsbCallback<Scalar>& on_iteration, int first_iteration) const {
    const Eigen::Index na = xa.size();
    Vector lb = Vector::Zero(na), ub = Vector::Constant(na, std::numeric_limits<Scalar>::infinity());
    lb[0] = -std::numeric_limits<Scalar>::infinity();
    LbfgsbOptions<Scalar> lo;
    lo.memory = o_.memory;
    lo.max_iterations = spec.max_iterations;
    lo.tolerance = Scalar(spec.tolerance);
    if constexpr (std::is_same_v<Scalar, double>) {
      if (o_.backend == "ceres") return MinimizeCeres(f, xa, lb, lo, on_iteration, first_iteration);
    }
    return MinimizeBounded<Scalar>(f, xa, lb, ub, lo, on_iteration, first_iteration);
  }

  // After iteration `it` of the pass `where`: the records, the absolute energy every
  // absolute_every iterations, and whether to stop (signal, callback) or restart the memory at a
  // checkpoint.
  IterationAction OnIteration(const IterationSummary& where, int it, int evaluations, double energy_start,
                              const Scalar& fx, const Scalar& pg) {
    ++st_.step;
    st_.pass_energy_start = energy_start;
    st_.pass_evaluations = evaluations;
    IterationSummary s = where;
    s.type = Type::kIteration;
    s.iteration = it;
    s.evaluations = evaluations;
    s.energy = ToDouble(fx);
    s.projected_gradient_norm = ToDouble(pg);
    Notify(s);
    if (it % o_.absolute_every == 0) {
      IterationSummary a = where;
      a.type = Type::kAbsolute;
      a.iteration = it;
      a.energy = weights_->Absolute(st_.Current().template cast<double>());
      Notify(a);
    }
    IterationAction action = IterationAction::kContinue;
    if (st_.step == TestSignalStep()) std::raise(SIGINT);  // a Ctrl-C, handled before raise returns
    if (g_interrupted || abort_) {
      WriteCheckpoint(where.level_index, where.pass_index, it, st_.Current(), st_.pass_start_x);
      action = IterationAction::kStop;
    } else if (it % o_.checkpoint_every == 0) {
      // The checkpoint writer wrote this state; the memory restarts so that resuming from it is
      // exact. Without a folder the memory restarts as well: the same run, with or without files.
      action = IterationAction::kRestartMemory;
    }
    if (st_.step == TestExitStep()) _exit(kTestExitCode);  // a crash after this step's log and checkpoint
    return action;
  }

  // The pass's absolute energy, the best map so far, the pass_end record.
  // A map is kept only if its one-step IoU on the target grid is at least the start's (keep iou).
  void EndPass(const IterationSummary& where, PassSummary& ps) {
    ps.absolute_end = weights_->Absolute(st_.x.template cast<double>());
    ps.stalled = ps.iterations == 0;
    ps.iou_start = weights_->TargetIou(st_.pass_start_x.template cast<double>());
    ps.iou_end = weights_->TargetIou(st_.x.template cast<double>());
    ps.iou_loss = ps.iou_end < ps.iou_start - o_.iou_tolerance;
    ps.eligible = o_.keep == OptimizeOptions::Keep::kLowestPsi || ps.iou_end >= st_.summary.iou_start;
    const int index = int(st_.summary.passes.size());
    if (ps.absolute_end < st_.best_absolute) {
      if (ps.eligible) {
        st_.best_absolute = ps.absolute_end;
        st_.best_x = st_.x;
        st_.summary.best_pass = index;
        st_.summary.iou_end = ps.iou_end;
      }
    }
    // The lowest absolute energy of the run, when the kept map is another.
    double lowest = st_.summary.absolute_start;
    int lowest_pass = -1;
    for (std::size_t k = 0; k <= st_.summary.passes.size(); ++k) {
      const double a = k < st_.summary.passes.size() ? st_.summary.passes[k].absolute_end : ps.absolute_end;
      if (a < lowest) lowest = a, lowest_pass = int(k);
    }
    st_.summary.lowest_psi_pass = lowest_pass != st_.summary.best_pass ? lowest_pass : -1;
    st_.summary.lowest_psi = lowest;
    st_.summary.passes.push_back(ps);
    IterationSummary s = where;
    s.type = Type::kPassEnd;
    s.pass = ps;
    Notify(s);  // the checkpoint writer records the next pass as the place to continue
  }

  OptimizeSummary Finish() {
    map_.set_variables(st_.best_x.template cast<double>());
    st_.summary.complete = !stopped_;
    if (stopped_) st_.summary.stop_reason = g_interrupted ? "interrupted" : "aborted by a callback";
    if (stopped_) st_.summary.signal = int(g_interrupted);
    st_.summary.seconds = st_.Elapsed();
    st_.summary.absolute_end = st_.best_absolute;
    if (folder_) WriteFileAtomically(Path("summary.json"), st_.summary.ToJson(o_).dump(1) + "\n");
    return st_.summary;
  }

  const ScalarGrid& sdf_;
  RationalMap& map_;
  const OptimizeOptions& o_;
  const bool folder_;  // an output folder: the log, checkpoints, maps and summary are written
  std::string evaluator_;  // resolved: band, dense or cached
  RunState<Scalar> st_;
  CheckpointPosition start_;  // where the run begins (a resume's checkpoint)
  std::optional<Fingerprint> fingerprint_;
  std::optional<JsonlLog> log_;
  ProgressLine progress_;
  std::optional<CheckpointWriter<Scalar>> checkpoints_;
  std::vector<IterationCallback*> observers_;
  std::optional<PassWeights> weights_;
  bool abort_ = false;    // a callback asked to stop
  bool stopped_ = false;  // by a signal or a callback
};

}  // namespace

OptimizeSummary Optimize(const ScalarGrid& sdf, RationalMap& map, const OptimizeOptions& options) {
  if (auto why = options.Validate(); !why.empty()) throw Error("optimize: " + why);
  if (options.resume && options.out_dir.empty())
    throw Error("optimize: resume needs the output folder of the interrupted run");
  if (auto why = map.Validate(); !why.empty()) throw Error("optimize: map: " + why);
  return DispatchPrecision(options.precision, [&]<class Real>() { return Runner<Real>(sdf, map, options).Run(); });
}

}  // namespace quijibo::optim
