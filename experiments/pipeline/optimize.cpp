#include "experiments/pipeline/optimize.h"

#include <cstdio>

#include "experiments/pipeline/settings.h"
#include "quijibo/error.h"
#include "quijibo/io.h"
#include "quijibo/target.h"

namespace quijibo::pipeline {

using nlohmann::json;
namespace fs = std::filesystem;

OptimizeStageOptions OptimizeStageOptions::FromJson(const JsonReader& r, const std::string& p, const fs::path& base,
                                                    bool named) {
  OptimizeStageOptions s;
  json& out = s.resolved;
  auto str = [&](const std::string& key, const std::string& fallback, const std::vector<std::string>& choices) {
    const json v = r.has(p + "/" + key)
                       ? ReadValue(r, p + "/" + key, SettingType::kChoice, 0, 0, false, false, choices, {}, base, false)
                       : json(fallback);
    out[key] = v;
    return v.get<std::string>();
  };
  auto num = [&](const std::string& key, double fallback, double lo, double hi, bool open_lo = false) {
    const json v = r.has(p + "/" + key)
                       ? ReadValue(r, p + "/" + key, SettingType::kNumber, lo, hi, open_lo, false, {}, {}, base, false)
                       : json(fallback);
    out[key] = v;
    return v.get<double>();
  };
  auto integer = [&](const std::string& pointer, long long fallback, long long lo, long long hi) {
    const json v = r.has(pointer) ? ReadValue(r, pointer, SettingType::kInteger, double(lo), double(hi), false, false,
                                              {}, {}, base, false)
                                  : json(fallback);
    out[json::json_pointer(pointer.substr(p.size()))] = v;
    return v.get<long long>();
  };
  if (!r.at(p).is_object()) r.fail(p, "expected an object, found " + JsonReader::describe(r.at(p)));
  r.allow_keys(p, {"name", "schedule", "backend", "evaluator", "precision", "weights", "level_weights", "level_start",
                   "alpha", "memory", "tolerance", "max_iterations", "checkpoint_every", "absolute_every", "storage",
                   "memory_budget_gb"});
  if (named) {
    s.name = r.has(p + "/name") ? r.string(p + "/name") : "";
    if (s.name.empty() || s.name.find_first_not_of(
                              "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789-_.") != std::string::npos)
      r.fail(p + "/name", "expected a non-empty name of letters, digits, '-', '_' or '.' (it names a folder)");
  }
  OptimizeOptions& o = s.optimizer;
  o.backend = str("backend", "lbfgspp", {"lbfgspp", "ceres"});
  o.evaluator = str("evaluator", OptimizeOptions{}.evaluator, kEvaluatorNames);
  const std::string pr = str("precision", "double", {"float", "double", "long-double", "float128"});
  o.precision = ParsePrecision(pr);
  if (ResolveEvaluator(o.evaluator, o.precision) != "cached" && pr != "double")
    r.fail(p + "/precision",
           "the loglinear evaluator runs in double only; use \"evaluator\": \"cached\" for \"" + pr + "\"");
  o.weights =
      ParseWeightField(str("weights", WeightFieldName(OptimizeOptions{}.weights), {"layer", "inverse", "balanced"}));
  o.level_weights = str("level_weights", "sample", {"sample", "recompute"}) == "sample" ? LevelWeights::kSampleFinest
                                                                                        : LevelWeights::kRecompute;
  o.level_start = ParseLevelStart(str("level_start", LevelStartName(OptimizeOptions{}.level_start), {"best", "last"}));
  o.loglinear.storage = ParseStorage(str("storage", "auto", {"auto", "double", "float", "on-the-fly"}));
  o.energy.alpha = num("alpha", 10.0, 0.0, 1e6, true);
  o.memory = int(integer(p + "/memory", 5, 1, 100));
  o.loglinear.memory_budget_bytes = num("memory_budget_gb", 8.0, 0.0, 1e6) * 1e9;
  o.checkpoint_every = int(integer(p + "/checkpoint_every", 25, 1, 1000000));
  o.absolute_every = int(integer(p + "/absolute_every", 10, 1, 1000000));
  const double tol = num("tolerance", 1e-5, 0.0, 1e6);
  PassSpec defaults[3] = {DefaultPass(PassKind::kVariable), DefaultPass(PassKind::kFull),
                          DefaultPass(PassKind::kReweighted)};
  if (r.has(p + "/max_iterations")) r.allow_keys(p + "/max_iterations", {"V", "F", "R"});
  const char* kinds[3] = {"V", "F", "R"};
  for (int k = 0; k < 3; ++k) {
    defaults[k].max_iterations =
        int(integer(p + "/max_iterations/" + kinds[k], defaults[k].max_iterations, 1, 10000000));
    defaults[k].tolerance = tol;
  }
  const std::string sp = p + "/schedule";
  Schedule& schedule = o.schedule;
  if (!r.has(sp)) {
    schedule = Schedule::Parse("25(VFRF)50(VFRF)97(VF)", defaults);
  } else {
    const json& node = r.at(sp);
    if (node.is_string()) {
      const std::string text = node.get<std::string>();
      if (text.find_first_not_of(" \t") == std::string::npos) r.fail(sp, "expected a schedule, found an empty string");
      if (text.ends_with(".json")) {
        const std::string file = ResolvePath(base, text);
        if (!fs::is_regular_file(file)) r.fail(sp, "no such schedule file: " + file);
        const json doc = ParseJson(ReadFile(file), file);
        schedule = Schedule::FromJson(JsonReader(doc, file), "");
      } else {
        try {
          schedule = Schedule::Parse(text, defaults);
        } catch (const Error& e) {
          r.fail(sp, e.what());
        }
      }
    } else if (node.is_object()) {
      if (node.empty()) r.fail(sp, "expected a schedule, found an empty object");
      schedule = Schedule::FromJson(r, sp);
    } else {
      r.fail(sp,
             "expected a schedule (notation string, JSON object or .json file), found " + JsonReader::describe(node));
    }
  }
  if (schedule.levels.empty()) r.fail(sp, "the schedule has no levels");
  out["schedule"] = schedule.ToJson();
  return s;
}

json OptimizeStageOptions::ToJson() const {
  json j = resolved;
  j["name"] = name;
  return j;
}

OptimizeStageResult OptimizeStage(const ScalarGrid& target, const RationalMap& initial, const OptimizeStageOptions& s,
                                  const std::string& out_dir, bool resume) {
  OptimizeOptions o = s.optimizer;
  o.out_dir = out_dir;
  o.resume = resume;
  // The initial map: given, or on resume the one the run started from.
  const std::string initial_path = out_dir + "/initial_map.json";
  OptimizeStageResult res;
  if (resume) {
    res.map = ReadMap(initial_path);
  } else {
    res.map = initial;
    fs::create_directories(out_dir);
    WriteMap(initial_path, res.map);
  }
  res.summary = Optimize(target, res.map, o);
  const OptimizeSummary& sum = res.summary;
  res.map.provenance["optimized"] = {{"schedule", o.schedule.notation()},
                                     {"evaluator", o.evaluator},
                                     {"precision", PrecisionName(o.precision)},
                                     {"backend", o.backend},
                                     {"absolute_energy", sum.absolute_end},
                                     {"best_pass", sum.best_pass},
                                     {"complete", sum.complete}};
  if (!sum.complete) {
    std::fprintf(stderr, "%s", sum.Report().c_str());
    throw Error("interrupted; checkpoint written to " + out_dir + "/checkpoint.json; continue with --resume");
  }
  WriteMap(out_dir + "/map.json", res.map);
  return res;
}

}  // namespace quijibo::pipeline
