#include "optim/schedule.h"

#include <cctype>
#include <cmath>

#include "util/error.h"
#include "util/json_reader.h"

namespace quijibo::optim {

namespace {
bool ParseKind(char c, PassKind& k) {
  switch (c) {
    case 'V': k = PassKind::kVariable; return true;
    case 'F': k = PassKind::kFull; return true;
    case 'R': k = PassKind::kReweighted; return true;
  }
  return false;
}
}  // namespace

int PassKindIndex(PassKind k) { return k == PassKind::kVariable ? 0 : k == PassKind::kFull ? 1 : 2; }

PassSpec DefaultPass(PassKind kind) {
  PassSpec p;
  p.kind = kind;
  p.max_iterations = kDefaultMaxIterations[PassKindIndex(kind)];
  return p;
}

const Schema<PassSpec>& PassSpec::Settings() {
  static const Schema<PassSpec> s =
      Schema<PassSpec>()
          .Integer(
              "max_iterations", "", "Iteration cap of the pass", [](auto& p) -> int& { return p.max_iterations; },
              kMaxIterationsRange)
          .Number(
              "tolerance", "", "Projected-gradient tolerance (infinity norm) of the pass",
              [](auto& p) -> double& { return p.tolerance; }, kToleranceRange);
  return s;
}

std::string PassSpec::Validate() const { return Settings().Check(*this); }

Schedule Schedule::Parse(const std::string& text, const PassSpec defaults[3]) {
  Schedule s;
  std::size_t i = 0;
  auto fail = [&](const std::string& what) {
    throw Error("schedule \"" + text + "\": at character " + std::to_string(i + 1) + ": " + what +
                " (expected levels like 25(VFRF)50(VF))");
  };
  auto skip = [&] {
    while (i < text.size() && std::isspace(static_cast<unsigned char>(text[i]))) ++i;
  };
  skip();
  while (i < text.size()) {
    if (!std::isdigit(static_cast<unsigned char>(text[i]))) fail("expected a resolution");
    long n = 0;
    while (i < text.size() && std::isdigit(static_cast<unsigned char>(text[i]))) {
      n = n * 10 + (text[i++] - '0');
      if (n > 4096) fail("resolution larger than 4096");
    }
    skip();
    if (i >= text.size() || text[i] != '(') fail("expected '(' after the resolution");
    ++i;
    LevelSpec level;
    level.resolution = int(n);
    while (i < text.size() && text[i] != ')') {
      PassKind k;
      if (std::isspace(static_cast<unsigned char>(text[i]))) { ++i; continue; }
      if (!ParseKind(char(std::toupper(static_cast<unsigned char>(text[i]))), k))
        fail(std::string("unknown pass '") + text[i] + "' (passes are V, F and R)");
      level.passes.push_back(defaults ? defaults[PassKindIndex(k)] : DefaultPass(k));
      level.passes.back().kind = k;
      ++i;
    }
    if (i >= text.size()) fail("missing ')'");
    ++i;
    if (level.passes.empty()) fail("a level without passes");
    s.levels.push_back(level);
    skip();
  }
  if (auto why = s.Validate(); !why.empty()) throw Error("schedule \"" + text + "\": " + why);
  return s;
}

Schedule Schedule::FromJson(const JsonReader& r, const std::string& ptr) {
  const nlohmann::json& node = r.at(ptr);
  PassSpec defaults[3] = {DefaultPass(PassKind::kVariable), DefaultPass(PassKind::kFull),
                          DefaultPass(PassKind::kReweighted)};
  auto read_pass = [&](const std::string& p, PassSpec& spec) { PassSpec::Settings().Read(r, p, "", spec, {"kind"}); };
  // Notation inside a JSON document: its errors name the document and the key too.
  auto parse = [&](const std::string& p, const std::string& text) {
    try {
      return Parse(text, defaults);
    } catch (const Error& e) {
      r.fail(p, e.what());
    }
  };
  if (node.is_string()) return parse(ptr, node.get<std::string>());
  r.allow_keys(ptr, {"levels", "defaults", "notation"});
  if (r.has(ptr + "/defaults")) {
    r.allow_keys(ptr + "/defaults", {"V", "F", "R"});
    const char* names[3] = {"V", "F", "R"};
    for (int k = 0; k < 3; ++k)
      if (r.has(ptr + "/defaults/" + names[k])) read_pass(ptr + "/defaults/" + names[k], defaults[k]);
  }
  // Notation alone; or levels, with the notation beside them (ToJson's form) only if it agrees.
  if (r.has(ptr + "/notation") && !r.has(ptr + "/levels")) return parse(ptr + "/notation", r.string(ptr + "/notation"));
  Schedule s;
  const std::size_t nl = r.array_size(ptr + "/levels");
  if (nl == 0) r.fail(ptr + "/levels", "expected at least one level");
  for (std::size_t l = 0; l < nl; ++l) {
    const std::string lp = ptr + "/levels/" + std::to_string(l);
    r.allow_keys(lp, {"resolution", "passes"});
    LevelSpec level;
    const long long n = r.integer(lp + "/resolution");
    if (n < 2 || n > 4096) r.fail(lp + "/resolution", "expected an integer in [2, 4096], found " + std::to_string(n));
    level.resolution = int(n);
    const nlohmann::json& passes = r.at(lp + "/passes");
    if (passes.is_string()) {
      const Schedule one = parse(lp + "/passes", std::to_string(n) + "(" + passes.get<std::string>() + ")");
      level.passes = one.levels[0].passes;
    } else {
      const std::size_t np = r.array_size(lp + "/passes");
      if (np == 0) r.fail(lp + "/passes", "expected at least one pass");
      for (std::size_t k = 0; k < np; ++k) {
        const std::string pp = lp + "/passes/" + std::to_string(k);
        const std::string kind = r.string(pp + "/kind");
        PassKind pk;
        if (kind.size() != 1 || !ParseKind(kind[0], pk)) r.fail(pp + "/kind", "expected \"V\", \"F\" or \"R\"");
        PassSpec spec = defaults[PassKindIndex(pk)];
        spec.kind = pk;
        read_pass(pp, spec);
        level.passes.push_back(spec);
      }
    }
    s.levels.push_back(level);
  }
  if (auto why = s.Validate(); !why.empty()) r.fail(ptr, why);
  if (r.has(ptr + "/notation") && r.string(ptr + "/notation") != s.notation())
    r.fail(ptr + "/notation", "\"" + r.string(ptr + "/notation") + "\" does not match the levels (" + s.notation() +
                                  "); give either \"notation\" or \"levels\"");
  return s;
}

nlohmann::json Schedule::ToJson() const {
  nlohmann::json levels = nlohmann::json::array();
  for (const LevelSpec& l : this->levels) {
    nlohmann::json passes = nlohmann::json::array();
    for (const PassSpec& p : l.passes)
      passes.push_back({{"kind", std::string(1, char(p.kind))}, {"max_iterations", p.max_iterations},
                        {"tolerance", p.tolerance}});
    levels.push_back({{"resolution", l.resolution}, {"passes", passes}});
  }
  return {{"notation", notation()}, {"levels", levels}};
}

std::string Schedule::notation() const {
  std::string s;
  for (const LevelSpec& l : levels) {
    s += std::to_string(l.resolution) + "(";
    for (const PassSpec& p : l.passes) s += char(p.kind);
    s += ")";
  }
  return s;
}

int Schedule::pass_count() const {
  int n = 0;
  for (const LevelSpec& l : levels) n += int(l.passes.size());
  return n;
}

std::string Schedule::Validate() const {
  if (levels.empty()) return "the schedule is empty";
  for (const LevelSpec& l : levels) {
    if (l.resolution < 2 || l.resolution > 4096) return "resolutions must be in [2, 4096]";
    if (l.passes.empty()) return "level " + std::to_string(l.resolution) + " has no passes";
    for (const PassSpec& p : l.passes)
      if (auto why = p.Validate(); !why.empty()) return why;
  }
  return {};
}

}  // namespace quijibo::optim
