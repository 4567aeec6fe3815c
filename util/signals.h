// Ctrl-C and termination: the one place SIGINT and SIGTERM handlers are installed. A run (its
// stages) and an optimization (which checkpoints and returns) each take them with their own
// async-signal-safe handler for their lifetime, nested: the inner guard puts the outer's back.
#pragma once

#include <signal.h>

namespace quijibo {

// Installs `handler` (async-signal-safe: it may only set a flag or write to a pipe) for SIGINT and
// SIGTERM; the destructor restores the handlers that were there before.
class InterruptGuard {
 public:
  explicit InterruptGuard(void (*handler)(int));
  ~InterruptGuard();
  InterruptGuard(const InterruptGuard&) = delete;
  InterruptGuard& operator=(const InterruptGuard&) = delete;

 private:
  struct sigaction old_int_ {}, old_term_ {};
};

}  // namespace quijibo
