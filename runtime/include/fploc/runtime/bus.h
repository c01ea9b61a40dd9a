// The LCM instance of a process (shared by all nodes composed into it).
#pragma once
#include <lcm/lcm-cpp.hpp>

#include <memory>
#include <string>

namespace fploc::rt {

// Default URL: multicast on the loopback-friendly group with TTL 0 and a receive buffer large
// enough for full scans (LCM 1.3.1 drops a fragmented message when one fragment is lost).
inline constexpr const char* kDefaultLcmUrl = "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304";
inline constexpr const char* kTelemetryChannel = "FPLOC_TELEMETRY";
inline constexpr const char* kControlChannel = "FPLOC_CONTROL";
// Initial / re-initialisation poses (pose_t), published by `fploc node initial-pose` (an operator, like
// RViz's "2D Pose Estimate"); the matcher subscribes to it.
inline constexpr const char* kInitialPoseChannel = "FPLOC_INITIAL_POSE";

class Bus {
 public:
  explicit Bus(const std::string& url);
  lcm::LCM& lcm() { return *lcm_; }
  bool good() const { return lcm_ && lcm_->good(); }
  const std::string& url() const { return url_; }

 private:
  std::string url_;
  std::unique_ptr<lcm::LCM> lcm_;
};

}  // namespace fploc::rt
