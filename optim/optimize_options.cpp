// OptimizeOptions: validation and the experiment's "optimizer" object (optim/optimizer.h).
#include <algorithm>
#include <cmath>

#include "optim/optimizer.h"
#include "util/error.h"
#include "util/io.h"
#include "util/json_reader.h"

namespace quijibo::optim {

using nlohmann::json;
namespace fs = std::filesystem;

std::string ResolveEvaluator(const std::string& name, Precision precision) {
  if (name == "auto") return precision == Precision::kDouble ? "band" : "cached";
  if (name == "loglinear") return "dense";
  if (name == "band" || name == "dense" || name == "cached") return name;
  throw Error("unknown evaluator \"" + name + "\": expected auto, band, dense (loglinear) or cached");
}

std::vector<PassSpec> OptimizeOptions::PassDefaults() const {
  std::vector<PassSpec> d;
  const int caps[3] = {max_iterations.V, max_iterations.F, max_iterations.R};
  for (int k = 0; k < 3; ++k) {
    d.push_back(DefaultPass(kPassKinds[k]));
    d.back().max_iterations = caps[k];
    d.back().tolerance = tolerance;
  }
  return d;
}

Schedule OptimizeOptions::ScheduleFromNotation(const std::string& notation) const {
  const std::vector<PassSpec> d = PassDefaults();
  return Schedule::Parse(notation, d.data());
}

LogLinearOptions OptimizeOptions::loglinear(const std::string& evaluator) const {
  LogLinearOptions l;
  l.storage = storage;
  l.memory_budget_bytes = memory_budget_gb * 1e9;
  l.band = evaluator != "dense";
  return l;
}

const Schema<OptimizeOptions>& OptimizeOptions::Settings() {
  using O = OptimizeOptions;
  static const Schema<O> s =
      Schema<O>()
          .Integer(
              "max_iterations/V", "--max-v", "Iteration cap of V passes (notation form)",
              [](auto& o) -> int& { return o.max_iterations.V; }, kMaxIterationsRange)
          .Doc("cap of V passes in the notation form (a JSON schedule's passes without a cap get the same "
               "default, or its own `\"defaults\"`)")
          .Integer(
              "max_iterations/F", "--max-f", "Iteration cap of F passes (notation form)",
              [](auto& o) -> int& { return o.max_iterations.F; }, kMaxIterationsRange)
          .Doc("the same for F passes")
          .Integer(
              "max_iterations/R", "--max-r", "Iteration cap of R passes (notation form)",
              [](auto& o) -> int& { return o.max_iterations.R; }, kMaxIterationsRange)
          .Doc("the same for R passes")
          .Number(
              "tolerance", "--tolerance",
              "Projected-gradient tolerance (infinity norm) of every pass (notation form)",
              [](auto& o) -> double& { return o.tolerance; }, kToleranceRange)
          .Choice("backend", "--backend", "lbfgspp (bound-constrained L-BFGS-B) or ceres (L-BFGS on x = y^2)",
                  [](auto& o) -> std::string& { return o.backend; }, kBackendNames)
          .Choice("evaluator", "-e,--evaluator",
                  "auto (band in double, else cached), band (log-linear, narrow band), dense (log-linear, every "
                  "cell; also: loglinear) or cached (the paper's)",
                  [](auto& o) -> std::string& { return o.evaluator; }, kEvaluatorNames)
          .Doc("`auto`: the narrow band in double, `cached` in other precisions; `band`: the log-linear evaluator "
               "on its narrow band (same ψ and gradient as dense, bit for bit; docs/architecture.md); `dense` "
               "(older name `loglinear`): log-linear on every cell (double only); `cached`: the paper's evaluator")
          .With(PrecisionSetting([](auto& o) -> Precision& { return o.precision; }))
          .With(WeightsSetting([](auto& o) -> WeightField& { return o.weights; }))
          .With(LevelWeightsSetting([](auto& o) -> LevelWeights& { return o.level_weights; }))
          .Enum(
              "level_start", "--level-start",
              "best: each level after the first starts from the map with the lowest absolute energy so far; "
              "last: from the last pass's map (the paper, the reference code)",
              kLevelStarts.names(), [](const O& o) { return LevelStartName(o.level_start); },
              [](O& o, const std::string& v) { o.level_start = ParseLevelStart(v); })
          .Doc("where each level after the first starts: the last pass's map (the paper and reference), or the "
               "map with the lowest absolute energy so far ([fidelity.md](fidelity.md) §5)")
          .Number(
              "min_level_fidelity", "--min-level-fidelity",
              "A level runs at the smallest resolution (up to the finest) whose grid represents the target with "
              "at least this IoU (0: the schedule as written)",
              [](auto& o) -> double& { return o.min_level_fidelity; }, 0, 1)
          .Doc("each level runs at the smallest resolution (from its scheduled one up to the finest) whose grid "
               "represents the target with at least this IoU; 0: the schedule as written, the paper's "
               "([fidelity.md](fidelity.md) §6)")
          .Enum(
              "between_nodes", "--between-nodes",
              "Also fit every level's cell corners (a staggered twin of its grid), so thin walls cannot pass "
              "through the nodes and narrow between them; about twice the work: on, auto (only on a thin-walled "
              "target) or off (the paper's energy)",
              kAutoSwitchNames, [](const O& o) { return AutoSwitchName(o.between_nodes); },
              [](O& o, const std::string& v) { o.between_nodes = ParseAutoSwitch(v); })
          .Doc("the energy also on every level's interior cell corners, a staggered twin of its grid (ψ is the sum "
               "over both): a fit whose walls two or three cells thin pass through the nodes and narrow between "
               "them pays for it, and on thick shapes it is what makes the optimized volume at least the start's; "
               "about twice the work; `auto`: only when the 90th percentile of the inside's depth is below 4 "
               "target cells; `off`: the paper's energy, on the nodes ([fidelity.md](fidelity.md) §8, §9, §11)")
          .Enum(
              "keep", "--keep",
              "Which map the run returns: iou (the lowest absolute energy among the maps whose one-step IoU on the "
              "target grid is at least the start's) or lowest-psi (the lowest absolute energy)",
              kKeeps.names(), [](const O& o) { return KeepName(o.keep); },
              [](O& o, const std::string& v) { o.keep = ParseKeep(v); })
          .Doc("the map the run returns: `iou`, the lowest absolute energy among the start and the pass ends whose "
               "one-step IoU on the target grid is at least the start's (the result never fits worse than the start "
               "by that measure); `lowest-psi`, the lowest absolute energy whatever its IoU ([fidelity.md](fidelity.md) §12)")
          .Number(
              "iou_tolerance", "--iou-tolerance",
              "A pass whose one-step IoU on the target grid falls more than this below its start's is reported",
              [](auto& o) -> double& { return o.iou_tolerance; }, 0, 1)
          .Doc("a pass whose one-step IoU on the target grid ends more than this below its start's is flagged in the "
               "pass table, summary.json (`iou_loss`) and the log")
          .Boolean("balance_scales", "--no-balance-scales",
                   "Start every pass whose tau and beta differ by more than a factor 2 with tau = beta and the exponents "
                   "rescaled to the same map (a better-conditioned problem); --no-balance-scales: the variables as the "
                   "last pass left them (the paper)",
                   [](auto& o) -> bool& { return o.balance_scales; })
          .Doc("a pass whose τ and β differ by more than a factor 2 starts with τ = β (their geometric mean) and each root's "
               "exponent rescaled so that its power τ·a (β·b) is unchanged: the same map, but top and bottom roots "
               "move at the same rate under L-BFGS where a pass had driven τ and β apart (the monopole start; the "
               "log-kernel start keeps them equal and is not touched) ([fidelity.md](fidelity.md) §12); `false`: "
               "the variables as the previous pass left them, the paper's and the reference's")
          .With(AlphaSetting([](auto& o) -> double& { return o.energy.alpha; }))
          .Integer(
              "memory", "--memory", "L-BFGS correction pairs", [](auto& o) -> int& { return o.memory; }, 1, 100)
          .With(StorageSetting([](auto& o) -> LogLinearOptions::Storage& { return o.storage; }))
          .Number(
              "memory_budget_gb", "--memory-budget",
              "GB the finest level's log-distance matrix may take with storage auto (else on the fly, ~5x slower); "
              "the nodes' and the corners' evaluators share it when between_nodes is on",
              [](auto& o) -> double& { return o.memory_budget_gb; }, 0, 1e6)
          .Integer(
              "checkpoint_every", "--checkpoint-every", "Iterations between checkpoints",
              [](auto& o) -> int& { return o.checkpoint_every; }, 1, 1000000)
          .Doc("iterations between checkpoints (and L-BFGS memory restarts)")
          .Integer(
              "absolute_every", "--absolute-every", "Iterations between absolute energies in the log",
              [](auto& o) -> int& { return o.absolute_every; }, 1, 1000000);
  return s;
}

namespace {
// The log-linear evaluators (band, dense) run in double only.
bool PrecisionMismatch(const OptimizeOptions& o) {
  return ResolveEvaluator(o.evaluator, o.precision) != "cached" && o.precision != Precision::kDouble;
}
}  // namespace

std::string OptimizeOptions::Validate() const {
  if (auto why = schedule.Validate(); !why.empty()) return "schedule: " + why;
  if (auto why = Settings().Check(*this); !why.empty()) return why;
  if (PrecisionMismatch(*this)) return "the loglinear evaluator (band or dense) runs in double only";
  if (backend == "ceres" && precision != Precision::kDouble) return "the ceres back end runs in double only";
  if (auto why = energy.Validate(); !why.empty()) return why;
  if (auto why = loglinear().Validate(); !why.empty()) return why;
  return {};
}

json OptimizeOptions::ToJson() const {
  json j = json::object();
  Settings().Write(*this, j);
  j["schedule"] = schedule.ToJson();
  return j;
}

Schedule OptimizeOptions::ScheduleFromString(const std::string& s, const fs::path& base) const {
  if (!s.ends_with(".json")) return ScheduleFromNotation(s);
  const std::string file = ResolvePath(base, s);
  if (!fs::is_regular_file(file)) throw Error("no such schedule file: " + file);
  const json doc = ParseJson(ReadFile(file), file);
  return Schedule::FromJson(JsonReader(doc, file), "");
}

OptimizeOptions OptimizeOptions::FromJson(const JsonReader& r, const std::string& p, const fs::path& base,
                                          const std::vector<std::string>& extra_keys) {
  if (!r.at(p).is_object()) r.fail(p, "expected an object, found " + JsonReader::describe(r.at(p)));
  std::vector<std::string> keys = extra_keys;
  keys.push_back("schedule");
  OptimizeOptions o;
  Settings().Read(r, p, base, o, keys);
  if (PrecisionMismatch(o))
    r.fail(p + "/precision", "the loglinear evaluator runs in double only; use \"evaluator\": \"cached\" for \"" +
                                 PrecisionName(o.precision) + "\"");
  // The schedule: notation, a JSON object, or a .json file holding one.
  const std::string sp = p + "/schedule";
  if (!r.has(sp)) {
    o.schedule = o.ScheduleFromNotation(kDefaultSchedule);
  } else {
    const json& node = r.at(sp);
    if (node.is_string()) {
      const std::string s = node.get<std::string>();
      if (s.find_first_not_of(" \t") == std::string::npos) r.fail(sp, "expected a schedule, found an empty string");
      if (s.ends_with(".json")) {
        if (!fs::is_regular_file(ResolvePath(base, s))) r.fail(sp, "no such schedule file: " + ResolvePath(base, s));
        o.schedule = o.ScheduleFromString(s, base);  // a file's errors name the file
      } else {
        try {
          o.schedule = o.ScheduleFromString(s, base);
        } catch (const Error& e) {
          r.fail(sp, e.what());
        }
      }
    } else if (node.is_object()) {
      if (node.empty()) r.fail(sp, "expected a schedule, found an empty object");
      o.schedule = Schedule::FromJson(r, sp);
    } else {
      r.fail(sp, "expected a schedule (notation string, JSON object or .json file), found " +
                     JsonReader::describe(node));
    }
  }
  if (o.schedule.levels.empty()) r.fail(sp, "the schedule has no levels");
  return o;
}

}  // namespace quijibo::optim
