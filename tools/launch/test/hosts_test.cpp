// The launch's host check (hosts.h, check_hosts): each host is one ssh round trip; the hosts are contacted at
// the same time and their problems reported in the graph's order. ssh is replaced by a script on PATH that
// logs when each call starts and ends.
#include "hosts.h"

#include <gtest/gtest.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>

namespace fs = std::filesystem;

namespace {
struct FakeSsh {
  fs::path dir = fs::temp_directory_path() / ("fploc-hosts-" + std::to_string(::getpid()));
  std::string old_path = getenv("PATH") ? getenv("PATH") : "";
  // The fake: logs "start ADDRESS" / "end ADDRESS" (the address is the argument before "--"), takes 2 s, and
  // fails as ssh does for a host that does not answer.
  FakeSsh() {
    fs::create_directories(dir);
    const fs::path ssh = dir / "ssh";
    std::ofstream(ssh) << "#!/bin/sh\nprev=\nfor a; do [ \"$a\" = -- ] && addr=$prev; prev=$a; done\n"
                          "echo \"start $addr\" >> '" << (dir / "log").string() << "'\nsleep 2\n"
                          "echo \"end $addr\" >> '" << (dir / "log").string() << "'\n"
                          "echo \"ssh: connect to host $addr port 22: No route to host\" >&2\nexit 255\n";
    ::chmod(ssh.c_str(), 0755);
    ::setenv("PATH", (dir.string() + ":" + old_path).c_str(), 1);
  }
  ~FakeSsh() {
    ::setenv("PATH", old_path.c_str(), 1);
    fs::remove_all(dir);
  }
  std::vector<std::string> log() const {
    std::ifstream in(dir / "log");
    std::vector<std::string> lines;
    for (std::string l; std::getline(in, l);) lines.push_back(l);
    return lines;
  }
};

fploc::launch::HostPlan host(const std::string& name, const std::string& address) {
  fploc::launch::HostPlan h;
  h.spec.set_name(name);
  h.spec.set_address(address);
  h.local_root = "/nonexistent-root";
  h.local_bin = "/nonexistent-root/build/bin";
  return h;
}
}  // namespace

TEST(CheckHosts, HostsAreContactedAtTheSameTimeAndReportedInTheGraphsOrder) {
  FakeSsh ssh;
  fploc::Graph g;
  const std::vector<fploc::launch::HostPlan> hosts{host("compute", "10.0.0.2"), host("unused", "10.0.0.9"),
                                                   host("sensor", "10.0.0.3")};
  const auto problems = fploc::launch::check_hosts(
      g, hosts, {{"sensor", "fploc-os1-driver"}, {"compute", "fploc-matcher"}}, "udpm://239.255.76.67:7667?ttl=1");
  ASSERT_EQ(problems.size(), 2u);
  EXPECT_EQ(problems[0].host, "compute");
  EXPECT_EQ(problems[1].host, "sensor");
  for (const auto& p : problems) {
    EXPECT_TRUE(p.unreachable) << p.message;
    EXPECT_NE(p.message.find("No route to host"), std::string::npos) << p.message;
  }
  // Both calls started before either ended (one after the other: start, end, start, end); a host no enabled node
  // runs on is not contacted.
  const auto log = ssh.log();
  ASSERT_EQ(log.size(), 4u);
  EXPECT_EQ(log[0].rfind("start ", 0), 0u) << log[0];
  EXPECT_EQ(log[1].rfind("start ", 0), 0u) << "the second host was contacted only after the first answered: " << log[1];
  for (const auto& l : log) EXPECT_EQ(l.find("10.0.0.9"), std::string::npos) << l;
}
