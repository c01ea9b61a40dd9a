// sim-sensor: a simulated OS-1-64 that speaks the real wire format. Ray-casts the scenario (modules/sim),
// encodes every frame as OS-1 legacy lidar packets (16 columns, 12,608 B) and the IMU as 48-byte packets,
// and sends them over UDP (default 127.0.0.1:7502 / 7503) at the pace of the simulated sensor clock, so the
// whole chain from fploc-os1-driver / fploc-imu-driver on is exercised. The ground truth goes out on LCM
// (FPLOC_GROUND_TRUTH, the sensor pose at each frame's first column time). Packet and message times are
// simulated sensor times (no wall clock in outputs).
#include <arpa/inet.h>
#include <fploc/ground_truth_t.hpp>
#include <netdb.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <cerrno>
#include <fstream>
#include <memory>
#include <stdexcept>

#include "fploc/os1/ports.h"
#include "fploc/floorplan/building.h"
#include "fploc/floorplan/io.h"
#include "fploc/adapters/ground_truth_t.h"
#include "fploc/os1/packet.h"
#include "fploc/runtime/node.h"
#include "fploc/sim/simulator.h"
#include "options/sim.pb.h"

namespace {

double wall_now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

class SimSensorNode : public fploc::rt::Node {
 public:
  static fploc::rt::NodeSpec spec() {
    return {"sim_sensor", "sim",
            "simulated OS-1-64: OS-1 UDP packets (lidar 7502, IMU 7503) + ground truth on LCM",
            {fploc::rt::output<fploc::ground_truth_t>("ground_truth", "FPLOC_GROUND_TRUTH")}};
  }

  std::unique_ptr<fploc::sim::Simulator> make_sim() const {
    if (building_) return std::make_unique<fploc::sim::Simulator>(*building_, floor_, so_, plan_options_);
    return std::make_unique<fploc::sim::Simulator>(plan_, so_);
  }

  ~SimSensorNode() override {
    if (fd_ >= 0) ::close(fd_);
  }

