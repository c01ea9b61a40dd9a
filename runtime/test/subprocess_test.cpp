#include "fploc/runtime/subprocess.h"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

using fploc::rt::run_program;
using fploc::rt::RunOptions;

TEST(RunProgram, CapturesStdoutAndExitCode) {
  const auto r = run_program({"/bin/sh", "-c", "echo out; echo err >&2; exit 3"});
  EXPECT_EQ(r.exit_code, 3);
  EXPECT_EQ(r.output, "out\n");  // stderr discarded by default
  EXPECT_EQ(r.problem, "exit code 3");
}

TEST(RunProgram, MergesStderrAndSearchesPath) {
  RunOptions o;
  o.merge_stderr = true;
  o.search_path = true;
  const auto r = run_program({"sh", "-c", "echo out; echo err >&2"}, o);
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_EQ(r.output, "out\nerr\n");
  EXPECT_EQ(r.problem, "");
}

TEST(RunProgram, KillsAtTheDeadlineWithItsChildren) {
  RunOptions o;
  o.timeout_s = 0.3;
  const auto r = run_program({"/bin/sh", "-c", "sleep 30 & sleep 30"}, o);
  EXPECT_TRUE(r.timed_out);
  EXPECT_EQ(r.exit_code, -1);
  EXPECT_EQ(r.problem, "timed out");
}

TEST(RunProgram, MissingProgramIsExit127) {
  const auto r = run_program({"/nonexistent/fploc-nothing"});
  EXPECT_EQ(r.exit_code, 127);
}

TEST(SpawnSupervised, OwnGroupEnvironmentAndDescriptors) {
  int out[2];
  ASSERT_EQ(::pipe(out), 0);
  const std::vector<std::string> env{"FPLOC_SPAWN_TEST=42"};
  fploc::rt::SpawnOptions o;
  o.env = &env;
  o.stdin_fd = fploc::rt::SpawnOptions::kDevNull;
  o.stdout_fd = out[1];
  o.close_other_fds = true;
  std::string error;
  const pid_t pid = fploc::rt::spawn_supervised(
      {"/bin/sh", "-c", "echo $FPLOC_SPAWN_TEST $(ps -o pgid= -p $$ | tr -d ' ') $$; read x || echo eof"}, o, error);
  ASSERT_GT(pid, 0) << error;
  ::close(out[1]);
  std::string text;
  char buf[256];
  for (ssize_t n; (n = ::read(out[0], buf, sizeof buf)) > 0;) text.append(buf, size_t(n));
  ::close(out[0]);
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  EXPECT_EQ(text, "42 " + std::to_string(pid) + " " + std::to_string(pid) + "\neof\n");  // own group; stdin empty
}

TEST(SpawnSupervised, ExecFailureIs127WithOneLine) {
  int err[2];
  ASSERT_EQ(::pipe(err), 0);
  fploc::rt::SpawnOptions o;
  o.stderr_fd = err[1];
  o.who = "test";
  std::string error;
  const pid_t pid = fploc::rt::spawn_supervised({"/nonexistent/fploc-nothing"}, o, error);
  ASSERT_GT(pid, 0) << error;
  ::close(err[1]);
  std::string text;
  char buf[256];
  for (ssize_t n; (n = ::read(err[0], buf, sizeof buf)) > 0;) text.append(buf, size_t(n));
  ::close(err[0]);
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  EXPECT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 127);
  EXPECT_EQ(text, "test: cannot run /nonexistent/fploc-nothing: No such file or directory\n");
}
