// checkpoint.json: the run's state, exact (scalars as decimal strings with max_digits10 digits),
// written atomically every checkpoint_every iterations, at pass ends and on an interrupt; and the
// fingerprint that lets --resume continue only the run that wrote it. Internal to optim/.
//
// The fingerprint is an FNV-1a 64 hash of the complete optimizer settings (OptimizeOptions::
// ToJson), the target grid (frame and values) and the initial map (without its provenance). The
// checkpoint stores the settings and the two content hashes beside it, so a refused resume can
// name the first setting that differs.
#pragma once

#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <type_traits>

#include "quijibo/real.h"

#include "optim/jsonl_log.h"
#include "optim/run_state.h"
#include "quijibo/grid.h"
#include "quijibo/rational_map.h"

namespace quijibo::optim {

struct Fingerprint {
  nlohmann::json options;  // OptimizeOptions::ToJson
  std::string target;      // hash of the target grid
  std::string initial_map;  // hash of the initial map
  Fingerprint(const OptimizeOptions& o, const ScalarGrid& sdf, const RationalMap& map);
  std::string hash() const;
};

// "prefix.key[1].sub = <was>, this run has <now>" for the first place where `was` and `now`
// differ (object keys in order, but a schedule's "notation" before its "levels"); "" if equal.
std::string FirstDifference(const nlohmann::json& was, const nlohmann::json& now, const std::string& prefix);

// Throws quijibo::Error "--resume: ..." unless the checkpoint `c` (read from `path`) was written by
// a run with the fingerprint `now`: names the first differing setting, or the target, or the map.
void CheckResumable(const nlohmann::json& c, const std::string& path, const Fingerprint& now);

template <class Scalar>
std::string ExactString(const Scalar& x) {
  std::ostringstream s;
  s.precision(std::numeric_limits<Scalar>::max_digits10);
  s << x;
  return s.str();
}

template <class Scalar>
Scalar ParseExact(const std::string& s) {
  if constexpr (std::is_same_v<Scalar, float128>) return float128(s);
  else if constexpr (std::is_same_v<Scalar, long double>) return std::strtold(s.c_str(), nullptr);
  else if constexpr (std::is_same_v<Scalar, float>) return std::strtof(s.c_str(), nullptr);
  else return std::strtod(s.c_str(), nullptr);
}

// Where a checkpoint says the run continues.
struct CheckpointPosition {
  int level_index = 0, pass_index = 0, iteration = 0;
  long long log_bytes = 0;
  bool complete = false;
};

// Reads `path` into `st` after CheckResumable; `variables` is the map's variable count.
template <class Scalar>
CheckpointPosition ReadCheckpoint(const std::string& path, const Fingerprint& now, Eigen::Index variables,
                                  RunState<Scalar>& st);

// The observer that writes checkpoints: after every checkpoint_every-th iteration (once the
// iteration's records, its absolute line included, are logged, so the log length it records is
// the iteration's end) and after every pass; the optimizer calls Write itself on an interrupt.
template <class Scalar>
class CheckpointWriter : public IterationCallback {
 public:
  using Vector = typename RunState<Scalar>::Vector;
  CheckpointWriter(std::string path, const Fingerprint& fingerprint, const OptimizeOptions& options,
                   const RunState<Scalar>& state, JsonlLog& log)
      : path_(std::move(path)), fingerprint_(fingerprint), hash_(fingerprint.hash()), o_(options), st_(state),
        log_(log) {}

  CallbackReturnType operator()(const IterationSummary& s) override {
    using T = IterationSummary::Type;
    const bool iteration_logged =
        (s.type == T::kIteration && s.iteration % o_.absolute_every != 0) || s.type == T::kAbsolute;
    if (iteration_logged && s.iteration % o_.checkpoint_every == 0)
      Write(s.level_index, s.pass_index, s.iteration, st_.Current(), st_.pass_start_x, false);
    if (s.type == T::kPassEnd) {
      // Continue at the next pass (or level); after the last one the run is complete.
      const int passes = int(o_.schedule.levels[std::size_t(s.level_index)].passes.size());
      const bool next_level = s.pass_index + 1 == passes;
      const bool last = next_level && s.level_index + 1 == int(o_.schedule.levels.size());
      Write(next_level ? s.level_index + 1 : s.level_index, next_level ? 0 : s.pass_index + 1, 0, st_.x, st_.x, last);
    }
    return CallbackReturnType::kContinue;
  }

  // A checkpoint at `iteration` of pass (li, pj) with the iterate `x`.
  void Write(int li, int pj, int iteration, const Vector& x, const Vector& pass_start, bool complete);

 private:
  std::string path_;
  const Fingerprint& fingerprint_;
  std::string hash_;
  const OptimizeOptions& o_;
  const RunState<Scalar>& st_;
  JsonlLog& log_;
};

}  // namespace quijibo::optim

// Instantiated for float, double, long double and float128 in checkpoint.cpp.