  void setup(fploc::rt::Context& ctx) override {
    ctx_ = &ctx;
    if (ctx.composed()) throw std::runtime_error("sim: sim_sensor sends UDP in real time; it cannot run in composed replay");
    const auto& opt = ctx.options<fploc::SimOptions>();
    if (!opt.plan().file().empty()) {
      const std::vector<std::string> layers(opt.plan().layers().begin(), opt.plan().layers().end());
      const std::string file = ctx.resolve_path(opt.plan().file());
      if (fploc::is_building_file(file)) {
        // A building: the floor the sensor is on is simulated; journeys ride ramps and lifts.
        building_ = std::make_shared<fploc::Building>(fploc::load_building(file));
        floor_ = opt.plan().floor();
        plan_options_.layer_globs = layers;
        plan_options_.units_override = opt.plan().units();
      } else {
        plan_ = fploc::load_floor_plan(file, layers, opt.plan().units(), opt.plan().floor());
      }
    }
    so_.scenario = opt.scenario().empty() ? "room-small-loop-medium" : opt.scenario();
    so_.seed = opt.seed();
    so_.clutter = opt.has_clutter() ? opt.clutter() : true;
    so_.ceiling_patches = opt.has_ceiling_patches() ? opt.ceiling_patches() : true;
    if (opt.range_noise_m() > 0) so_.range_noise_m = opt.range_noise_m();
    if (opt.dropout() > 0) so_.dropout = opt.dropout();
    so_.ceiling_height_m = opt.ceiling_height_m();
    if (!opt.perturb().empty()) so_.perturb = fploc::sim::parse_perturb(opt.perturb());
    if (!opt.world().empty()) so_.world_file = ctx.resolve_path(opt.world());
    if (!opt.metadata().empty()) so_.metadata = ctx.resolve_path(opt.metadata());
    so_.beams = opt.beams();
    const char* sd = std::getenv("FPLOC_SHARED_DIR");
    so_.shared_dir = sd && *sd ? sd : FPLOC_SHARED_DIR;
    loop_ = opt.loop();
    rate_ = opt.rate() > 0 ? opt.rate() : 1.0;
    if (opt.duration_s() < 0) throw std::runtime_error("sim.duration_s: must be >= 0");
    duration_s_ = opt.duration_s();
    clock0_s_ = so_.t0_s;
    scenario_ = so_.scenario;
    sim_ = make_sim();
    std::cerr << "[" << ctx.name() << "] " << so_.scenario << ": " << sim_->num_frames() << " frames, "
              << sim_->motion().length() << " m; beams: " << sim_->beam_source() << "\n"
              << sim_->info();
    info_ = fploc::sim::sensor_info_for(sim_->lidar().config().beams, so_.width, so_.rate_hz);
    fmt_ = fploc::os1::PacketFormat::from(info_);
    if (!opt.metadata_out().empty()) {
      // Written beside it and renamed: a driver polling for the file never reads it half-written (or truncated, when
      // an older one is overwritten).
      const std::string p = ctx.resolve_path(opt.metadata_out());
      const std::string tmp = p + ".tmp" + std::to_string(::getpid());
      {
        std::ofstream f(tmp);
        f << fploc::sim::metadata_json(info_);
        if (!f) throw std::runtime_error("sim: cannot write metadata_out " + p + " (writing " + tmp + ")");
      }
      if (std::rename(tmp.c_str(), p.c_str()) != 0) {
        const std::string why = std::strerror(errno);
        std::remove(tmp.c_str());
        throw std::runtime_error("sim: cannot write metadata_out " + p + " (" + why + ")");
      }
    }
    gt_ = ctx.advertise<fploc::ground_truth_t>("ground_truth");
    // UDP socket.
    const std::string host = opt.udp_host().empty() ? "127.0.0.1" : opt.udp_host();
    fd_ = ::socket(AF_INET, SOCK_DGRAM, 0);
    if (fd_ < 0) throw std::runtime_error("sim: socket() failed");
    int sndbuf = 4 << 20;
    ::setsockopt(fd_, SOL_SOCKET, SO_SNDBUF, &sndbuf, sizeof(sndbuf));
    auto make_addr = [&](int port) {
      sockaddr_in a{};
      a.sin_family = AF_INET;
      a.sin_port = htons(uint16_t(port));
      if (::inet_pton(AF_INET, host.c_str(), &a.sin_addr) != 1) throw std::runtime_error("sim: udp_host '" + host + "' is not an IPv4 address");
      return a;
    };
    lidar_addr_ = make_addr(fploc::os1::port_or_default(opt.lidar_port(), fploc::os1::kDefaultLidarPort));
    imu_addr_ = make_addr(fploc::os1::port_or_default(opt.imu_port(), fploc::os1::kDefaultImuPort));
    if (opt.start_delay_s() < 0) throw std::runtime_error("sim.start_delay_s: must be >= 0");
    wall0_ = wall_now() + opt.start_delay_s();
    ctx.every(0.002, [this] { tick(); });
  }

  // The frame in flight: its ground truth is out (start_frame), so its remaining packets go too, at once
  // (their column times are in the packets). The launcher stops the drivers after the simulator (they
  // listen on its ports), so they receive it: every ground-truth frame is a complete scan.
  void shutdown() override {
    if (fd_ < 0) return;
    for (; next_pkt_ < int(pkts_.size()); ++next_pkt_) send(lidar_addr_, pkts_[size_t(next_pkt_)].data(), pkts_[size_t(next_pkt_)].size());
    if (!pkts_.empty()) ++k_;
    pkts_.clear();
  }

 private:
  void send(const sockaddr_in& a, const uint8_t* d, size_t n) {
    if (::sendto(fd_, d, n, 0, reinterpret_cast<const sockaddr*>(&a), sizeof(a)) != ssize_t(n))
      ctx_->error("sim: sendto failed for a " + std::to_string(n) + " B packet");
  }

  void start_frame() {
    sim_->frame(k_, cur_);
    cur_.scan.frame_id = int32_t(frame_counter_ & 0xFFFF);
    fploc::os1::encode_frame(cur_.scan, uint16_t(frame_counter_ & 0xFFFF), fmt_, pkts_);
    ++frame_counter_;
    next_pkt_ = 0;
    const double t = cur_.scan.utime * 1e-6;
    gt_.publish(fploc::adapters::ground_truth_msg(cur_.scan.utime, gt_seq_++, sim_->ground_truth(t), sim_->velocity(t),
                                        sim_->angular_velocity(t), scenario_));
  }

