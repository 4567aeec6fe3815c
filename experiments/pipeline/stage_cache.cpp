#include "experiments/pipeline/stage_cache.h"

#include <chrono>
#include <cstdio>
#include <filesystem>

#include "experiments/pipeline/product.h"
#include "util/hash.h"
#include "util/io.h"

namespace quijibo::pipeline {

using nlohmann::json;
namespace fs = std::filesystem;

std::string StageHash(const std::string& stage, const json& inputs, const std::vector<std::string>& files,
                      const std::vector<std::string>& upstream) {
  Fnv1a h;
  h.add("quijibo-stage-v1");
  h.add(stage);
  h.add(inputs.dump());  // nlohmann's objects are sorted by key: canonical
  for (const auto& f : files) {
    Fnv1a file;
    file.add(ReadFile(f));
    h.add(file.hex());
  }
  for (const auto& u : upstream) h.add(u);
  return h.hex();
}

json ReadStageFile(const std::string& path) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) return nullptr;
  try {
    return json::parse(ReadFile(path));
  } catch (...) {
    return nullptr;
  }
}

StageCache::StageCache(std::string results, bool resume, std::function<void(const std::string&)> announce,
                       std::function<void(const std::string&)> note, std::function<void(const StageRecord&)> done,
                       std::function<void(const std::string&)> computing)
    : results_(std::move(results)),
      resume_(resume),
      announce_(std::move(announce)),
      note_(std::move(note)),
      done_(std::move(done)),
      computing_(std::move(computing)) {}

bool StageCache::Reuse(const std::string& name, const std::string& hash, const std::string& dir) {
  const json old = ReadStageFile(dir + "/stage.json");
  if (!old.is_object() || old.value("hash", "") != hash || !old.value("complete", false)) return false;
  records_.push_back({name, "reused", hash, old.value("seconds", 0.0)});
  done_(records_.back());
  return true;
}

std::string StageCache::Run(const std::string& name, const std::string& folder, const json& inputs,
                            const std::vector<std::string>& files, const std::vector<std::string>& upstream,
                            const std::function<void(const std::string&)>& compute) {
  announce_(name);
  const std::string hash = StageHash(name, inputs, files, upstream);
  const std::string dir = Path(folder);
  if (Reuse(name, hash, dir)) return hash;
  const std::string partial = dir + ".partial";
  fs::remove_all(partial);
  fs::create_directories(partial);
  const auto t0 = std::chrono::steady_clock::now();
  try {
    if (computing_) computing_(folder);
    compute(partial);
  } catch (...) {
    std::error_code ec;
    fs::remove_all(partial, ec);
    throw;
  }
  const double s = Since(t0);
  WriteFileAtomically(
      partial + "/stage.json",
      json{{"stage", name}, {"hash", hash}, {"complete", true}, {"seconds", s}, {"inputs", inputs}}.dump(1) + "\n");
  fs::remove_all(dir);
  fs::rename(partial, dir);
  records_.push_back({name, "ran", hash, s});
  done_(records_.back());
  return hash;
}

std::string StageCache::RunInPlace(const std::string& stage, const std::string& name, const std::string& title,
                                   const std::string& folder, const json& inputs,
                                   const std::vector<std::string>& upstream,
                                   const std::function<void(const std::string&, bool)>& compute) {
  announce_(title);
  const std::string hash = StageHash(stage, inputs, {}, upstream);
  const std::string dir = Path(folder);
  if (Reuse(name, hash, dir)) return hash;
  const json pending = ReadStageFile(dir + "/stage.pending.json");
  std::error_code ec;
  const bool can_resume = resume_ && pending.is_object() && pending.value("hash", "") == hash &&
                          fs::is_regular_file(dir + "/checkpoint.json", ec);
  if (resume_ && !can_resume) note_("no checkpoint of these settings in " + dir + ": starting the optimization afresh");
  if (computing_) computing_(folder);
  double earlier = 0;
  if (!can_resume) {
    fs::remove_all(dir);
    fs::create_directories(dir);
    WriteFileAtomically(dir + "/stage.pending.json", json{{"stage", stage}, {"hash", hash}}.dump() + "\n");
  } else {
    earlier = pending.value("seconds", 0.0);
  }
  const auto t0 = std::chrono::steady_clock::now();
  try {
    compute(dir, can_resume);
  } catch (...) {
    // Keep the folder (checkpoint) for --resume; remember the time spent.
    try {
      WriteFileAtomically(dir + "/stage.pending.json",
                          json{{"stage", stage}, {"hash", hash}, {"seconds", earlier + Since(t0)}}.dump() + "\n");
    } catch (...) {
    }
    throw;
  }
  const double s = earlier + Since(t0);
  WriteFileAtomically(
      dir + "/stage.json",
      json{{"stage", stage}, {"hash", hash}, {"complete", true}, {"seconds", s}, {"inputs", inputs}}.dump(1) + "\n");
  fs::remove(dir + "/stage.pending.json");
  records_.push_back({name, can_resume ? "resumed" : "ran", hash, s});
  done_(records_.back());
  return hash;
}

}  // namespace quijibo::pipeline
