// OS-1 lidar driver: Ouster lidar packets from UDP (default port 7502), a pcap, or os1_packet_t messages
// (input port "packets", e.g. an ouster_ros bag imported by `fploc import`, with the metadata on the
// "metadata" port or in the `metadata` option) -> FrameAssembler -> OS1_SCAN (scan_t: staggered range
// image, signal, reflectivity, column times, beam intrinsics).
// Bad input (wrong sizes, garbage columns, late packets, missing columns) is counted with ctx.error and
// never stops the node. Output times are sensor times from the packets (deterministic for a pcap).
#include <fploc/os1_metadata_t.hpp>
#include <fploc/os1_packet_t.hpp>
#include <fploc/scan_t.hpp>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <stdexcept>

#include "fploc/os1/ports.h"
#include "fploc/adapters/scan_t.h"
#include "fploc/os1/metadata.h"
#include "fploc/os1/sensor_http.h"
#include "sensor_session.h"
#include "fploc/os1/packet.h"
#include "fploc/os1/source.h"
#include "fploc/runtime/node.h"
#include "options/sensors.pb.h"

namespace {

using namespace fploc::os1;

class Os1DriverNode : public fploc::rt::Node {
 public:
  static fploc::rt::NodeSpec spec() {
    return {"os1_driver", "os1_driver", "Ouster OS-1 lidar packets (UDP or pcap) -> full frames on OS1_SCAN",
            {fploc::rt::output<fploc::scan_t>("scan", "OS1_SCAN"),
             // Recorded packets (not connected unless the graph maps them: then no UDP, no pcap).
             fploc::rt::input<fploc::os1_packet_t>("packets", ""),
             fploc::rt::input<fploc::os1_metadata_t>("metadata", "")}};
  }

  void setup(fploc::rt::Context& ctx) override {
    ctx_ = &ctx;
    started_ = std::chrono::steady_clock::now();
    const auto& opt = ctx.options<fploc::Os1DriverOptions>();
    out_ = ctx.advertise<fploc::scan_t>("scan");
    port_ = fploc::os1::port_or_default(opt.lidar_port(), fploc::os1::kDefaultLidarPort);
    pcap_mode_ = !opt.pcap().empty();
    metadata_path_ = opt.metadata().empty() ? std::string() : ctx.resolve_path(opt.metadata());
    sensor_host_ = opt.sensor_hostname();
    if (!ctx.channel("packets").empty()) {
      setup_packets(ctx);
      return;
    }
    // A live sensor is set up over HTTP on start (unless keep_sensor_config) by a worker thread; its
    // metadata arrives through drain_session(), its status and alerts go to telemetry.
    if (!pcap_mode_ && !sensor_host_.empty() && !opt.keep_sensor_config()) {
      SensorConfigRequest req;
      req.udp_dest = opt.udp_dest();
      req.udp_port_lidar = port_;
      req.udp_port_imu = fploc::os1::port_or_default(opt.sensor_imu_port(), fploc::os1::kDefaultImuPort);
      req.lidar_mode = opt.lidar_mode();
      req.udp_profile_lidar = opt.udp_profile_lidar();
      req.timestamp_mode = opt.timestamp_mode();
      req.operating_mode = opt.operating_mode().empty() ? "NORMAL" : opt.operating_mode();
      req.timeout_s = opt.sensor_timeout_s() > 0 ? opt.sensor_timeout_s() : 60.0;
      req.persist = opt.persist_sensor_config();
      try {
        validate(req);  // a wrong option is a graph error: fail the start with the parameter's name
      } catch (const SensorConfigError& e) {
        throw std::runtime_error("os1_driver: sensor " + sensor_host_ + ": " + e.what());
      }
      session_ = std::make_unique<SensorSession>(sensor_host_, req, opt.alerts_period_s() > 0 ? opt.alerts_period_s() : 2.0);
      session_->start();
      ctx.every(0.2, [this] { drain_session(); });
    }
    // A missing or broken metadata file is bad input, not a reason to die: it is reported (stderr and
    // telemetry, once per distinct error), packets are dropped and counted, and the file is read again
    // every 0.5 s until it loads. A file that does not exist yet is waited for quietly for the first
    // kMetadataGraceS (the simulator writes it a moment after the driver starts: every start of the demo
    // printed "cannot open metadata file ... retrying"); still missing after that, it is reported.
    if (!load()) ctx.every(0.5, [this] { if (!assembler_) load(); });
    if (pcap_mode_) {
      std::string err;
      const double rate = opt.pcap_rate() == 0 ? 1.0 : opt.pcap_rate();
      if (!replay_.open(ctx.resolve_path(opt.pcap()), rate, opt.pcap_loop(), &err)) throw fploc::rt::SetupMayPass("os1_driver: " + err);
      // Looping: the capture starts over with the same frame ids; never treat them as late packets.
      replay_.set_on_restart([this] {
        assembler_->resync(frames_);
        publish_frames();
      });
      ctx.every(rate > 0 ? 0.002 : 0.001, [this] {
        if (assembler_) poll_pcap();  // a capture waits for its metadata
      });
    } else {
      const int buf = opt.recv_buffer_bytes() > 0 ? opt.recv_buffer_bytes() : 8 << 20;
      std::string err;
      if (!udp_.open(opt.bind_address(), port_, buf, &err)) throw std::runtime_error("os1_driver: " + err);
      if (udp_.actual_buffer_bytes() < buf)
        ctx.error("SO_RCVBUF is " + std::to_string(udp_.actual_buffer_bytes()) + " B, asked " + std::to_string(buf) +
                  " (raise net.core.rmem_max); packets may be dropped at 10 Hz");
      ctx.watch_fd(udp_.fd(), [this] {
        udp_.drain([this](uint16_t p, const uint8_t* d, size_t n) { on_datagram(p, d, n); });
      });
    }
  }

