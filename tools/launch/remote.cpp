// fploc-remote: the far end of a node that `fploc launch` runs on another host through ssh.
//   ssh HOST fploc-remote [--timeout S] [--restarts N] -- EXE ARGS...
// Starts EXE in its own process group (FPLOC_RESTARTS=N) and reads one-byte commands on stdin, which the
// launcher writes through the ssh session: '.' alive (every 0.5 s), 'I' SIGINT, 'T' SIGTERM, 'K' SIGKILL
// to the node's group. When stdin ends (ssh or the launcher died) or goes silent for --timeout seconds
// (the link was cut and ssh has not noticed yet), the node is killed — no orphan survives its launcher.
// First line on stdout: "FPLOC_REMOTE_PID <pid>" (how the launcher matches the node's heartbeats).
// Exit status: the node's (128 + signal when killed), so the launcher's restart policy sees it.
#include "fploc/runtime/subprocess.h"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

namespace {
double now_s() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}
int g_sig_pipe[2];
void on_signal(int sig) {
  const char c = char(sig);
  [[maybe_unused]] auto r = ::write(g_sig_pipe[1], &c, 1);
}
}  // namespace

int main(int argc, char** argv) {
  double timeout = 3.0;
  std::string restarts = "0";
  int i = 1;
  for (; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--timeout" && i + 1 < argc) timeout = std::atof(argv[++i]);
    else if (a == "--restarts" && i + 1 < argc) restarts = argv[++i];
    else if (a == "--") { ++i; break; }
    else { std::fprintf(stderr, "fploc-remote: unexpected argument '%s'\n", a.c_str()); return 2; }
  }
  if (i >= argc) {
    std::fprintf(stderr, "usage: fploc-remote [--timeout S] [--restarts N] -- EXE ARGS...\n");
    return 2;
  }
  if (::pipe2(g_sig_pipe, O_CLOEXEC | O_NONBLOCK) != 0) return 1;
  struct sigaction sa {};
  sa.sa_handler = on_signal;
  sigemptyset(&sa.sa_mask);
  for (int s : {SIGINT, SIGTERM, SIGHUP, SIGCHLD}) sigaction(s, &sa, nullptr);
  signal(SIGPIPE, SIG_IGN);
  ::setenv("FPLOC_RESTARTS", restarts.c_str(), 1);
  fploc::rt::SpawnOptions o;
  o.search_path = true;
  o.stdin_fd = fploc::rt::SpawnOptions::kDevNull;
  o.who = "fploc-remote";
  std::string error;
  const pid_t pid = fploc::rt::spawn_supervised(std::vector<std::string>(argv + i, argv + argc), o, error);
  if (pid < 0) {
    std::fprintf(stderr, "fploc-remote: %s\n", error.c_str());
    return 1;
  }
  std::printf("FPLOC_REMOTE_PID %d\n", int(pid));
  std::fflush(stdout);
  auto kill_node = [&](int sig) { ::kill(-pid, sig); };
  double last = now_s();
  bool stdin_open = true;
  double kill_at = 0;  // after losing the launcher: SIGTERM sent, SIGKILL at this time
  for (;;) {
    pollfd p[2] = {{stdin_open ? 0 : -1, POLLIN, 0}, {g_sig_pipe[0], POLLIN, 0}};
    ::poll(p, 2, 100);
    if (stdin_open && (p[0].revents & (POLLIN | POLLHUP | POLLERR))) {
      char buf[64];
      const ssize_t n = ::read(0, buf, sizeof buf);
      if (n <= 0) {
        stdin_open = false;
        std::fprintf(stderr, "fploc-remote: the launcher's ssh session ended: stopping the node (pid %d)\n", int(pid));
        kill_node(SIGTERM);
        kill_at = now_s() + 1.0;
      } else {
        last = now_s();
        for (ssize_t k = 0; k < n; ++k) {
          if (buf[k] == 'I') kill_node(SIGINT);
          else if (buf[k] == 'T') kill_node(SIGTERM);
          else if (buf[k] == 'K') kill_node(SIGKILL);
        }
      }
    }
    if (p[1].revents & POLLIN) {
      char buf[16];
      const ssize_t n = ::read(g_sig_pipe[0], buf, sizeof buf);
      for (ssize_t k = 0; k < n; ++k)
        if (buf[k] != SIGCHLD) kill_node(buf[k] == SIGHUP ? SIGTERM : buf[k]);
    }
    int status = 0;
    if (::waitpid(pid, &status, WNOHANG) == pid) {
      ::kill(-pid, SIGKILL);  // anything left in its group
      return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    }
    const double t = now_s();
    if (stdin_open && t - last > timeout) {
      std::fprintf(stderr, "fploc-remote: nothing from the launcher for %.1f s (link cut?): stopping the node (pid %d)\n",
                   t - last, int(pid));
      stdin_open = false;
      kill_node(SIGTERM);
      kill_at = t + 1.0;
    }
    if (kill_at > 0 && t >= kill_at) {
      kill_node(SIGKILL);
      kill_at = t + 1e9;
    }
  }
}
