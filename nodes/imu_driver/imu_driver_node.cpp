// IMU driver: publishes imu_t (SI units) on OS1_IMU. A source turns raw input into ImuSamples; the only
// one implemented is "os1" (Ouster 48-byte IMU packets over UDP, default port 7503, or from a pcap,
// including captures where lidar and IMU share a port: IMU packets are told apart by their size).
// "xsens" is an Xsens MTi (MTData2 over a serial port or from a recorded stream). With the input port
// "packets" mapped (os1_packet_t, e.g. an ouster_ros bag imported by `fploc import`), Ouster IMU packets
// come from there instead of UDP or a pcap.
#include <fploc/imu_t.hpp>
#include <fploc/os1_packet_t.hpp>

#include <fcntl.h>
#include <sys/stat.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <memory>
#include <stdexcept>

#include "fploc/os1/ports.h"
#include "fploc/adapters/imu_t.h"
#include "fploc/os1/packet.h"
#include "fploc/os1/source.h"
#include "fploc/os1/xsens.h"
#include "fploc/runtime/node.h"
#include "options/sensors.pb.h"

namespace {

using namespace fploc::os1;

struct Sample {
  ImuSample s;
  std::string source;
};
using SampleFn = std::function<void(const Sample&)>;

// One IMU input. setup() registers fds / timers with the context and calls `emit` per sample.
class ImuSource {
 public:
  virtual ~ImuSource() = default;
  virtual void setup(fploc::rt::Context& ctx, const fploc::ImuDriverOptions& opt, SampleFn emit) = 0;
};

class Os1ImuSource : public ImuSource {
 public:
  void setup(fploc::rt::Context& ctx, const fploc::ImuDriverOptions& opt, SampleFn emit) override {
    ctx_ = &ctx;
    emit_ = std::move(emit);
    const int port = fploc::os1::port_or_default(opt.imu_port(), fploc::os1::kDefaultImuPort);
    if (!opt.pcap().empty()) {
      pcap_port_ = opt.imu_port();  // 0: any port, IMU packets recognised by size
      std::string err;
      const double rate = opt.pcap_rate() == 0 ? 1.0 : opt.pcap_rate();
      if (!replay_.open(ctx.resolve_path(opt.pcap()), rate, opt.pcap_loop(), &err)) throw fploc::rt::SetupMayPass("imu_driver: " + err);
      ctx.every(0.002, [this] {
        const bool more = replay_.poll([this](uint16_t p, const uint8_t* d, size_t n) {
          if (pcap_port_ == 0 || p == pcap_port_) on_datagram(d, n, pcap_port_ == 0);
        });
        for (const auto& e : replay_.take_errors()) ctx_->error("pcap: " + e);
        if (!more) ctx_->request_stop();
      });
    } else {
      std::string err;
      if (!udp_.open(opt.bind_address(), port, 1 << 20, &err)) throw std::runtime_error("imu_driver: " + err);
      ctx.watch_fd(udp_.fd(), [this] {
        udp_.drain([this](uint16_t, const uint8_t* d, size_t n) { on_datagram(d, n, false); });
      });
    }
  }

