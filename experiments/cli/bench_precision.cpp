// `quijibo bench precision`: seconds per energy+gradient evaluation, accuracy and overflow of
// the paper's cached evaluator in four precisions against the exact log-linear one, on seeded
// random maps of the paper's sizes (tooth 108, bunny 331, dragon 708 roots).
//
// Each case runs in a child process (`quijibo bench precision-case ...`) so that its peak
// memory is its own (wait4's ru_maxrss) and a case that runs out of memory cannot take the
// table down with it.
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <map>
#include <sstream>

#include "experiments/cli/cli.h"
#include "experiments/pipeline/energy.h"
#include "util/child_process.h"
#include "util/error.h"
#include "quijibo/frame.h"
#include "util/progress.h"
#include "quijibo/rational_map.h"
#include "quijibo/target.h"

namespace quijibo::cli {

using nlohmann::json;

namespace {

struct Split {
  int roots, top, bottom;
};
// The paper's Table 1 splits.
Split SplitFor(int roots) {
  if (roots == 108) return {108, 65, 43};
  if (roots == 331) return {331, 178, 153};
  if (roots == 364) return {364, 194, 170};
  if (roots == 708) return {708, 352, 356};
  return {roots, (roots + 1) / 2, roots / 2};
}

struct CaseSpec {
  int roots = 108, grid = 25, repeats = 3;
  std::string evaluator = "cached", precision = "long-double", storage = "auto";
  std::uint64_t seed = 1;
  double exponent_min = 1.0, exponent_max = 5.0;
};

// The problem of a case: a sphere target (radius 1) on the default target box at N^3, and a
// seeded random map whose ln C puts the median of L at 0.
void RunCase(const CaseSpec& s) {
  const Split split = SplitFor(s.roots);
  const ScalarGrid sdf = AnalyticTarget("sphere:radius=1", TargetGridFrame(s.grid, FractalFrame{}));
  const EnergyGrid grid = MakeEnergyGrid(sdf, WeightField::kLayer);
  RandomMapOptions o;
  o.top = split.top;
  o.bottom = split.bottom;
  o.root_radius = 1.2;
  o.exponent_min = s.exponent_min;
  o.exponent_max = s.exponent_max;
  o.seed = s.seed + std::uint64_t(s.roots);
  RationalMap map = RandomMap(o);
  map.ln_C = -MedianLogModulus(map, grid);
  pipeline::EnergyStageOptions choice;
  choice.evaluator = s.evaluator;
  choice.precision = ParsePrecision(s.precision);
  choice.storage = ParseStorage(s.storage);
  choice.repeats = s.repeats;
  choice.weights = WeightField::kLayer;  // the grid above
  const json r = pipeline::EnergyStage(map, sdf, choice);
  WriteOutput("", r.dump() + "\n");
}

struct CaseResult {
  bool ok = false;
  json report;
  std::string error;
  double peak_mb = 0;
  double wall = 0;
};

// One case in a child process of this executable: its peak memory is its own.
CaseResult Spawn(const CaseSpec& s) {
  ChildOptions c;
  c.program = SelfExecutable();
  c.argv0 = "quijibo";
  c.args = {"--quiet", "bench", "precision-case", "--roots", std::to_string(s.roots), "--grid", std::to_string(s.grid),
            "--evaluator", s.evaluator, "--precision", s.precision, "--storage", s.storage, "--repeats",
            std::to_string(s.repeats), "--seed", std::to_string(s.seed), "--exponent-min",
            std::to_string(s.exponent_min), "--exponent-max", std::to_string(s.exponent_max)};
  c.stdin_path = "";
  c.capture_stdout = true;
  ChildResult child;
  try {
    child = RunChild(c);
  } catch (const Error&) {
    throw Error("bench: cannot start a case process");
  }
  CaseResult r;
  r.wall = child.wall_seconds;
  r.peak_mb = child.peak_rss_mb;
  if (child.ok()) {
    try {
      r.report = json::parse(child.out);
      r.ok = true;
    } catch (const std::exception&) {
      r.error = "unreadable case output";
    }
  } else {
    r.error = child.Describe();
  }
  return r;
}

std::vector<int> ParseList(const std::string& s, const char* what) {
  std::vector<int> v;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ',')) {
    try {
      const int x = std::stoi(item);
      if (x <= 0) throw std::invalid_argument("");
      v.push_back(x);
    } catch (const std::exception&) {
      throw Error(std::string("--") + what + ": expected positive integers separated by commas, found \"" + s + "\"");
    }
  }
  if (v.empty()) throw Error(std::string("--") + what + " is empty");
  return v;
}

long double ParseExact(const json& s) { return std::strtold(s.get<std::string>().c_str(), nullptr); }

std::string Fmt(const char* f, double x) {
  char b[64];
  std::snprintf(b, sizeof b, f, x);
  return b;
}

