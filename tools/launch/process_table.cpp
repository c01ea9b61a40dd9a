#include "process_table.h"

#include "fploc/runtime/subprocess.h"

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fcntl.h>

#include <cerrno>
#include <cstdlib>
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

ProcessTable::~ProcessTable() {
  for (size_t i = 0; i < io_.size(); ++i) close_io(i);
}

void ProcessTable::close_io(size_t i) {
  auto& io = io_[i];
  if (io.in >= 0) ::close(io.in);
  if (io.out >= 0) ::close(io.out);
  io = RemoteIo{};
}

void ProcessTable::send(size_t i, char c) {
  if (io_[i].in >= 0) [[maybe_unused]] auto r = ::write(io_[i].in, &c, 1);
}

std::vector<std::string> ProcessTable::read_lines(size_t i, bool& eof) {
  std::vector<std::string> lines;
  eof = false;
  auto& io = io_[i];
  if (io.out < 0) return lines;
  char buf[8192];
  for (;;) {
    const ssize_t n = ::read(io.out, buf, sizeof buf);
    if (n == 0) {
      eof = true;
      break;
    }
    if (n < 0) break;  // EAGAIN
    io.partial.append(buf, size_t(n));
  }
  size_t nl;
  while ((nl = io.partial.find('\n')) != std::string::npos) {
    std::string l = io.partial.substr(0, nl);
    io.partial.erase(0, nl + 1);
    if (!l.empty() && l.back() == '\r') l.pop_back();
    if (io.remote_pid < 0 && l.rfind("FPLOC_REMOTE_PID ", 0) == 0) {
      io.remote_pid = std::atoi(l.c_str() + 17);
      continue;
    }
    lines.push_back(std::move(l));
  }
  if (eof && !io.partial.empty()) lines.push_back(std::move(io.partial)), io.partial.clear();
  return lines;
}

pid_t ProcessTable::spawn(size_t i, int restarts, std::string& error) {
  auto args = command(i);
  int in_pipe[2] = {-1, -1}, out_pipe[2] = {-1, -1};
  if (entries_[i].host) {
    close_io(i);
    args = entries_[i].host->ssh_argv(remote_node_command(*entries_[i].host, args, restarts, watchdog_s));
    if (::pipe2(in_pipe, O_CLOEXEC) != 0 || ::pipe2(out_pipe, O_CLOEXEC) != 0) {
      error = std::string("pipe failed: ") + strerror(errno);
      return -1;
    }
  }
  std::vector<std::string> env;
  for (char** e = environ; *e; ++e)
    if (std::strncmp(*e, "FPLOC_RESTARTS=", 15) != 0) env.push_back(*e);
  env.push_back("FPLOC_RESTARTS=" + std::to_string(restarts));
  rt::SpawnOptions o;
  o.close_other_fds = true;
  o.who = "fploc launch";
  if (in_pipe[0] >= 0) {  // through ssh: its stdin/stdout carry the watchdog protocol and the output
    o.search_path = true;
    o.stdin_fd = in_pipe[0];
    o.stdout_fd = o.stderr_fd = out_pipe[1];
  } else {
    o.env = &env;
  }
  const pid_t pid = rt::spawn_supervised(args, o, error);
  if (pid < 0) {
    for (int fd : {in_pipe[0], in_pipe[1], out_pipe[0], out_pipe[1]})
      if (fd >= 0) ::close(fd);
    return -1;
  }
  if (in_pipe[0] >= 0) {
    ::close(in_pipe[0]);
    ::close(out_pipe[1]);
    ::fcntl(in_pipe[1], F_SETFL, O_NONBLOCK);
    ::fcntl(out_pipe[0], F_SETFL, O_NONBLOCK);
    io_[i].in = in_pipe[1];
    io_[i].out = out_pipe[0];
  }
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
