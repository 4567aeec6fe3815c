// The observer that writes log.jsonl: one line per record (IterationSummary::ToJson), flushed at
// once so that a crash loses nothing logged. Internal to optim/.
#pragma once

#include <fstream>
#include <string>

#include "optim/iteration_callback.h"

namespace quijibo::optim {

class JsonlLog : public IterationCallback {
 public:
  // A fresh, empty log at `path`; or, resuming, the log cut back to the `keep_bytes` a checkpoint
  // recorded (the resumed run writes the later lines again).
  JsonlLog(const std::string& path, long long keep_bytes = -1);
  CallbackReturnType operator()(const IterationSummary& s) override;
  long long bytes();  // the log's size, all lines written

 private:
  std::string path_;
  std::ofstream out_;
};

}  // namespace quijibo::optim
