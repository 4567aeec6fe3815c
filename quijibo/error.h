// The toolkit's one exception type. Its message is the one line the command prints: it names
// the file (and line, or JSON pointer) and says what was expected and what was found.
#pragma once

#include <stdexcept>
#include <string>

namespace quijibo {

class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& message) : std::runtime_error(message) {}
};

}  // namespace quijibo
