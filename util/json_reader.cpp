#include "util/json_reader.h"

#include <algorithm>
#include <cctype>
#include <cmath>

#include "util/error.h"

namespace quijibo {

using nlohmann::json;

void JsonReader::fail(const std::string& pointer, const std::string& what) const {
  throw Error(source_ + ": " + (pointer.empty() ? "/" : pointer) + ": " + what);
}

bool JsonReader::has(const std::string& pointer) const {
  return doc_.contains(json::json_pointer(pointer));
}

const json& JsonReader::at(const std::string& pointer) const {
  if (!has(pointer)) fail(pointer, "missing (required)");
  return doc_.at(json::json_pointer(pointer));
}

std::string JsonReader::describe(const json& v) {
  std::string s = v.dump();
  if (s.size() > 40) s = s.substr(0, 37) + "...";
  return std::string(v.type_name()) + " " + s;
}

namespace {

// Letters and digits only, lower case: "maxIterations" and "max-iterations" read as "maxiterations".
std::string Folded(const std::string& s) {
  std::string f;
  for (unsigned char c : s)
    if (std::isalnum(c)) f += char(std::tolower(c));
  return f;
}

}  // namespace

std::string SuggestKey(const std::string& key, const std::vector<std::string>& allowed) {
  // A typo (a small edit distance) or the same key spelt another way.
  std::string best;
  int best_d = 3;
  for (const auto& a : allowed) {
    const int d = Folded(key) == Folded(a) ? 0 : EditDistance(key, a);
    if (d < best_d) best_d = d, best = a;
  }
  if (!best.empty()) return best;
  // An abbreviation or a clipped word ("max_iters" for "max_iterations"): the key is all but its
  // last letters a prefix of a longer known key.
  std::size_t best_prefix = 0;
  for (const auto& a : allowed) {
    std::size_t n = 0;
    while (n < key.size() && n < a.size() && key[n] == a[n]) ++n;
    if (n >= 4 && n + 2 >= key.size() && a.size() > key.size() && n > best_prefix) best_prefix = n, best = a;
  }
  return best;
}

void JsonReader::allow_keys(const std::string& pointer,
                            const std::vector<std::string>& allowed) const {
  const json& obj = pointer.empty() ? doc_ : at(pointer);
  if (!obj.is_object()) fail(pointer, "expected an object, found " + describe(obj));
  for (const auto& [key, value] : obj.items()) {
    if (std::find(allowed.begin(), allowed.end(), key) != allowed.end()) continue;
    const std::string best = SuggestKey(key, allowed);
    fail(pointer + "/" + key,
         "unknown key" + (best.empty() ? std::string() : " (did you mean \"" + best + "\"?)"));
  }
}

double JsonReader::number(const std::string& pointer) const {
  const json& v = at(pointer);
  if (!v.is_number()) fail(pointer, "expected a number, found " + describe(v));
  const double d = v.get<double>();
  if (!std::isfinite(d)) fail(pointer, "expected a finite number");
  return d;
}

double JsonReader::number_or(const std::string& pointer, double fallback) const {
  return has(pointer) ? number(pointer) : fallback;
}

double JsonReader::number_at_least(const std::string& pointer, double min) const {
  const double d = number(pointer);
  if (d < min)
    fail(pointer, "expected a number >= " + json(min).dump() + ", found " + json(d).dump());
  return d;
}

long long JsonReader::integer(const std::string& pointer) const {
  const json& v = at(pointer);
  if (!v.is_number_integer()) fail(pointer, "expected an integer, found " + describe(v));
  return v.get<long long>();
}

bool JsonReader::boolean_or(const std::string& pointer, bool fallback) const {
  if (!has(pointer)) return fallback;
  const json& v = at(pointer);
  if (!v.is_boolean()) fail(pointer, "expected true or false, found " + describe(v));
  return v.get<bool>();
}

std::string JsonReader::string(const std::string& pointer) const {
  const json& v = at(pointer);
  if (!v.is_string()) fail(pointer, "expected a string, found " + describe(v));
  return v.get<std::string>();
}

std::string JsonReader::string_or(const std::string& pointer, const std::string& fallback) const {
  return has(pointer) ? string(pointer) : fallback;
}

std::size_t JsonReader::array_size(const std::string& pointer) const {
  const json& v = at(pointer);
  if (!v.is_array()) fail(pointer, "expected an array, found " + describe(v));
  return v.size();
}

json ParseJson(const std::string& text, const std::string& source, std::size_t first_line) {
  try {
    return json::parse(text);
  } catch (const json::parse_error& e) {
    // Turn the byte offset into line:column.
    std::size_t line = first_line, col = 1;
    for (std::size_t i = 0; i + 1 < e.byte && i < text.size(); ++i) {
      if (text[i] == '\n') ++line, col = 1;
      else ++col;
    }
    std::string what = e.what();
    const auto p = what.find("syntax error");
    if (p != std::string::npos) what = what.substr(p);
    throw Error(source + ":" + std::to_string(line) + ":" + std::to_string(col) +
                ": invalid JSON: " + what);
  } catch (const json::exception& e) {
    // Not a syntax error but a value the parser cannot hold, e.g. 1e99999 (number overflow).
    std::string what = e.what();
    const auto p = what.find("] ");
    if (p != std::string::npos) what = what.substr(p + 2);
    throw Error(source + (first_line == 1 ? std::string() : ":" + std::to_string(first_line)) +
                ": invalid JSON: " + what);
  }
}

int EditDistance(const std::string& a, const std::string& b) {
  std::vector<int> prev(b.size() + 1), cur(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) prev[j] = int(j);
  for (std::size_t i = 1; i <= a.size(); ++i) {
    cur[0] = int(i);
    for (std::size_t j = 1; j <= b.size(); ++j)
      cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, prev[j - 1] + (a[i - 1] != b[j - 1])});
    std::swap(prev, cur);
  }
  return prev[b.size()];
}

}  // namespace quijibo