 private:
  void on_datagram(const uint8_t* d, size_t n, bool any_port) {
    if (n != kImuPacketSize) {
      if (!any_port) ctx_->error("imu packet: " + std::to_string(n) + " B, expected 48");
      return;  // other traffic in a capture (lidar packets)
    }
    Sample s{{}, "os1"};
    if (!parse_imu_packet(d, n, s.s)) {
      ctx_->error("imu packet: non-finite accel/gyro value");
      return;
    }
    emit_(s);
  }
  fploc::rt::Context* ctx_ = nullptr;
  SampleFn emit_;
  UdpReceiver udp_;
  PcapReplay replay_;
  int pcap_port_ = 0;
};

// Xsens MTi (MTi-30 in the paper): Xbus MTData2 with Acceleration, RateOfTurn and SampleTimeFine
// enabled (configure the device with MT Manager). `serial_device` is a tty (raw 8N1 at serial_baud) or a
// file holding a recorded byte stream (read as fast as possible; the node stops at its end). Times are
// the device's SampleTimeFine (10 kHz) so a recording replays deterministically.
class XsensSource : public ImuSource {
 public:
  ~XsensSource() override {
    if (fd_ >= 0) ::close(fd_);
  }
  void setup(fploc::rt::Context& ctx, const fploc::ImuDriverOptions& opt, SampleFn emit) override {
    ctx_ = &ctx;
    emit_ = std::move(emit);
    if (opt.serial_device().empty()) throw std::runtime_error("imu_driver: source 'xsens' needs option 'serial_device'");
    const std::string dev = ctx.resolve_path(opt.serial_device());
    fd_ = ::open(dev.c_str(), O_RDONLY | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
    if (fd_ < 0) throw std::runtime_error("imu_driver: " + dev + ": " + std::strerror(errno));
    struct stat st {};
    ::fstat(fd_, &st);
    if (S_ISREG(st.st_mode)) {
      ctx.every(0.001, [this] {
        if (!read_some()) ctx_->request_stop();
      });
      return;
    }
    termios t{};
    if (::tcgetattr(fd_, &t) != 0) throw std::runtime_error("imu_driver: " + dev + ": not a tty: " + std::strerror(errno));
    ::cfmakeraw(&t);
    const int baud = opt.serial_baud() > 0 ? opt.serial_baud() : 115200;
    speed_t sp;
    switch (baud) {
      case 115200: sp = B115200; break;
      case 230400: sp = B230400; break;
      case 460800: sp = B460800; break;
      case 921600: sp = B921600; break;
      default: throw std::runtime_error("imu_driver: option 'serial_baud': unsupported " + std::to_string(baud));
    }
    ::cfsetispeed(&t, sp);
    ::cfsetospeed(&t, sp);
    t.c_cflag |= CLOCAL | CREAD;
    if (::tcsetattr(fd_, TCSANOW, &t) != 0) throw std::runtime_error("imu_driver: " + dev + ": " + std::strerror(errno));
    ctx.watch_fd(fd_, [this] { read_some(); });
  }

 private:
  // Returns false at the end of a file.
  bool read_some() {
    uint8_t buf[4096];
    const ssize_t n = ::read(fd_, buf, sizeof(buf));
    if (n <= 0) return n < 0 && (errno == EAGAIN || errno == EINTR);
    const auto before = parser_.stats();
    parser_.feed(buf, size_t(n), [this](const XsensSample& x) {
      if (!x.has_time || !x.has_accel || !x.has_gyro) {
        ctx_->error("xsens MTData2 without SampleTimeFine/Acceleration/RateOfTurn (enable them on the device)");
        return;
      }
      Sample s{{}, "xsens"};
      const uint64_t ns = uint64_t(x.sample_time_fine) * 100000u;  // 10 kHz ticks
      s.s.sys_ts_ns = s.s.accel_ts_ns = s.s.gyro_ts_ns = ns;
      s.s.accel_mps2 = x.accel;
      s.s.gyro_radps = x.gyro;
      emit_(s);
    });
    const auto& after = parser_.stats();
    if (after.checksum_errors > before.checksum_errors) ctx_->error("xsens: Xbus checksum error");
    if (after.bad_payloads > before.bad_payloads) ctx_->error("xsens: malformed MTData2 payload");
    return true;
  }
  fploc::rt::Context* ctx_ = nullptr;
  SampleFn emit_;
  XbusParser parser_;
  int fd_ = -1;
};

class ImuDriverNode : public fploc::rt::Node {
 public:
  static fploc::rt::NodeSpec spec() {
    return {"imu_driver", "imu_driver", "IMU samples (Ouster IMU packets over UDP/pcap, or Xsens MTi MTData2 over serial) in SI units -> OS1_IMU",
            {fploc::rt::output<fploc::imu_t>("imu", "OS1_IMU"),
             fploc::rt::input<fploc::os1_packet_t>("packets", "")}};  // recorded packets (not connected by default)
  }

  void setup(fploc::rt::Context& ctx) override {
    const auto& opt = ctx.options<fploc::ImuDriverOptions>();
    const std::string kind = opt.source().empty() ? "os1" : opt.source();
    if (kind == "os1") source_ = std::make_unique<Os1ImuSource>();
    else if (kind == "xsens") source_ = std::make_unique<XsensSource>();
    else throw std::runtime_error("imu_driver: option 'source': unknown '" + kind + "' (os1, xsens)");
    out_ = ctx.advertise<fploc::imu_t>("imu");
    if (!ctx.channel("packets").empty()) {
      if (kind != "os1") throw std::runtime_error("imu_driver: input 'packets' carries Ouster packets: option 'source' must be 'os1'");
      ctx.subscribe<fploc::os1_packet_t>("packets", [this, &ctx](const fploc::os1_packet_t& m) {
        Sample s{{}, "os1"};
        if (m.data.size() != kImuPacketSize) {
          ctx.error("imu packet: " + std::to_string(m.data.size()) + " B, expected 48");
        } else if (!parse_imu_packet(m.data.data(), m.data.size(), s.s)) {
          ctx.error("imu packet: non-finite accel/gyro value");
        } else {
          publish(s);
        }
      });
      return;
    }
    source_->setup(ctx, opt, [this](const Sample& s) { publish(s); });
  }

 private:
  void publish(const Sample& s) {
    out_.publish(fploc::adapters::to_msg(s.s, seq_++, s.source));
  }
  std::unique_ptr<ImuSource> source_;
  fploc::rt::Publisher<fploc::imu_t> out_;
  int64_t seq_ = 0;
};

FPLOC_REGISTER_NODE(ImuDriverNode)

}  // namespace
