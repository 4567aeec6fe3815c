// The toolkit's one exception type. Its message is the one line the command prints: it names
// the file (and line, or JSON pointer) and says what was expected and what was found.
#pragma once

#include <csignal>
#include <stdexcept>
#include <string>

namespace quijibo {

class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& message) : std::runtime_error(message) {}
};

// Work stopped by SIGINT or SIGTERM (`signal`): the command prints its message as is, without
// "error:", and exits with 128 + signal as a shell expects of an interrupted program.
class Interrupted : public Error {
 public:
  Interrupted(const std::string& message, int signal) : Error(message), signal(signal) {}
  int signal;
};

// "SIGINT", "SIGTERM" or "signal N", for messages.
inline std::string SignalName(int signal) {
  return signal == SIGINT ? "SIGINT" : signal == SIGTERM ? "SIGTERM" : "signal " + std::to_string(signal);
}

}  // namespace quijibo
