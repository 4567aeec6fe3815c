// Comparing what two runs wrote, byte for byte, apart from wall-clock fields: for tests of resume
// and of determinism across thread counts.
#pragma once
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <string>

namespace quijibo::testing {

inline std::string SlurpFile(const std::string& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), {});
}

// A key that holds a time, or a size that depends on one (a log's byte count, whose "seconds"
// digits vary), or the thread count, or the narrow band's work counters (a resumed process
// re-anchors its band, so it counts other work for the same energies).
inline bool IsClockKey(const std::string& k) {
  return k == "seconds" || k.ends_with("_seconds") || k.starts_with("seconds_") || k == "log_bytes" ||
         k == "threads" || k == "date" || k == "band";
}

// `j` without clock keys, at any depth.
inline nlohmann::json WithoutClock(nlohmann::json j) {
  if (j.is_object()) {
    for (auto it = j.begin(); it != j.end();) it = IsClockKey(it.key()) ? j.erase(it) : std::next(it);
    for (auto& [k, v] : j.items()) v = WithoutClock(v);
  } else if (j.is_array()) {
    for (auto& v : j) v = WithoutClock(v);
  }
  return j;
}

// The file's text with clock keys removed: JSON and JSON lines are parsed and dumped again; an
// OpenVDB file without its UUID (36 characters after the 21-byte header, new at every write); any
// other file as it is. Occurrences of `folder` (the run's output folder, which files may name) are
// replaced by "OUT".
inline std::string Comparable(const std::filesystem::path& p, const std::string& folder = "") {
  std::string text = SlurpFile(p.string());
  if (!folder.empty())
    for (std::size_t k; (k = text.find(folder)) != std::string::npos;) text.replace(k, folder.size(), "OUT");
  if (p.extension() == ".vdb" && text.size() >= 57) return text.substr(0, 21) + text.substr(57);
  if (p.extension() == ".json") return WithoutClock(nlohmann::json::parse(text)).dump(1);
  if (p.extension() == ".jsonl") {
    std::string out;
    std::istringstream in(text);
    for (std::string line; std::getline(in, line);) out += WithoutClock(nlohmann::json::parse(line)).dump() + "\n";
    return out;
  }
  return text;
}

// Both folders hold the same files (recursively) with the same comparable contents.
inline void ExpectSameOutputs(const std::string& a, const std::string& b) {
  namespace fs = std::filesystem;
  std::set<std::string> names_a, names_b;
  for (const auto& e : fs::recursive_directory_iterator(a))
    if (e.is_regular_file()) names_a.insert(fs::relative(e.path(), a).string());
  for (const auto& e : fs::recursive_directory_iterator(b))
    if (e.is_regular_file()) names_b.insert(fs::relative(e.path(), b).string());
  EXPECT_EQ(names_a, names_b) << a << " vs " << b;
  for (const std::string& n : names_a)
    if (names_b.count(n)) {
      EXPECT_TRUE(Comparable(fs::path(a) / n, a) == Comparable(fs::path(b) / n, b))
          << n << " differs: " << a << " vs " << b;
    }
}

}  // namespace quijibo::testing
