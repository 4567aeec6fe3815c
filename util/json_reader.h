// Strict reading of JSON documents with errors that point at the offending value:
//   "map.json: /top/3/exponent: expected a number >= 0, found -1"
// Unknown keys are errors, with a suggestion when one is close to a known key.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace quijibo {

class JsonReader {
 public:
  // `source` names the document in messages (usually its path).
  JsonReader(const nlohmann::json& doc, std::string source) : doc_(doc), source_(std::move(source)) {}

  // Throws quijibo::Error "<source>: <pointer>: <what>".
  [[noreturn]] void fail(const std::string& pointer, const std::string& what) const;

  // The value at pointer, or throws "missing".
  const nlohmann::json& at(const std::string& pointer) const;
  bool has(const std::string& pointer) const;
  // Throws if the object at pointer has keys outside `allowed`.
  void allow_keys(const std::string& pointer, const std::vector<std::string>& allowed) const;

  double number(const std::string& pointer) const;
  double number_or(const std::string& pointer, double fallback) const;
  double number_at_least(const std::string& pointer, double min) const;
  long long integer(const std::string& pointer) const;
  bool boolean_or(const std::string& pointer, bool fallback) const;
  std::string string(const std::string& pointer) const;
  std::string string_or(const std::string& pointer, const std::string& fallback) const;
  std::size_t array_size(const std::string& pointer) const;

  const std::string& source() const { return source_; }

  // "a number", "a string", ... for messages; `value` itself, abbreviated, after "found".
  static std::string describe(const nlohmann::json& value);

 private:
  const nlohmann::json& doc_;
  std::string source_;
};

// Parses text as JSON, reporting "<source>:<line>:<column>: invalid JSON: ..." on a syntax error and
// "<source>: invalid JSON: ..." on a value the parser cannot hold (1e99999). `first_line` is the
// line number of the text's first line (for one line of a JSON-lines file).
nlohmann::json ParseJson(const std::string& text, const std::string& source, std::size_t first_line = 1);

// The known key an unknown one was probably meant as (a typo, another spelling, an abbreviation),
// or "" when none is close: the "did you mean" of unknown-key errors.
std::string SuggestKey(const std::string& key, const std::vector<std::string>& allowed);

// Edit distance, for "did you mean" suggestions.
int EditDistance(const std::string& a, const std::string& b);

}  // namespace quijibo