struct PrecisionArgs {
  std::string roots = "108,331,708", grids = "25,50,97", out_json = "bench-precision.json",
              out_md = "bench-precision.md";
  int repeats = 3;
  double max_seconds = 600;
  bool quick = false;
  std::uint64_t seed = 1;
  double exponent_min = 1.0, exponent_max = 5.0;
};

struct PrecisionConfig {
  std::string evaluator, precision;
};

// The reference of the gradient and energy errors at one size: the first cached float128 or long
// double case without overflow.
struct PrecisionReference {
  json gradient;
  std::string name;
  long double energy = 0;
};

// One case (a child process) into `row`: its figures, and its errors against `ref`, which it
// becomes when it is the first that qualifies. `rate` (seconds per cell x root, per
// configuration) predicts the case's time; a case predicted over --max-seconds is skipped.
void MeasurePrecisionCase(const PrecisionArgs& a, int r, int n, const PrecisionConfig& c,
                          std::map<std::string, double>& rate, PrecisionReference& ref, json& row) {
  const std::string key = c.evaluator + "/" + c.precision;
  const double work = double(n) * n * n * r;
  const double predicted = rate.count(key) ? rate[key] * work * (a.repeats + 0.5) : 0.0;
  if (predicted > a.max_seconds) {
    row["skipped"] = "predicted " + FormatDuration(predicted) + " > --max-seconds " + FormatDuration(a.max_seconds);
    return;
  }
  CaseSpec s;
  s.roots = r;
  s.grid = n;
  s.repeats = a.repeats;
  s.evaluator = c.evaluator;
  s.precision = c.precision;
  s.seed = a.seed;
  s.exponent_min = a.exponent_min;
  s.exponent_max = a.exponent_max;
  const CaseResult res = Spawn(s);
  if (!res.ok) {
    row["skipped"] = "case failed: " + res.error;
    return;
  }
  const json& rep = res.report;
  for (const char* k : {"median_seconds", "seconds", "setup_seconds", "energy", "energy_exact", "overflowed_cells",
                        "singular_cells", "cells"})
    row[k] = rep[k];
  row["peak_memory_mb"] = res.peak_mb;
  if (rep.contains("storage")) row["storage"] = rep["storage"];
  rate[key] = std::max(rep["median_seconds"].get<double>(), 1e-6) / work;
  if (ref.gradient.is_null() && c.evaluator == "cached" && rep["overflowed_cells"] == 0 &&
      (c.precision == "float128" || c.precision == "long-double")) {
    ref.gradient = rep["gradient_exact"];
    ref.name = c.precision;
    ref.energy = ParseExact(rep["energy_exact"]);
  }
  if (ref.gradient.is_null()) return;
  long double gmax = 0, emax = 0;
  const json& g = rep["gradient_exact"];
  for (std::size_t k = 0; k < g.size(); ++k) {
    const long double reference = ParseExact(ref.gradient[k]);
    gmax = std::max(gmax, std::fabs(reference));
    emax = std::max(emax, std::fabs(ParseExact(g[k]) - reference));
  }
  row["gradient_error"] = double(gmax > 0 ? emax / gmax : emax);
  row["energy_error"] =
      double(std::fabs(ParseExact(rep["energy_exact"]) - ref.energy) / std::max(std::fabs(ref.energy), 1e-300L));
  row["reference"] = ref.name;
}

// A case's line of the Markdown table.
std::string PrecisionLine(const json& row, int r, const Split& split, int n, const PrecisionConfig& c) {
  std::string line = "| " + std::to_string(r) + " (" + std::to_string(split.top) + "/" + std::to_string(split.bottom) +
                     ") | " + std::to_string(n) + "³ | " + c.evaluator + " | " + c.precision + " | ";
  if (row.contains("skipped")) return line + "skipped: " + row["skipped"].get<std::string>() + " | | | | |\n";
  line += Fmt("%.3g", row["median_seconds"].get<double>()) + " | " + Fmt("%.12f", row["energy"].get<double>()) + " | ";
  if (row.contains("gradient_error"))
    line += Fmt("%.1e", row["gradient_error"].get<double>()) + (row["reference"] == "float128" ? "" : " (vs long double)");
  else
    line += "no reference";
  return line + " | " + std::to_string(row["overflowed_cells"].get<long long>()) + " / " +
         std::to_string(row["cells"].get<long long>()) + " | " + Fmt("%.0f MB", row["peak_memory_mb"].get<double>()) +
         " |\n";
}

