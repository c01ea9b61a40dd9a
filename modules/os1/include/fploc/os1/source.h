// Datagram sources for the drivers (no LCM): a non-blocking UDP socket with a large receive buffer, and a
// pcap replayed at a chosen speed. Both hand out (dst_port, bytes) to a callback.
#pragma once
#include <chrono>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "fploc/os1/pcap.h"

namespace fploc::os1 {

using DatagramFn = std::function<void(uint16_t dst_port, const uint8_t* data, size_t size)>;

class UdpReceiver {
 public:
  ~UdpReceiver();
  // Binds bind_address:port (IPv4, "" = any). recv_buffer_bytes is requested with SO_RCVBUF (and
  // SO_RCVBUFFORCE when permitted); actual_buffer_bytes() reports what the kernel granted.
  bool open(const std::string& bind_address, int port, int recv_buffer_bytes, std::string* err);
  int fd() const { return fd_; }
  int actual_buffer_bytes() const { return actual_buf_; }
  // Reads every queued datagram (recvmmsg batches of 32) without blocking. Returns the number read.
  int drain(const DatagramFn& fn);
  int port() const { return port_; }

 private:
  int fd_ = -1;
  int port_ = 0;
  int actual_buf_ = 0;
  std::vector<uint8_t> buf_;
};

// Replays a pcap's UDP datagrams against the wall clock. rate > 0: capture time / rate; rate <= 0: as fast
// as possible (poll() hands out up to `max_burst` datagrams per call).
class PcapReplay {
 public:
  bool open(const std::string& path, double rate, bool loop, std::string* err);
  // Delivers the datagrams that are due. Returns false when the file is done (and not looping).
  // `stop_after` ends the call early when it returns true (e.g. after a frame was published).
  bool poll(const DatagramFn& fn, const std::function<bool()>& stop_after = {}, int max_burst = 100000);
  const PcapReader& reader() const { return reader_; }
  // Read errors seen so far (one per pass), for the node's error reporting.
  std::vector<std::string> take_errors();
  int passes() const { return passes_; }
  // Called when a looping replay starts the file over (before its first datagram is handed out).
  void set_on_restart(std::function<void()> fn) { on_restart_ = std::move(fn); }

 private:
  bool fetch();
  PcapReader reader_;
  std::string path_;
  double rate_ = 1.0;
  bool loop_ = false;
  bool have_pending_ = false, done_ = false;
  std::vector<uint8_t> pending_;
  uint16_t pending_port_ = 0;
  int64_t pending_ts_ = 0, first_ts_ = 0;
  bool started_ = false;
  std::chrono::steady_clock::time_point t0_;
  int passes_ = 0;
  std::vector<std::string> errors_;
  std::function<void()> on_restart_;
};

}  // namespace fploc::os1
