// Running the `quijibo` binary from a test, as a user would: the one launcher of the command tests.
//   RunQuijibo("mesh map.json -o m.ply")       `quijibo --quiet ARGS 2>&1` through the shell
//   RunQuijiboArgs({"run", exp}, options)      the binary itself, without a shell: stderr apart,
//                                              a file-size limit, an extra environment variable,
//                                              as the user nobody, or in the background
#pragma once
#include <grp.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fcntl.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace quijibo::testing {

struct CommandResult {
  int code;         // the exit status (-1 when killed by a signal)
  std::string out;  // stdout and stderr together (RunQuijibo); stdout (RunQuijiboArgs)
  std::string err;  // stderr (RunQuijiboArgs)
};

struct LaunchOptions {
  // "NAME=value" added to the child's environment.
  std::string env;
  // Every file the child writes is limited to this (0: no limit); SIGXFSZ is ignored, so an
  // over-long write fails with EFBIG as a write to a full disk fails with ENOSPC.
  rlim_t max_file_bytes = 0;
  // Run as the user nobody (a test running as root ignores file permissions otherwise).
  bool as_nobody = false;
  // Return at once with the child's pid here (no output collected).
  pid_t* background = nullptr;
};

// Runs `argv` (argv[0] the program) with stdout and stderr into temporary files.
inline CommandResult Launch(const std::vector<std::string>& argv, const LaunchOptions& o = {}) {
  const auto tmp = std::filesystem::temp_directory_path();
  static int count = 0;
  const std::string tag = std::to_string(::getpid()) + "_" + std::to_string(count++);
  const std::string out_path = (tmp / ("quijibo_test_out_" + tag)).string();
  const std::string err_path = (tmp / ("quijibo_test_err_" + tag)).string();
  std::vector<std::string> words = argv;
  std::vector<char*> args;
  for (auto& a : words) args.push_back(a.data());
  args.push_back(nullptr);
  std::string env = o.env;
  const pid_t pid = fork();
  if (pid == 0) {
    if (o.max_file_bytes) {
      const rlimit limit{o.max_file_bytes, o.max_file_bytes};
      setrlimit(RLIMIT_FSIZE, &limit);
      signal(SIGXFSZ, SIG_IGN);
    }
    const int out = open(o.background ? "/dev/null" : out_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    const int err = open(o.background ? "/dev/null" : err_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    dup2(out, STDOUT_FILENO);
    dup2(err, STDERR_FILENO);
    if (!env.empty()) ::putenv(env.data());
    if (o.as_nobody && (::setgroups(0, nullptr) != 0 || ::setgid(65534) != 0 || ::setuid(65534) != 0)) _exit(126);
    execv(args[0], args.data());
    _exit(127);
  }
  if (o.background) {
    *o.background = pid;
    return {0, "", ""};
  }
  int status = 0;
  waitpid(pid, &status, 0);
  auto slurp = [](const std::string& p) {
    std::ifstream in(p);
    std::string text((std::istreambuf_iterator<char>(in)), {});
    std::filesystem::remove(p);
    return text;
  };
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, slurp(out_path), slurp(err_path)};
}

// `quijibo ARGS...` without a shell.
inline CommandResult RunQuijiboArgs(const std::vector<std::string>& args, const LaunchOptions& o = {}) {
  std::vector<std::string> argv = {QUIJIBO_BINARY};
  argv.insert(argv.end(), args.begin(), args.end());
  return Launch(argv, o);
}

// `quijibo --quiet ARGS 2>&1` through the shell (ARGS may redirect); `env` ("NAME=value ...",
// shell words) is set for this command only.
inline CommandResult RunQuijibo(const std::string& args, const std::string& env = "") {
  const std::string cmd =
      (env.empty() ? "" : "env " + env + " ") + std::string(QUIJIBO_BINARY) + " --quiet " + args + " 2>&1";
  return Launch({"/bin/sh", "-c", cmd});
}

// Any shell command line, stdout and stderr together in `out`.
inline CommandResult RunShell(const std::string& cmd) { return Launch({"/bin/sh", "-c", cmd + " 2>&1"}); }

}  // namespace quijibo::testing
