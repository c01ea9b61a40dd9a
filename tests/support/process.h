// Child processes for the integration tests (tests/*/..._it.cpp): paths of the built programs, a
// process whose stdout/stderr go to files in the test folder, waiting with a timeout, liveness.
// Header-only; each test binary that starts fploc programs includes it.
#pragma once
#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#ifndef FPLOC_SOURCE_DIR
#error "FPLOC_SOURCE_DIR must be defined by the test's CMakeLists"
#endif

namespace fploc::test {

inline std::string env(const char* k, const std::string& d = "") {
  const char* v = getenv(k);
  return v ? v : d;
}
// The source tree and the built programs (FPLOC_ROOT / FPLOC_BUILD_DIR override them; a test's CMakeLists
// may define FPLOC_BUILD_DIR_DEFAULT, its own build folder).
inline std::string root() { return env("FPLOC_ROOT", FPLOC_SOURCE_DIR); }
#ifdef FPLOC_BUILD_DIR_DEFAULT
inline std::string build_dir() { return env("FPLOC_BUILD_DIR", FPLOC_BUILD_DIR_DEFAULT); }
#else
inline std::string build_dir() { return env("FPLOC_BUILD_DIR", root() + "/build"); }
#endif
inline std::string bin(const std::string& exe) { return build_dir() + "/bin/" + exe; }

inline double now_s() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}
inline std::string slurp(const std::string& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// A child process started in `dir` with stderr to DIR/TAG.stderr and stdout to DIR/TAG.stdout. At the
// end of its scope it gets SIGINT, 2 s to exit, then SIGKILL.
struct Proc {
  pid_t pid = -1;
  std::string err_file;
  static Proc spawn(const std::vector<std::string>& args, const std::string& dir, const std::string& tag) {
    Proc p;
    p.err_file = dir + "/" + tag + ".stderr";
    const std::string out_file = dir + "/" + tag + ".stdout";
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    p.pid = fork();
    if (p.pid == 0) {
      if (chdir(dir.c_str()) != 0) _exit(126);
      const int e = open(p.err_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      const int o = open(out_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      dup2(e, 2);
      dup2(o, 1);
      execv(argv[0], argv.data());
      _exit(127);
    }
    return p;
  }
  // Waits up to timeout_s; returns the wait status, or -1 on timeout.
  int wait(double timeout_s) {
    const double t0 = now_s();
    int st = 0;
    while (pid > 0 && now_s() - t0 < timeout_s) {
      if (waitpid(pid, &st, WNOHANG) == pid) {
        pid = -1;
        return st;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    return -1;
  }
  bool alive() const {
    int st = 0;
    return pid > 0 && waitpid(pid, &st, WNOHANG) == 0;
  }
  Proc() = default;
  Proc(Proc&& o) noexcept : pid(o.pid), err_file(std::move(o.err_file)) { o.pid = -1; }
  Proc& operator=(Proc&&) = delete;
  ~Proc() {
    if (pid <= 0) return;
    kill(pid, SIGINT);
    for (int i = 0; i < 100 && waitpid(pid, nullptr, WNOHANG) == 0; ++i)
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    kill(pid, SIGKILL);
    waitpid(pid, nullptr, 0);
  }
};

// A child that shares the test's stdout/stderr (its messages show in the ctest log); stop() ends it.
inline pid_t spawn(std::vector<std::string> args) {
  const pid_t pid = fork();
  if (pid == 0) {
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    execv(argv[0], argv.data());
    _exit(127);
  }
  return pid;
}
// SIGTERM, 2.5 s to exit, then SIGKILL.
inline void stop(pid_t pid) {
  if (pid <= 0) return;
  kill(pid, SIGTERM);
  int st = 0;
  for (int i = 0; i < 50; ++i) {
    if (waitpid(pid, &st, WNOHANG) == pid) return;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  kill(pid, SIGKILL);
  waitpid(pid, &st, 0);
}

// Runs a program to its end (or timeout_s); its exit code, 128 + signal, or -1 on timeout.
inline int run(const std::vector<std::string>& args, const std::string& dir, const std::string& tag,
               double timeout_s = 60) {
  Proc p = Proc::spawn(args, dir, tag);
  const int st = p.wait(timeout_s);
  return st < 0 ? -1 : (WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st));
}

// Whether any process (not only our child) with this pid is alive; a zombie counts as gone.
inline bool pid_alive(pid_t pid) {
  if (kill(pid, 0) != 0) return false;
  std::ifstream st("/proc/" + std::to_string(pid) + "/stat");
  std::string s;
  std::getline(st, s);
  const auto rp = s.rfind(')');
  return !(rp != std::string::npos && rp + 2 < s.size() && s[rp + 2] == 'Z');
}

}  // namespace fploc::test
