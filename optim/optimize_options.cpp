// OptimizeOptions: validation and the experiment's "optimizer" object (optim/optimizer.h).
#include <algorithm>
#include <cmath>

#include "optim/optimizer.h"
#include "quijibo/error.h"
#include "quijibo/io.h"
#include "quijibo/json_reader.h"

namespace quijibo::optim {

using nlohmann::json;
namespace fs = std::filesystem;

OptimizeOptions::LevelStart ParseLevelStart(const std::string& name) {
  if (name == "best") return OptimizeOptions::LevelStart::kBest;
  if (name == "last") return OptimizeOptions::LevelStart::kLast;
  throw Error("unknown level start \"" + name + "\" (expected best or last)");
}

std::string LevelStartName(OptimizeOptions::LevelStart s) {
  return s == OptimizeOptions::LevelStart::kBest ? "best" : "last";
}

LevelWeights ParseLevelWeights(const std::string& name) {
  if (name == "sample") return LevelWeights::kSampleFinest;
  if (name == "recompute") return LevelWeights::kRecompute;
  throw Error("unknown level weights \"" + name + "\" (expected sample or recompute)");
}

std::string LevelWeightsName(LevelWeights w) { return w == LevelWeights::kSampleFinest ? "sample" : "recompute"; }

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

LogLinearOptions OptimizeOptions::loglinear() const {
  LogLinearOptions l;
  l.storage = storage;
  l.memory_budget_bytes = memory_budget_gb * 1e9;
  return l;
}

std::string OptimizeOptions::Validate() const {
  if (auto why = schedule.validate(); !why.empty()) return "schedule: " + why;
  if (std::find(kEvaluatorNames.begin(), kEvaluatorNames.end(), evaluator) == kEvaluatorNames.end())
    return "evaluator must be auto, band, dense (loglinear) or cached, found \"" + evaluator + "\"";
  if (ResolveEvaluator(evaluator, precision) != "cached" && precision != Precision::kDouble)
    return "the loglinear evaluator (band or dense) runs in double only";
  if (std::find(kBackendNames.begin(), kBackendNames.end(), backend) == kBackendNames.end())
    return "unknown back end \"" + backend + "\" (available: lbfgspp, ceres)";
  if (backend == "ceres" && precision != Precision::kDouble) return "the ceres back end runs in double only";
  const std::pair<SettingRange, double> values[] = {
      {kAlphaRange, energy.alpha},       {kMemoryRange, double(memory)},
      {kMemoryBudgetRange, memory_budget_gb}, {kCheckpointEveryRange, double(checkpoint_every)},
      {kAbsoluteEveryRange, double(absolute_every)}, {kToleranceRange, tolerance},
      {kMinLevelFidelityRange, min_level_fidelity}};
  for (const auto& [range, value] : values)
    if (auto why = range.Check(value); !why.empty()) return why;
  const std::pair<const char*, int> caps[] = {{"V", max_iterations.V}, {"F", max_iterations.F}, {"R", max_iterations.R}};
  for (const auto& [kind, cap] : caps)
    if (!kMaxIterationsRange.contains(cap))
      return std::string("max_iterations.") + kind + " must be in " + kMaxIterationsRange.interval() + ", found " +
             std::to_string(cap);
  if (auto why = energy.validate(); !why.empty()) return why;
  if (auto why = loglinear().validate(); !why.empty()) return why;
  return {};
}

json OptimizeOptions::ToJson() const {
  return {{"backend", backend},
          {"evaluator", evaluator},
          {"precision", PrecisionName(precision)},
          {"weights", WeightFieldName(weights)},
          {"level_weights", LevelWeightsName(level_weights)},
          {"level_start", LevelStartName(level_start)},
          {"min_level_fidelity", min_level_fidelity},
          {"storage", StorageName(storage)},
          {"alpha", energy.alpha},
          {"memory", memory},
          {"memory_budget_gb", memory_budget_gb},
          {"checkpoint_every", checkpoint_every},
          {"absolute_every", absolute_every},
          {"tolerance", tolerance},
          {"max_iterations", {{"V", max_iterations.V}, {"F", max_iterations.F}, {"R", max_iterations.R}}},
          {"schedule", schedule.ToJson()}};
}

namespace {

// One of `choices` at `p`, or `fallback` when missing.
std::string Choice(const JsonReader& r, const std::string& p, const std::string& fallback,
                   const std::vector<std::string>& choices) {
  const std::string v = r.string_or(p, fallback);
  if (std::find(choices.begin(), choices.end(), v) == choices.end()) {
    std::string list;
    for (const auto& c : choices) list += (list.empty() ? "" : ", ") + ("\"" + c + "\"");
    r.fail(p, "expected one of " + list + ", found \"" + v + "\"");
  }
  return v;
}

// A number in `range` at `p` (an integer for integer ranges; 5.0 counts as 5), or `fallback`.
double InRange(const JsonReader& r, const std::string& p, const SettingRange& range, double fallback) {
  if (!r.has(p)) return fallback;
  double v;
  if (range.integer) {
    const json& j = r.at(p);
    if (j.is_number_float() && std::isfinite(j.get<double>()) && j.get<double>() == std::floor(j.get<double>()) &&
        std::abs(j.get<double>()) < 9e15)
      v = j.get<double>();
    else
      v = double(r.integer(p));
  } else {
    v = r.number(p);
  }
  if (!range.contains(v)) r.fail(p, range.Expected(v));
  return v;
}

}  // namespace

OptimizeOptions OptimizeOptions::FromJson(const JsonReader& r, const std::string& p, const fs::path& base,
                                          const std::vector<std::string>& extra_keys) {
  if (!r.at(p).is_object()) r.fail(p, "expected an object, found " + JsonReader::describe(r.at(p)));
  std::vector<std::string> keys = extra_keys;
  keys.insert(keys.end(), {"schedule", "backend", "evaluator", "precision", "weights", "level_weights", "level_start",
                           "min_level_fidelity", "alpha", "memory", "tolerance", "max_iterations", "checkpoint_every", "absolute_every",
                           "storage", "memory_budget_gb"});
  r.allow_keys(p, keys);
  OptimizeOptions o;
  o.backend = Choice(r, p + "/backend", o.backend, kBackendNames);
  o.evaluator = Choice(r, p + "/evaluator", o.evaluator, kEvaluatorNames);
  const std::string precision = Choice(r, p + "/precision", PrecisionName(o.precision), kPrecisionNames);
  o.precision = ParsePrecision(precision);
  if (ResolveEvaluator(o.evaluator, o.precision) != "cached" && o.precision != Precision::kDouble)
    r.fail(p + "/precision", "the loglinear evaluator runs in double only; use \"evaluator\": \"cached\" for \"" +
                                 precision + "\"");
  o.weights = ParseWeightField(Choice(r, p + "/weights", WeightFieldName(o.weights), kWeightNames));
  o.level_weights =
      ParseLevelWeights(Choice(r, p + "/level_weights", LevelWeightsName(o.level_weights), kLevelWeightNames));
  o.level_start = ParseLevelStart(Choice(r, p + "/level_start", LevelStartName(o.level_start), kLevelStartNames));
  o.min_level_fidelity = InRange(r, p + "/min_level_fidelity", kMinLevelFidelityRange, o.min_level_fidelity);
  o.storage = ParseStorage(Choice(r, p + "/storage", StorageName(o.storage), kStorageNames));
  o.energy.alpha = InRange(r, p + "/alpha", kAlphaRange, o.energy.alpha);
  o.memory = int(InRange(r, p + "/memory", kMemoryRange, o.memory));
  o.memory_budget_gb = InRange(r, p + "/memory_budget_gb", kMemoryBudgetRange, o.memory_budget_gb);
  o.checkpoint_every = int(InRange(r, p + "/checkpoint_every", kCheckpointEveryRange, o.checkpoint_every));
  o.absolute_every = int(InRange(r, p + "/absolute_every", kAbsoluteEveryRange, o.absolute_every));
  o.tolerance = InRange(r, p + "/tolerance", kToleranceRange, o.tolerance);
  if (r.has(p + "/max_iterations")) r.allow_keys(p + "/max_iterations", {"V", "F", "R"});
  const std::pair<const char*, int*> caps[] = {
      {"V", &o.max_iterations.V}, {"F", &o.max_iterations.F}, {"R", &o.max_iterations.R}};
  for (const auto& [kind, cap] : caps)
    *cap = int(InRange(r, p + "/max_iterations/" + kind, kMaxIterationsRange, *cap));
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
        const fs::path f(s);
        const std::string file = (f.is_relative() ? (base / f).lexically_normal() : f).string();
        if (!fs::is_regular_file(file)) r.fail(sp, "no such schedule file: " + file);
        const json doc = ParseJson(ReadFile(file), file);
        o.schedule = Schedule::FromJson(JsonReader(doc, file), "");
      } else {
        try {
          o.schedule = o.ScheduleFromNotation(s);
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
