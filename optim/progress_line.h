// The observer that draws "level 25 pass F  42%  psi -0.31" on a terminal (util/progress.h):
// one progress bar per pass, against the pass's iteration cap. Internal to optim/.
#pragma once

#include <memory>
#include <string>

#include "optim/iteration_callback.h"
#include "optim/schedule.h"
#include "util/progress.h"

namespace quijibo::optim {

class ProgressLine : public IterationCallback {
 public:
  explicit ProgressLine(const Schedule& schedule) : schedule_(schedule) {}
  CallbackReturnType operator()(const IterationSummary& s) override {
    using T = IterationSummary::Type;
    // A resumed pass has no pass_start record: its first iteration opens the bar.
    if (s.type == T::kPassStart || (s.type == T::kIteration && !bar_)) {
      const LevelSpec& level = schedule_.levels[std::size_t(s.level_index)];
      const PassSpec& pass = level.passes[std::size_t(s.pass_index)];
      bar_ = std::make_unique<Progress>(
          "level " + std::to_string(level.resolution) + " pass " + std::string(1, char(pass.kind)),
          pass.max_iterations, false);
    }
    if (s.type == T::kIteration) bar_->update(s.iteration, "psi " + std::to_string(s.energy));
    if (s.type == T::kPassEnd) bar_.reset();
    return CallbackReturnType::kContinue;
  }

 private:
  const Schedule& schedule_;
  std::unique_ptr<Progress> bar_;
};

}  // namespace quijibo::optim
