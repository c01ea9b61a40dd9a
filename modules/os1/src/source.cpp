#include "fploc/os1/source.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace fploc::os1 {

UdpReceiver::~UdpReceiver() {
  if (fd_ >= 0) ::close(fd_);
}

bool UdpReceiver::open(const std::string& bind_address, int port, int recv_buffer_bytes, std::string* err) {
  auto fail = [&](const std::string& what) {
    if (err) *err = "udp " + (bind_address.empty() ? std::string("0.0.0.0") : bind_address) + ":" +
                    std::to_string(port) + ": " + what + ": " + std::strerror(errno);
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
    return false;
  };
  fd_ = ::socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd_ < 0) return fail("socket");
  const int one = 1;
  ::setsockopt(fd_, SOL_SOCKET, SO_REUSEADDR, &one, sizeof(one));
  if (recv_buffer_bytes > 0) {
    // SO_RCVBUFFORCE ignores rmem_max (needs CAP_NET_ADMIN); fall back to SO_RCVBUF.
    if (::setsockopt(fd_, SOL_SOCKET, SO_RCVBUFFORCE, &recv_buffer_bytes, sizeof(int)) != 0)
      ::setsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &recv_buffer_bytes, sizeof(int));
  }
  socklen_t len = sizeof(actual_buf_);
  ::getsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &actual_buf_, &len);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(uint16_t(port));
  if (bind_address.empty()) {
    a.sin_addr.s_addr = htonl(INADDR_ANY);
  } else if (::inet_pton(AF_INET, bind_address.c_str(), &a.sin_addr) != 1) {
    errno = EINVAL;
    return fail("bad bind address");
  }
  if (::bind(fd_, reinterpret_cast<sockaddr*>(&a), sizeof(a)) != 0) return fail("bind");
  if (port == 0) {
    sockaddr_in b{};
    socklen_t bl = sizeof(b);
    ::getsockname(fd_, reinterpret_cast<sockaddr*>(&b), &bl);
    port_ = ntohs(b.sin_port);
  } else {
    port_ = port;
  }
  return true;
}

int UdpReceiver::drain(const DatagramFn& fn) {
  if (fd_ < 0) return 0;
  constexpr int kBatch = 32;
  constexpr size_t kMax = 65536;
  buf_.resize(kBatch * kMax);
  mmsghdr msgs[kBatch];
  iovec iov[kBatch];
  int total = 0;
  for (;;) {
    std::memset(msgs, 0, sizeof(msgs));
    for (int i = 0; i < kBatch; ++i) {
      iov[i] = {buf_.data() + size_t(i) * kMax, kMax};
      msgs[i].msg_hdr.msg_iov = &iov[i];
      msgs[i].msg_hdr.msg_iovlen = 1;
    }
    const int n = ::recvmmsg(fd_, msgs, kBatch, MSG_DONTWAIT, nullptr);
    if (n <= 0) break;
    for (int i = 0; i < n; ++i) {
      // A UDP payload is at most 65,507 B, so a buffer of 64 KiB never truncates.
      fn(uint16_t(port_), buf_.data() + size_t(i) * kMax, msgs[i].msg_len);
    }
    total += n;
    if (n < kBatch) break;
  }
  return total;
}

bool PcapReplay::open(const std::string& path, double rate, bool loop, std::string* err) {
  path_ = path;
  rate_ = rate;
  loop_ = loop;
  if (!reader_.open(path)) {
    if (err) *err = reader_.error();
    return false;
  }
  passes_ = 1;
  return true;
}

bool PcapReplay::fetch() {
  if (have_pending_) return true;
  for (int attempt = 0; attempt < 2; ++attempt) {
    UdpDatagram d;
    if (reader_.next(d)) {
      pending_.assign(d.data, d.data + d.size);
      pending_port_ = d.dst_port;
      pending_ts_ = d.ts_us;
      have_pending_ = true;
      if (!started_) {
        started_ = true;
        first_ts_ = d.ts_us;
        t0_ = std::chrono::steady_clock::now();
      }
      return true;
    }
    if (!reader_.error().empty()) errors_.push_back(reader_.error());
    if (!loop_ || reader_.stats().datagrams == 0) return false;
    // Loop: reopen, keep the clock running (the next pass starts right away).
    if (!reader_.open(path_)) {
      errors_.push_back(reader_.error());
      return false;
    }
    ++passes_;
    started_ = false;
    if (on_restart_) on_restart_();
  }
  return false;
}

bool PcapReplay::poll(const DatagramFn& fn, const std::function<bool()>& stop_after, int max_burst) {
  if (done_) return false;
  for (int n = 0; n < max_burst; ++n) {
    if (!fetch()) {
      done_ = true;
      return false;
    }
    if (rate_ > 0) {
      const double due_s = double(pending_ts_ - first_ts_) * 1e-6 / rate_;
      const double now_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count();
      if (due_s > now_s) return true;
    }
    have_pending_ = false;
    fn(pending_port_, pending_.data(), pending_.size());
    if (stop_after && stop_after()) return true;
  }
  return true;
}

std::vector<std::string> PcapReplay::take_errors() {
  auto e = std::move(errors_);
  errors_.clear();
  return e;
}

}  // namespace fploc::os1
