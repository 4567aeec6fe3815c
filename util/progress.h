// Progress of long work on stderr: "stage  42%  ETA 1m05s". Silent when stderr is not a
// terminal or when quiet; the last line is cleared when done.
#pragma once

#include <chrono>
#include <string>

namespace quijibo {

class Progress {
 public:
  Progress(std::string stage, double total, bool quiet);
  ~Progress();
  // Reports `done` units of `total`; redraws at most ~5 times a second.
  void update(double done, const std::string& detail = {});
  void finish();
  static bool& globally_quiet();  // set by --quiet

 private:
  std::string stage_;
  double total_;
  bool enabled_;
  bool finished_ = false;
  std::chrono::steady_clock::time_point start_, last_;
};

// "1h02m", "3m05s", "4.2s".
std::string FormatDuration(double seconds);

}  // namespace quijibo
