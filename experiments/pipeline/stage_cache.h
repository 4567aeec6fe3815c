// The stage cache of `quijibo run` (docs/experiments.md): each stage's folder holds stage.json
// with an FNV-1a 64 hash of what the stage read (its resolved settings, the bytes of its input
// files, the hashes of the stages upstream); a rerun with an unchanged hash reuses the folder.
// Stages fill "<folder>.partial" and rename it when done, so a failed stage leaves no partial
// folder; a stage that runs in place (the optimization, whose checkpoint must survive a kill for
// --resume) records its hash in stage.pending.json until it completes.
#pragma once

#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace quijibo::pipeline {

// The content hash of a stage (16 hex digits; stable across runs, compilers and machines).
std::string StageHash(const std::string& stage, const nlohmann::json& inputs, const std::vector<std::string>& files,
                      const std::vector<std::string>& upstream);

struct StageRecord {
  std::string name;
  std::string status;  // "ran", "reused" or "resumed"
  std::string hash;
  double seconds = 0;  // of the run that made it (reused stages keep their time)
};

class StageCache {
 public:
  // `announce` is told each stage as it starts, `note` what a stage has to say, `done` each record
  // as it ends, `computing` the folder of each stage that is not reused, before it computes.
  StageCache(std::string results, bool resume, std::function<void(const std::string&)> announce,
             std::function<void(const std::string&)> note, std::function<void(const StageRecord&)> done,
             std::function<void(const std::string& folder)> computing = nullptr);

  // A stage into `folder` of the results: reused when its hash matches, else `compute(dir)` fills
  // a fresh folder, renamed into place when it returns. Returns the hash.
  std::string Run(const std::string& name, const std::string& folder, const nlohmann::json& inputs,
                  const std::vector<std::string>& files, const std::vector<std::string>& upstream,
                  const std::function<void(const std::string& dir)>& compute);
  // The same in place: `compute(dir, resume)` is asked to resume when --resume was given and the
  // folder holds a checkpoint of the same hash (stage.pending.json). `stage` names the hash's
  // stage kind, `name` the record, `title` the announcement.
  std::string RunInPlace(const std::string& stage, const std::string& name, const std::string& title,
                         const std::string& folder, const nlohmann::json& inputs,
                         const std::vector<std::string>& upstream,
                         const std::function<void(const std::string& dir, bool resume)>& compute);

  const std::vector<StageRecord>& records() const { return records_; }
  std::string Path(const std::string& relative) const { return results_ + "/" + relative; }

 private:
  // A complete stage.json of `hash` in `dir`: the stage is recorded as reused.
  bool Reuse(const std::string& name, const std::string& hash, const std::string& dir);
  std::string results_;
  bool resume_;
  std::function<void(const std::string&)> announce_, note_;
  std::function<void(const StageRecord&)> done_;
  std::function<void(const std::string&)> computing_;
  std::vector<StageRecord> records_;
};

// A JSON file a stage wrote, or null when it is missing or unreadable.
nlohmann::json ReadStageFile(const std::string& path);

}  // namespace quijibo::pipeline
