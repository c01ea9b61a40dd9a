#include "fploc/runtime/subprocess.h"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>

namespace fploc::rt {

RunResult run_program(const std::vector<std::string>& args, const RunOptions& o) {
  RunResult r;
  if (args.empty()) {
    r.problem = "no program";
    return r;
  }
  int pipefd[2];
  if (::pipe2(pipefd, O_CLOEXEC) != 0) {
    r.problem = "pipe failed";
    return r;
  }
  std::vector<char*> argv;
  for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  const pid_t pid = ::fork();
  if (pid < 0) {
    ::close(pipefd[0]);
    ::close(pipefd[1]);
    r.problem = "fork failed";
    return r;
  }
  if (pid == 0) {
    ::setpgid(0, 0);
    ::dup2(pipefd[1], 1);
    const int devnull = ::open("/dev/null", O_RDWR);
    if (devnull >= 0) ::dup2(devnull, 0);
    if (o.merge_stderr) ::dup2(pipefd[1], 2);
    else if (devnull >= 0) ::dup2(devnull, 2);
    if (o.search_path) ::execvp(argv[0], argv.data());
    else ::execv(argv[0], argv.data());
    ::_exit(127);
  }
  ::close(pipefd[1]);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(o.timeout_s);
  char buf[4096];
  for (;;) {
    const double left = std::chrono::duration<double>(deadline - std::chrono::steady_clock::now()).count();
    if (left <= 0) {
      r.timed_out = true;
      break;
    }
    pollfd p{pipefd[0], POLLIN, 0};
    const int n_ready = ::poll(&p, 1, int(left * 1000) + 1);
    if (n_ready <= 0) continue;  // EINTR or not yet
    const ssize_t n = ::read(pipefd[0], buf, sizeof buf);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    r.output.append(buf, size_t(n));
  }
  ::close(pipefd[0]);
  if (r.timed_out) {
    ::kill(-pid, SIGKILL);
    ::kill(pid, SIGKILL);
  }
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (r.timed_out) {
    r.problem = "timed out";
  } else if (WIFEXITED(status)) {
    r.exit_code = WEXITSTATUS(status);
    if (r.exit_code != 0) r.problem = "exit code " + std::to_string(r.exit_code);
  } else {
    r.problem = "killed by signal " + std::to_string(WTERMSIG(status));
  }
  return r;
}

pid_t spawn_supervised(const std::vector<std::string>& args, const SpawnOptions& o, std::string& error) {
  if (args.empty()) {
    error = "no program";
    return -1;
  }
  // Everything the child needs is built before fork: only async-signal-safe calls after it.
  std::vector<char*> argv;
  for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  std::vector<char*> envp;
  if (o.env) {
    for (const auto& e : *o.env) envp.push_back(const_cast<char*>(e.c_str()));
    envp.push_back(nullptr);
  }
  const std::string failed = (o.who.empty() ? std::string() : o.who + ": ") + "cannot run " + args[0] + ": ";
  const pid_t parent = ::getpid();
  const pid_t pid = ::fork();
  if (pid < 0) {
    error = std::string("fork failed: ") + std::strerror(errno);
    return -1;
  }
  if (pid == 0) {
    ::setpgid(0, 0);
    ::prctl(PR_SET_PDEATHSIG, SIGKILL);
    if (::getppid() != parent) ::_exit(127);  // the parent died before prctl
    sigset_t none;
    sigemptyset(&none);
    ::sigprocmask(SIG_SETMASK, &none, nullptr);
    for (int s : {SIGINT, SIGTERM, SIGCHLD, SIGPIPE, SIGHUP}) ::signal(s, SIG_DFL);
    if (o.stdin_fd == SpawnOptions::kDevNull) {
      const int devnull = ::open("/dev/null", O_RDONLY);
      if (devnull >= 0) ::dup2(devnull, 0);
    } else if (o.stdin_fd >= 0) {
      ::dup2(o.stdin_fd, 0);
    }
    if (o.stdout_fd >= 0) ::dup2(o.stdout_fd, 1);
    if (o.stderr_fd >= 0) ::dup2(o.stderr_fd, 2);
    if (o.close_other_fds) ::syscall(SYS_close_range, 3u, ~0u, 0u);
    char** env = o.env ? envp.data() : environ;
    if (o.search_path) ::execvpe(argv[0], argv.data(), env);
    else ::execve(argv[0], argv.data(), env);
    const char* why = std::strerror(errno);
    [[maybe_unused]] auto r1 = ::write(2, failed.data(), failed.size());
    [[maybe_unused]] auto r2 = ::write(2, why, std::strlen(why));
    [[maybe_unused]] auto r3 = ::write(2, "\n", 1);
    ::_exit(127);
  }
  ::setpgid(pid, pid);
  return pid;
}

}  // namespace fploc::rt
