// fploc os1 send --pcap F [--host 127.0.0.1] [--lidar-port 7502] [--imu-port 7503] [--rate 1] [--loop N]
// Replays the Ouster datagrams of a capture as UDP to a host (default loopback): 48-byte packets to the
// IMU port, everything else to the lidar port, paced by capture time / rate (rate <= 0: as fast as possible).
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <iostream>
#include <thread>

#include "fploc/os1/packet.h"
#include "fploc/os1/source.h"
#include "fploc/runtime/cli_messages.h"

int main(int argc, char** argv) {
  CLI::App app{"fploc os1 send: replay an Ouster pcap as UDP packets (to a driver under test)"};
  fploc::rt::install_cli_messages(app, "fploc os1 send");
  std::string pcap, host = "127.0.0.1";
  int lidar_port = 7502, imu_port = 7503, loops = 1;
  double rate = 1.0;
  app.add_option("--pcap", pcap, "capture file")->required();
  app.add_option("--host", host, "destination IPv4 address");
  app.add_option("--lidar-port", lidar_port, "destination port of lidar packets");
  app.add_option("--imu-port", imu_port, "destination port of IMU packets (48 B)");
  app.add_option("--rate", rate, "speed factor (<= 0: as fast as possible)");
  app.add_option("--loop", loops, "send the capture this many times");
  CLI11_PARSE(app, argc, argv);

  const int fd = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  sockaddr_in to{};
  to.sin_family = AF_INET;
  if (fd < 0 || ::inet_pton(AF_INET, host.c_str(), &to.sin_addr) != 1) {
    std::cerr << "fploc os1 send: bad host '" << host << "'\n";
    return 2;
  }
  uint64_t sent = 0, failed = 0;
  for (int pass = 0; pass < loops; ++pass) {
    fploc::os1::PcapReplay replay;
    std::string err;
    if (!replay.open(pcap, rate, false, &err)) {
      std::cerr << "fploc os1 send: " << err << "\n";
      return 2;
    }
    while (replay.poll([&](uint16_t, const uint8_t* d, size_t n) {
      to.sin_port = htons(uint16_t(n == fploc::os1::kImuPacketSize ? imu_port : lidar_port));
      if (::sendto(fd, d, n, 0, reinterpret_cast<sockaddr*>(&to), sizeof(to)) == ssize_t(n)) ++sent;
      else ++failed;
      if (rate <= 0 && sent % 16 == 0) std::this_thread::sleep_for(std::chrono::microseconds(200));  // let receivers drain
    })) {
      std::this_thread::sleep_for(std::chrono::microseconds(500));
    }
    for (const auto& e : replay.take_errors()) std::cerr << "fploc os1 send: " << e << "\n";
  }
  ::close(fd);
  std::cerr << "fploc os1 send: " << sent << " datagrams sent, " << failed << " failed\n";
  return failed ? 1 : 0;
}
