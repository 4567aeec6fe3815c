// Running the `quijibo` binary from a test, as a user would: `quijibo --quiet ARGS 2>&1`.
#pragma once
#include <sys/wait.h>

#include <cstdio>
#include <string>

namespace quijibo::testing {

struct CommandResult {
  int code;         // the exit status (-1 when killed by a signal)
  std::string out;  // stdout and stderr together
};

// `env` ("NAME=value ...", shell words) is set for this command only.
inline CommandResult RunQuijibo(const std::string& args, const std::string& env = "") {
  const std::string cmd = (env.empty() ? "" : "env " + env + " ") + std::string(QUIJIBO_BINARY) + " --quiet " + args + " 2>&1";
  FILE* p = popen(cmd.c_str(), "r");
  if (!p) return {-1, "popen failed"};
  std::string out;
  char buf[4096];
  for (std::size_t n; (n = fread(buf, 1, sizeof buf, p)) > 0;) out.append(buf, n);
  const int status = pclose(p);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}

}  // namespace quijibo::testing
