#include "experiments/pipeline/convergence_log.h"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <optional>
#include <set>

#include "util/error.h"
#include "util/io.h"
#include "util/json_reader.h"

namespace quijibo::pipeline {

using nlohmann::json;

namespace {

// "<level> <pass>" from whichever of the two keys a line has.
std::string PassLabel(const JsonReader& r) {
  std::string label;
  if (r.has("/level") && r.at("/level").is_number()) label = r.at("/level").dump();
  if (r.has("/pass") && r.at("/pass").is_string()) {
    if (!label.empty()) label += " ";
    label += r.at("/pass").get<std::string>();
  }
  return label;
}

// Identifies the pass an iteration line belongs to (empty when the line names none).
std::string PassKey(const json& j) {
  std::string key;
  for (const char* k : {"level", "level_index", "pass", "pass_index"})
    if (j.contains(k)) key += std::string(k) + "=" + j[k].dump() + ";";
  return key;
}

// psi of key `pointer`, or nothing for null (a NaN the writer could not put into JSON).
std::optional<double> Energy(const JsonReader& r, const std::string& pointer) {
  if (r.at(pointer).is_null()) return std::nullopt;
  return r.number(pointer);
}

constexpr const char* kExpected =
    "expected an optimizer log: one JSON object with a \"type\" per line, as quijibo optimize and run write";

}  // namespace

bool HasEnergies(const ConvergenceLog& log) {
  for (const auto& segment : log.relative)
    if (!segment.empty()) return true;
  return !log.absolute.empty();
}

ConvergenceLog ReadConvergenceLog(const std::string& path) {
  ConvergenceLog log;
  log.path = path;
  const std::string text = ReadFile(path);
  std::vector<std::string> lines;
  for (std::size_t b = 0; b <= text.size();) {
    std::size_t e = text.find('\n', b);
    if (e == std::string::npos) e = text.size();
    lines.push_back(text.substr(b, e - b));
    b = e + 1;
  }
  std::size_t last = lines.size();
  while (last > 0 && IsBlank(lines[last - 1])) --last;  // the last non-blank line is lines[last - 1]

  bool any_line = false;
  std::string current_pass;  // PassKey of the current segment
  bool open_segment = false;
  std::vector<ConvergenceLog::Point> pass_end_absolute;
  for (std::size_t n = 1; n <= last; ++n) {
    const std::string& line = lines[n - 1];
    if (IsBlank(line)) continue;
    const std::string where = path + ":" + std::to_string(n);
    // A file whose first line is not a log line (a pretty-printed summary.json, a map) is named as
    // what it is not; "invalid JSON" would send the user looking for a syntax error.
    const bool first = !any_line;
    any_line = true;
    json j;
    try {
      j = ParseJson(line, path, n);
    } catch (const Error&) {
      if (first && n != last) throw Error(path + ": not a log.jsonl (" + kExpected + ")");
      if (n != last) throw;
      std::fprintf(stderr, "quijibo: warning: %s: skipped the unparsable last line (a killed run?)\n", where.c_str());
      log.truncated = true;
      break;
    }
    const JsonReader r(j, where);
    if (first && !(j.is_object() && j.contains("type")))
      throw Error(path + ": not a log.jsonl (" + kExpected + ")");
    if (!j.is_object()) r.fail("", "expected a JSON object, found " + JsonReader::describe(j));
    const std::string type = r.string("/type");
    if (type == "run") {
      log.run = j;
      // The start map's absolute energy: the first point of the absolute curve.
      if (r.has("/absolute_energy") && r.has("/step"))
        if (const auto psi = Energy(r, "/absolute_energy")) pass_end_absolute.push_back({r.integer("/step"), *psi});
    } else if (type == "pass_start") {
      const long long step = r.integer("/step");
      log.passes.push_back({step, PassLabel(r)});
      current_pass = PassKey(j);
      open_segment = false;
    } else if (type == "iteration") {
      const long long step = r.integer("/step");
      const std::string key = PassKey(j);
      if (key != current_pass) {
        // A pass the log did not announce (e.g. no pass_start lines, or a log begun mid-pass).
        if (!key.empty()) log.passes.push_back({step, PassLabel(r)});
        current_pass = key;
        open_segment = false;
      }
      if (!open_segment) {
        if (log.relative.empty() || !log.relative.back().empty()) log.relative.emplace_back();
        open_segment = true;
      }
      if (const auto psi = Energy(r, "/energy")) log.relative.back().push_back({step, *psi});
    } else if (type == "absolute") {
      const long long step = r.integer("/step");
      if (const auto psi = Energy(r, "/energy")) log.absolute.push_back({step, *psi});
    } else if (type == "pass_end") {
      const long long step = r.integer("/step");
      // The optimizer writes "absolute_end"; "absolute_energy" is the older name.
      for (const char* key : {"/absolute_end", "/absolute_energy"})
        if (r.has(key)) {
          if (const auto psi = Energy(r, key)) pass_end_absolute.push_back({step, *psi});
          break;
        }
      open_segment = false;
    }
    // Other line types are for other readers.
  }
  while (!log.relative.empty() && log.relative.back().empty()) log.relative.pop_back();
  std::set<long long> covered;
  for (const auto& p : log.absolute) covered.insert(p.step);
  for (const auto& p : pass_end_absolute)
    if (covered.insert(p.step).second) log.absolute.push_back(p);
  std::stable_sort(log.absolute.begin(), log.absolute.end(),
                   [](const auto& a, const auto& b) { return a.step < b.step; });
  // Two marks at one step (pass_start followed by an unannounced change) keep the later label.
  std::vector<ConvergenceLog::PassMark> marks;
  for (const auto& m : log.passes) {
    if (!marks.empty() && marks.back().step == m.step)
      marks.back() = m;
    else
      marks.push_back(m);
  }
  log.passes = std::move(marks);
  return log;
}

}  // namespace quijibo::pipeline