  void shutdown() override {
    session_.reset();  // stops the worker thread
    // What the socket still holds (under CPU load the loop may lag the packets; a simulator stopped just
    // before sent its frame in flight), then the frame in progress.
    udp_.drain([this](uint16_t p, const uint8_t* d, size_t n) { on_datagram(p, d, n); });
    if (assembler_) {
      assembler_->flush(frames_);
      publish_frames();
    }
  }

 private:
  // Packets from LCM (a recording): the metadata comes from the `metadata` option's file, else from the
  // first os1_metadata_t on the "metadata" port; packets before it are dropped and counted, as live.
  void setup_packets(fploc::rt::Context& ctx) {
    packets_mode_ = true;
    if (!metadata_path_.empty()) load();
    ctx.subscribe<fploc::os1_metadata_t>("metadata", [this](const fploc::os1_metadata_t& m) {
      if (assembler_) return;  // latched and republished: the first one counts
      try {
        info_ = parse_metadata(m.json, m.source.empty() ? std::string("os1_metadata_t") : m.source);
      } catch (const MetadataError& e) {
        report_metadata(e.what());
        return;
      }
      assembler_ = std::make_unique<FrameAssembler>(info_);
      if (!metadata_error_.empty()) ctx_->error_resolved(), metadata_error_.clear();
    });
    ctx.subscribe<fploc::os1_packet_t>("packets", [this](const fploc::os1_packet_t& m) {
      if (!assembler_) {
        if (++dropped_without_metadata_ % 6400 == 1) ctx_->error("lidar packets dropped: no valid metadata yet");
        return;
      }
      const size_t n = m.data.size();
      if (n == kImuPacketSize) return;  // IMU packets: the imu driver's job
      const PacketError e = assembler_->add_packet(m.data.data(), n, frames_);
      if (e != PacketError::kNone) report(e, n);
      publish_frames();
    });
  }

  // Once: a problem with the metadata (each distinct one is reported once; retried by the caller).
  void report_metadata(const std::string& what) {
    if (what != metadata_error_) ctx_->error(what + " (lidar packets are dropped; retrying)");
    metadata_error_ = what;
  }

