#include "util/progress.h"

#include <unistd.h>

#include <cmath>
#include <cstdio>

namespace quijibo {

bool& Progress::globally_quiet() {
  static bool quiet = false;
  return quiet;
}

Progress::Progress(std::string stage, double total, bool quiet)
    : stage_(std::move(stage)),
      total_(total),
      enabled_(!quiet && !globally_quiet() && ::isatty(STDERR_FILENO)),
      start_(std::chrono::steady_clock::now()),
      last_(start_ - std::chrono::seconds(1)) {}

Progress::~Progress() { finish(); }

void Progress::update(double done, const std::string& detail) {
  if (!enabled_ || finished_) return;
  const auto now = std::chrono::steady_clock::now();
  if (now - last_ < std::chrono::milliseconds(200)) return;
  last_ = now;
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  const double frac = total_ > 0 ? std::min(1.0, done / total_) : 0.0;
  std::string eta = "--";
  if (frac > 0.01) eta = FormatDuration(elapsed * (1 - frac) / frac);
  std::fprintf(stderr, "\r\033[K%s %3.0f%%  ETA %s  %s", stage_.c_str(), 100 * frac, eta.c_str(),
               detail.c_str());
  std::fflush(stderr);
}

void Progress::finish() {
  if (!enabled_ || finished_) return;
  finished_ = true;
  std::fprintf(stderr, "\r\033[K");
  std::fflush(stderr);
}

std::string FormatDuration(double s) {
  char buf[32];
  if (!std::isfinite(s) || s < 0) return "--";
  if (s < 60) std::snprintf(buf, sizeof buf, "%.1fs", s);
  else if (s < 3600) std::snprintf(buf, sizeof buf, "%dm%02ds", int(s) / 60, int(s) % 60);
  else std::snprintf(buf, sizeof buf, "%dh%02dm", int(s) / 3600, (int(s) % 3600) / 60);
  return buf;
}

}  // namespace quijibo
