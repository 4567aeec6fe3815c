// Child processes, one helper for every command that starts one: a program (no shell) with its
// standard streams on files, /dev/null or a pipe we read, waited for with its resource usage
// (wait4: the child's own peak memory and CPU time). Benchmarks run each case in a child so its
// peak memory is its own and a case that runs out of memory cannot take the others with it.
#pragma once

#include <sys/resource.h>
#include <sys/types.h>

#include <functional>
#include <string>
#include <vector>

namespace quijibo {

struct ChildOptions {
  std::string program;            // a path, or with `search_path` a name looked up on PATH
  std::vector<std::string> args;  // argv[1...]
  std::string argv0;              // argv[0]; empty: `program`
  bool search_path = false;
  // Where the standard streams go: a file (created or truncated), "" to inherit ours. stdout may
  // instead be read through a pipe into ChildResult::out.
  std::string stdin_path = "/dev/null";
  std::string stdout_path, stderr_path;
  bool capture_stdout = false;
  int file_mode = 0644;  // of the stdout and stderr files
};

struct ChildResult {
  int exit_code = 0;  // the exit status, or 128 + the signal
  bool signaled = false;
  int signal = 0;
  std::string out;                           // stdout, with capture_stdout
  double wall_seconds = 0, cpu_seconds = 0;  // user + system
  double peak_rss_mb = 0;
  bool ok() const { return !signaled && exit_code == 0; }
  std::string Describe() const;  // "exit code 3", "killed by signal 9"
};

// A started child; Wait or Poll collect it (the destructor waits for a child not yet collected).
class ChildProcess {
 public:
  // Throws quijibo::Error when it cannot start (the message names the program and the reason;
  // ENOENT for a program that does not exist).
  explicit ChildProcess(const ChildOptions& options);
  // Runs `body` in a forked copy of this process (no exec); its return value is the child's
  // ChildResult::out, its exit code 0 (2 if writing the result failed).
  explicit ChildProcess(const std::function<std::string()>& body);
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;
  ~ChildProcess();

  pid_t pid() const { return pid_; }
  ChildResult Wait();
  // Collects the child if it has finished (true, `result` filled), else returns false at once.
  bool Poll(ChildResult* result);

 private:
  void Finish(int status, const ::rusage& usage, ChildResult* result);
  pid_t pid_ = -1;
  int out_fd_ = -1;
  double start_ = 0;
  std::string out_;
};

// Starts, waits and returns the result.
ChildResult RunChild(const ChildOptions& options);

// This executable (/proc/self/exe), for running our own commands in a child.
std::string SelfExecutable();

}  // namespace quijibo