  // What the sensor set-up worker found: errors to telemetry, the state line, a (new) metadata.
  void drain_session() {
    auto u = session_->take();
    for (const auto& n : u.notes) std::cerr << "[" << ctx_->name() << "] " << n << "\n";
    for (const auto& e : u.errors) ctx_->error(e);
    if (u.detail) ctx_->set_detail(*u.detail);
    session_failed_ = u.setup_failed;
    if (u.metadata) {
      session_metadata_ = std::move(*u.metadata);
      load();  // (re)builds the assembler from the sensor's current metadata
    } else if (session_failed_ && !assembler_ && !metadata_path_.empty() && !cache_tried_) {
      cache_tried_ = true;  // the sensor could not be set up: decode with the cached file meanwhile
      std::cerr << "[" << ctx_->name() << "] sensor set-up failed: trying the cached " << metadata_path_ << "\n";
      load();
    }
  }

  bool load() {
    if (session_) return load_from_session();
    if (metadata_path_.empty() && sensor_host_.empty()) {
      ctx_->error("neither 'metadata' (sensor metadata JSON) nor 'sensor_hostname' is set: lidar packets are dropped");
      return false;
    }
    std::string source = metadata_path_;
    try {
      std::string text, err;
      // From the sensor (at most every 5 s while it does not answer; the file cache meanwhile).
      if (!sensor_host_.empty() && std::chrono::steady_clock::now() >= next_http_) {
        if (fetch_sensor_metadata(sensor_host_, 1.0, &text, &err)) {
          source = "http://" + sensor_host_ + kMetadataPath;
        } else {
          next_http_ = std::chrono::steady_clock::now() + std::chrono::seconds(5);
          if (metadata_path_.empty()) throw MetadataError(err);
          std::cerr << "[" << ctx_->name() << "] " << err << ": trying the cached " << metadata_path_ << "\n";
        }
      }
      if (!text.empty()) {
        info_ = parse_metadata(text, source);
        if (!metadata_path_.empty()) {
          std::ofstream cache(metadata_path_, std::ios::trunc);
          cache << text;
          if (!cache) ctx_->error("cannot write the metadata cache " + metadata_path_);
        }
      } else if (!metadata_path_.empty()) {
        info_ = load_metadata(metadata_path_);
      } else {
        return false;  // waiting for the next HTTP attempt
      }
    } catch (const MetadataError& e) {
      std::string what = e.what();
      if (source == metadata_path_ && !metadata_path_.empty()) {
        std::error_code ec;
        if (!std::filesystem::exists(metadata_path_, ec)) {
          if (std::chrono::steady_clock::now() - started_ < std::chrono::duration<double>(kMetadataGraceS)) return false;
          what += " (no such file " + std::to_string(int(kMetadataGraceS)) + " s after the driver started)";
        }
      }
      report_metadata(what);
      return false;
    }
    if (!metadata_error_.empty() || source != metadata_path_)
      std::cerr << "[" << ctx_->name() << "] metadata from " << source << " (" << info_.sensor_name() << ")\n";
    if (!metadata_error_.empty()) {  // the start-up wait is over: the dashboard no longer shows it as the last error
      ctx_->error_resolved();
      metadata_error_.clear();
    }
    for (const auto& f : info_.defaulted)
      if (f == "pixel_shift_by_row" || f == "lidar_origin_to_beam_origin_mm")
        std::cerr << "[" << ctx_->name() << "] metadata: '" << f << "' absent, using the Ouster default\n";
    assembler_ = std::make_unique<FrameAssembler>(info_);
    classifier_ = PacketClassifier{pcap_mode_ ? ctx_->options<fploc::Os1DriverOptions>().lidar_port() : port_, -1,
                                   assembler_->format().lidar_packet_size()};
    return true;
  }