// `quijibo bench precision`: every grid x root count x configuration, then the JSON and the table.
void BenchPrecision(const PrecisionArgs& a) {
  const std::vector<int> roots = a.quick ? std::vector<int>{108} : ParseList(a.roots, "roots");
  const std::vector<int> grids = a.quick ? std::vector<int>{25} : ParseList(a.grids, "grids");
  // float128 first: it is the reference for the gradient error.
  const std::vector<PrecisionConfig> configs = {{"cached", "float128"}, {"cached", "long-double"},
                                                {"cached", "double"},   {"cached", "float"},
                                                {"loglinear", "double"}};
  // Seconds per (cell x root) of one evaluation, learned from the cases run so far.
  std::map<std::string, double> rate;
  json results = json::array();
  std::string md =
      "| roots (top/bottom) | grid | evaluator | precision | s / eval (median) | energy psi | "
      "max rel. gradient error | overflowed cells | peak memory |\n"
      "|---|---|---|---|---|---|---|---|---|\n";
  const double total_cases = double(roots.size() * grids.size() * configs.size());
  Progress progress("bench precision", total_cases, false);
  int done = 0;
  for (int n : grids) {
    for (int r : roots) {
      const Split split = SplitFor(r);
      PrecisionReference ref;
      for (const PrecisionConfig& c : configs) {
        progress.update(done++, std::to_string(r) + " roots, " + std::to_string(n) + "^3, " + c.evaluator + " " +
                                    c.precision);
        json row = {{"roots", r}, {"top", split.top}, {"bottom", split.bottom}, {"grid", n},
                    {"evaluator", c.evaluator}, {"precision", c.precision}};
        MeasurePrecisionCase(a, r, n, c, rate, ref, row);
        results.push_back(row);
        md += PrecisionLine(row, r, split, n, c);
      }
    }
  }
  progress.finish();
  char host[256] = {0};
  ::gethostname(host, sizeof host - 1);
  const std::time_t now = std::time(nullptr);
  char date[32];
  std::strftime(date, sizeof date, "%Y-%m-%d", std::gmtime(&now));
  const json doc = {{"benchmark", "precision"}, {"date", date}, {"cores", int(::sysconf(_SC_NPROCESSORS_ONLN))},
                    {"repeats", a.repeats}, {"exponent_range", {a.exponent_min, a.exponent_max}},
                    {"seed", a.seed}, {"results", results}};
  const std::string header = "Precision benchmark, " + std::string(date) + ", " +
                             std::to_string(int(::sysconf(_SC_NPROCESSORS_ONLN))) + " cores, median of " +
                             std::to_string(a.repeats) + " evaluations; gradient error = max_k |g_k - ref_k| / "
                             "max_k |ref_k| against cached float128 (or long double where float128 was "
                             "skipped); seeded random maps, exponents in [" +
                             Fmt("%g", a.exponent_min) + ", " + Fmt("%g", a.exponent_max) +
                             "], sphere target, layer weights, alpha 10.\n\n";
  if (!a.out_json.empty()) WriteOutput(a.out_json, doc.dump(1) + "\n");
  if (!a.out_md.empty()) WriteOutput(a.out_md, header + md);
  std::fputs((header + md).c_str(), stdout);
}

}  // namespace

void AddBenchPrecisionCommands(CLI::App& bench) {
  CLI::App* b = &bench;  // precision and precision-case

  // precision
  auto a = std::make_shared<PrecisionArgs>();
  CLI::App* p = b->add_subcommand(
      "precision",
      "Seconds per energy+gradient evaluation, energy, gradient error against float128, overflowed "
      "cells and peak memory: cached float/double/long double/float128 and loglinear double");
  p->add_option("--roots", a->roots, "Root counts (paper splits for 108, 331, 364, 708)")->capture_default_str();
  p->add_option("--grids", a->grids, "Grid resolutions N (N^3 cells)")->capture_default_str();
  p->add_option("--repeats", a->repeats, "Evaluations per case (the median is reported)")
      ->capture_default_str()
      ->check(CLI::Range(1, 100));
  p->add_option("--max-seconds", a->max_seconds,
                "Skip a case whose predicted time (from the smaller cases) exceeds this")
      ->capture_default_str();
  p->add_flag("--quick", a->quick, "Only 108 roots at 25^3 (a minute)");
  p->add_option("--seed", a->seed, "Seed of the random maps")->capture_default_str();
  p->add_option("--exponent-min", a->exponent_min, "Smallest random exponent")->capture_default_str();
  p->add_option("--exponent-max", a->exponent_max, "Largest random exponent")->capture_default_str();
  p->add_option("--json", a->out_json, "Write the results as JSON here")->capture_default_str();
  p->add_option("--markdown", a->out_md, "Write the Markdown table here")->capture_default_str();
  p->callback([a] { BenchPrecision(*a); });

  // precision-case: one case, run by `precision` in a child process.
  auto s = std::make_shared<CaseSpec>();
  CLI::App* pc = b->add_subcommand("precision-case", "One case of `bench precision` (used internally)");
  pc->group("");  // hidden from --help
  pc->add_option("--roots", s->roots);
  pc->add_option("--grid", s->grid);
  pc->add_option("--evaluator", s->evaluator);
  pc->add_option("--precision", s->precision);
  pc->add_option("--storage", s->storage);
  pc->add_option("--repeats", s->repeats);
  pc->add_option("--seed", s->seed);
  pc->add_option("--exponent-min", s->exponent_min);
  pc->add_option("--exponent-max", s->exponent_max);
  pc->callback([s] { RunCase(*s); });
}

}  // namespace quijibo::cli