  void tick() {
    if (done_ || wall_now() < wall0_) return;
    // The simulated sensor clock runs from clock0_s_ (fixed); each loop's scenario starts at so_.t0_s.
    const double ts = clock0_s_ + (wall_now() - wall0_) * rate_;
    const double period = 1.0 / so_.rate_hz;
    const int W = so_.width;
    // At most ~50 ms of work per call: behind schedule (a loaded machine: each new frame is ray-cast), the
    // catch-up continues in the next call, and the node's loop meanwhile sees a stop request (the stop
    // waited for the whole catch-up, and the drivers stopped meanwhile lost the frames sent).
    const double t_call = wall_now();
    send_imu(ts);  // measured by now: before this call's lidar packets
    for (int guard = 0; guard < 1000 && wall_now() - t_call < 0.05; ++guard) {
      if (k_ >= frames_per_loop()) {
        if (!loop_) {
          std::cerr << "[" << ctx_->name() << "] scenario finished (" << frame_counter_ << " frames sent)\n";
          done_ = true;
          return;
        }
        // Start over: the next loop's scenario begins where this one ended on the same clock.
        so_.t0_s = sim_->frame_time(frames_per_loop());
        sim_ = make_sim();
        k_ = 0;
        imu_k_ = 0;
        continue;
      }
      if (pkts_.empty()) {
        if (sim_->frame_time(k_) > ts) break;
        // (After a loop's restart: the new pass's samples.) The IMU samples due go before the frame is ray-cast
        // (tens of ms on a busy machine) and before its packets: a sweep's last packet does not overtake the IMU
        // samples of its sweep, as from the sensor.
        send_imu(ts);
        start_frame();
      }
      // A packet goes out when its last column has been measured.
      const int cols = fmt_.columns_per_packet;
      const double due = sim_->frame_time(k_) + double((next_pkt_ + 1) * cols - 1) / W * period;
      if (due > ts) break;
      send(lidar_addr_, pkts_[size_t(next_pkt_)].data(), pkts_[size_t(next_pkt_)].size());
      if (++next_pkt_ >= int(pkts_.size())) {
        pkts_.clear();
        ++k_;
      }
    }
    send_imu(ts);
  }

  // The IMU samples measured up to sensor time ts, as IMU packets.
  void send_imu(double ts) {
    const auto& imu = sim_->imu();
    const double imu_end = sim_->frame_time(frames_per_loop());
    for (; imu_k_ < imu.size() && so_.t0_s + imu[imu_k_].t <= ts && so_.t0_s + imu[imu_k_].t < imu_end; ++imu_k_) {
      fploc::os1::ImuSample s;
      s.sys_ts_ns = s.accel_ts_ns = s.gyro_ts_ns = uint64_t(std::llround((so_.t0_s + imu[imu_k_].t) * 1e9));
      for (int i = 0; i < 3; ++i) {
        s.accel_mps2[size_t(i)] = imu[imu_k_].accel[i];
        s.gyro_radps[size_t(i)] = imu[imu_k_].gyro[i];
      }
      const auto b = fploc::os1::encode_imu_packet(s);
      send(imu_addr_, b.data(), b.size());
    }
  }

  // Frames of one pass of the scenario (all of it, or the first duration_s seconds).
  int frames_per_loop() const {
    const int n = sim_->num_frames();
    return duration_s_ > 0 ? std::min(n, int(std::floor(duration_s_ * so_.rate_hz))) : n;
  }

  fploc::rt::Context* ctx_ = nullptr;
  fploc::FloorPlan plan_;
  std::shared_ptr<fploc::Building> building_;  // when the plan file is a building (.pbtxt/.ifc)
  std::string floor_;
  fploc::PlanLoadOptions plan_options_;
  fploc::sim::SimulatorOptions so_;
  std::unique_ptr<fploc::sim::Simulator> sim_;
  fploc::os1::SensorInfo info_;
  fploc::os1::PacketFormat fmt_;
  fploc::rt::Publisher<fploc::ground_truth_t> gt_;
  int fd_ = -1;
  sockaddr_in lidar_addr_{}, imu_addr_{};
  double wall0_ = 0, rate_ = 1, clock0_s_ = 0, duration_s_ = 0;
  bool loop_ = false, done_ = false;
  std::string scenario_;
  int k_ = 0;
  size_t imu_k_ = 0;
  int next_pkt_ = 0;
  int64_t frame_counter_ = 0, gt_seq_ = 0;
  fploc::sim::SimScan cur_;
  std::vector<std::vector<uint8_t>> pkts_;
};

FPLOC_REGISTER_NODE(SimSensorNode)

}  // namespace