  // Metadata of a configured sensor (read after its set-up), cached in `metadata`; or the cached file
  // when the set-up failed.
  bool load_from_session() {
    std::string source;
    try {
      if (!session_metadata_.empty()) {
        source = "http://" + sensor_host_ + kMetadataPath + " (after the set-up)";
        info_ = parse_metadata(session_metadata_, source);
        if (!metadata_path_.empty()) {
          std::ofstream cache(metadata_path_, std::ios::trunc);
          cache << session_metadata_;
          if (!cache) ctx_->error("cannot write the metadata cache " + metadata_path_);
        }
        session_metadata_.clear();
      } else if (session_failed_ && !metadata_path_.empty()) {
        source = metadata_path_;
        info_ = load_metadata(metadata_path_);
      } else {
        return false;  // waiting for the sensor
      }
    } catch (const MetadataError& e) {
      report_metadata(e.what());
      return false;
    }
    std::cerr << "[" << ctx_->name() << "] metadata from " << source << " (" << info_.sensor_name() << ", "
              << info_.lidar_mode << ", " << to_string(info_.profile) << ")\n";
    assembler_ = std::make_unique<FrameAssembler>(info_);
    classifier_ = PacketClassifier{port_, -1, assembler_->format().lidar_packet_size()};
    return true;
  }

  void poll_pcap() {
    const bool more = replay_.poll([this](uint16_t p, const uint8_t* d, size_t n) { on_datagram(p, d, n); },
                                   [this] { return published_in_poll_; });
    published_in_poll_ = false;
    for (const auto& e : replay_.take_errors()) ctx_->error("pcap: " + e);
    if (!more) {
      assembler_->flush(frames_);
      publish_frames();
      ctx_->request_stop();
    }
  }

  void on_datagram(uint16_t port, const uint8_t* d, size_t n) {
    if (!assembler_) {
      if (++dropped_without_metadata_ % 6400 == 1) ctx_->error("lidar packets dropped: no valid metadata");
      return;
    }
    if (n == kImuPacketSize) return;  // IMU on the lidar port (same-port setups): the imu driver's job
    if (classifier_.classify(port, n) != PacketKind::kLidar) {
      if (classifier_.lidar_port == 0 || port == classifier_.lidar_port) report(PacketError::kWrongSize, n);
      return;  // another port in a pcap: not ours
    }
    const PacketError e = assembler_->add_packet(d, n, frames_);
    if (e != PacketError::kNone) report(e, n);
    publish_frames();
  }

  void report(PacketError e, size_t n) {
    std::string msg = std::string("lidar packet: ") + to_string(e);
    if (e == PacketError::kWrongSize)
      msg += " (" + std::to_string(n) + " B, expected " + std::to_string(assembler_->format().lidar_packet_size()) + ")";
    ctx_->error(msg);
  }

  void publish_frames() {
    for (auto& s : frames_) {
      if (s.missing_columns > 0)
        ctx_->error("frame " + std::to_string(s.frame_id) + ": " + std::to_string(s.missing_columns) +
                    " columns missing (published as invalid)");
      fploc::adapters::to_msg(s, msg_);
      out_.publish(msg_);
      published_in_poll_ = true;
      assembler_->recycle(std::move(s));
    }
    frames_.clear();
  }

  fploc::rt::Context* ctx_ = nullptr;
  SensorInfo info_;
  std::unique_ptr<FrameAssembler> assembler_;
  PacketClassifier classifier_;
  UdpReceiver udp_;
  PcapReplay replay_;
  std::vector<fploc::Scan> frames_;
  fploc::scan_t msg_;
  fploc::rt::Publisher<fploc::scan_t> out_;
  bool published_in_poll_ = false;
  bool pcap_mode_ = false;
  bool packets_mode_ = false;
  int port_ = fploc::os1::kDefaultLidarPort;
  std::string metadata_path_;
  std::string metadata_error_;  // last load error (reported once)
  static constexpr double kMetadataGraceS = 3.0;  // a metadata file that does not exist yet: quiet this long
  std::chrono::steady_clock::time_point started_{};
  std::string sensor_host_;
  std::chrono::steady_clock::time_point next_http_{};
  std::unique_ptr<SensorSession> session_;
  std::string session_metadata_;
  bool session_failed_ = false, cache_tried_ = false;
  uint64_t dropped_without_metadata_ = 0;
};

FPLOC_REGISTER_NODE(Os1DriverNode)

}  // namespace
