#include "process_table.h"

#include <signal.h>
#include <sys/prctl.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace fploc::launch {

std::vector<std::string> ProcessTable::command(size_t i) const {
  const auto& e = entries_[i];
  std::vector<std::string> args{e.exe_path};
  if (e.fploc_node) {
    args.insert(args.end(), {"--graph", graph_, "--node", e.name});
    for (const auto& s : e.sets) args.insert(args.end(), {"--set", s});
  }
  args.insert(args.end(), e.args.begin(), e.args.end());
  return args;
}

pid_t ProcessTable::spawn(size_t i, int restarts, std::string& error) const {
  auto args = command(i);
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  std::vector<std::string> env_s;
  for (char** e = environ; *e; ++e)
    if (std::strncmp(*e, "FPLOC_RESTARTS=", 15) != 0) env_s.push_back(*e);
  env_s.push_back("FPLOC_RESTARTS=" + std::to_string(restarts));
  std::vector<char*> envp;
  for (auto& e : env_s) envp.push_back(e.data());
  envp.push_back(nullptr);
  const pid_t parent = ::getpid();
  const pid_t pid = ::fork();
  if (pid < 0) {
    error = std::string("fork failed: ") + strerror(errno);
    return -1;
  }
  if (pid == 0) {
    ::setpgid(0, 0);
    ::prctl(PR_SET_PDEATHSIG, SIGKILL);
    if (::getppid() != parent) ::_exit(127);  // the launcher died before prctl
    sigset_t none;
    sigemptyset(&none);
    ::sigprocmask(SIG_SETMASK, &none, nullptr);
    for (int s : {SIGINT, SIGTERM, SIGCHLD, SIGPIPE, SIGHUP}) ::signal(s, SIG_DFL);
    ::syscall(SYS_close_range, 3u, ~0u, 0u);
    ::execve(argv[0], argv.data(), envp.data());
    const char msg[] = "fploc launch: exec failed\n";
    [[maybe_unused]] auto r = ::write(2, msg, sizeof msg - 1);
    ::_exit(127);
  }
  ::setpgid(pid, pid);  // also from the parent: no race with kill(-pid)
  return pid;
}

void ProcessTable::signal_group(pid_t pid, int sig) {
  if (pid > 0) ::kill(-pid, sig);
}

pid_t ProcessTable::reap_one(ExitStatus& st) {
  int status = 0;
  const pid_t pid = ::waitpid(-1, &status, WNOHANG);
  if (pid <= 0) return 0;
  st.exited = WIFEXITED(status);
  st.code = st.exited ? WEXITSTATUS(status) : 0;
  st.signal = WIFSIGNALED(status) ? WTERMSIG(status) : 0;
  return pid;
}

}  // namespace fploc::launch
