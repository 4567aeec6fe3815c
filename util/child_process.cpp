#include "util/child_process.h"

#include <fcntl.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>

#include "util/error.h"

extern char** environ;

namespace quijibo {

namespace {

double Now() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

// Appends what is readable on fd; false at end of file.
bool Drain(int fd, std::string& out, bool block) {
  char buf[65536];
  for (;;) {
    const ssize_t n = ::read(fd, buf, sizeof buf);
    if (n > 0) {
      out.append(buf, std::size_t(n));
      continue;
    }
    if (n == 0) return false;
    if (errno == EINTR) continue;
    if (!block && (errno == EAGAIN || errno == EWOULDBLOCK)) return true;
    return false;
  }
}

}  // namespace

std::string ChildResult::Describe() const {
  return signaled ? "killed by signal " + std::to_string(signal) : "exit code " + std::to_string(exit_code);
}

std::string SelfExecutable() { return "/proc/self/exe"; }

ChildProcess::ChildProcess(const ChildOptions& o) {
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  struct Cleanup {
    posix_spawn_file_actions_t* fa;
    ~Cleanup() { posix_spawn_file_actions_destroy(fa); }
  } cleanup{&fa};
  if (!o.stdin_path.empty()) posix_spawn_file_actions_addopen(&fa, STDIN_FILENO, o.stdin_path.c_str(), O_RDONLY, 0);
  int pipe_fd[2] = {-1, -1};
  if (o.capture_stdout) {
    if (::pipe(pipe_fd) != 0) throw Error(o.program + ": cannot create a pipe: " + std::strerror(errno));
    ::fcntl(pipe_fd[0], F_SETFD, FD_CLOEXEC);
    posix_spawn_file_actions_adddup2(&fa, pipe_fd[1], STDOUT_FILENO);
    posix_spawn_file_actions_addclose(&fa, pipe_fd[1]);
  } else if (!o.stdout_path.empty()) {
    posix_spawn_file_actions_addopen(&fa, STDOUT_FILENO, o.stdout_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC,
                                     o.file_mode);
  }
  if (!o.stderr_path.empty())
    posix_spawn_file_actions_addopen(&fa, STDERR_FILENO, o.stderr_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC,
                                     o.file_mode);
  std::vector<std::string> words{o.argv0.empty() ? o.program : o.argv0};
  words.insert(words.end(), o.args.begin(), o.args.end());
  std::vector<char*> argv;
  for (auto& w : words) argv.push_back(w.data());
  argv.push_back(nullptr);
  std::fflush(nullptr);
  start_ = Now();
  const int rc = o.search_path ? ::posix_spawnp(&pid_, o.program.c_str(), &fa, nullptr, argv.data(), environ)
                               : ::posix_spawn(&pid_, o.program.c_str(), &fa, nullptr, argv.data(), environ);
  if (pipe_fd[1] >= 0) ::close(pipe_fd[1]);
  if (rc != 0) {
    if (pipe_fd[0] >= 0) ::close(pipe_fd[0]);
    pid_ = -1;
    throw Error("cannot start " + o.program + ": " + std::strerror(rc));
  }
  out_fd_ = pipe_fd[0];
}

ChildProcess::ChildProcess(const std::function<std::string()>& body) {
  int fd[2];
  if (::pipe(fd) != 0) throw Error(std::string("cannot create a pipe: ") + std::strerror(errno));
  std::fflush(nullptr);
  start_ = Now();
  pid_ = ::fork();
  if (pid_ < 0) {
    ::close(fd[0]), ::close(fd[1]);
    throw Error(std::string("cannot fork: ") + std::strerror(errno));
  }
  if (pid_ == 0) {
    ::close(fd[0]);
    const std::string text = body();
    std::size_t at = 0;
    while (at < text.size()) {
      const ssize_t n = ::write(fd[1], text.data() + at, text.size() - at);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) _exit(2);
      at += std::size_t(n);
    }
    _exit(0);
  }
  ::close(fd[1]);
  out_fd_ = fd[0];
}

ChildProcess::~ChildProcess() {
  if (pid_ > 0) {
    try {
      Wait();
    } catch (...) {
    }
  }
  if (out_fd_ >= 0) ::close(out_fd_);
}

void ChildProcess::Finish(int status, const ::rusage& ru, ChildResult* r) {
  r->wall_seconds = Now() - start_;
  r->signaled = WIFSIGNALED(status);
  r->signal = r->signaled ? WTERMSIG(status) : 0;
  r->exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + r->signal;
  r->cpu_seconds =
      double(ru.ru_utime.tv_sec + ru.ru_stime.tv_sec) + 1e-6 * double(ru.ru_utime.tv_usec + ru.ru_stime.tv_usec);
  r->peak_rss_mb = double(ru.ru_maxrss) / 1024.0;
  r->out = std::move(out_);
  if (out_fd_ >= 0) ::close(out_fd_), out_fd_ = -1;
  pid_ = -1;
}

ChildResult ChildProcess::Wait() {
  ChildResult r;
  if (pid_ <= 0) throw Error("no child to wait for");
  if (out_fd_ >= 0) Drain(out_fd_, out_, true);
  int status = 0;
  rusage ru{};
  while (::wait4(pid_, &status, 0, &ru) < 0)
    if (errno != EINTR) throw Error(std::string("waiting for a child: ") + std::strerror(errno));
  Finish(status, ru, &r);
  return r;
}

bool ChildProcess::Poll(ChildResult* r) {
  if (pid_ <= 0) return false;
  if (out_fd_ >= 0) {
    ::fcntl(out_fd_, F_SETFL, ::fcntl(out_fd_, F_GETFL) | O_NONBLOCK);
    Drain(out_fd_, out_, false);
  }
  int status = 0;
  rusage ru{};
  const pid_t got = ::wait4(pid_, &status, WNOHANG, &ru);
  if (got != pid_) return false;
  if (out_fd_ >= 0) Drain(out_fd_, out_, false);
  Finish(status, ru, r);
  return true;
}

ChildResult RunChild(const ChildOptions& options) { return ChildProcess(options).Wait(); }

}  // namespace quijibo
