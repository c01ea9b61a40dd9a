// The live sensor's set-up and watch, off the driver's event loop: a worker thread runs
// configure_sensor (fploc/os1/sensor_config.h; HTTP calls may take seconds, waiting for RUNNING up to
// sensor_timeout_s), then polls the sensor's status and alerts. The node drains what it found with
// take() on its own thread and turns it into ctx.error / set_detail / a new metadata. No LCM here.
#pragma once
#include <atomic>
#include <condition_variable>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "fploc/os1/sensor_config.h"

namespace fploc::os1 {

class SensorSession {
 public:
  struct Update {
    std::vector<std::string> errors;     // for ctx.error (telemetry last_error, stderr)
    std::vector<std::string> notes;      // for stderr only
    std::optional<std::string> detail;   // new state line (node_status_t.detail) when it changed
    std::optional<std::string> metadata; // metadata JSON read after a (re)configuration
    bool setup_failed = false;           // the last set-up attempt failed (the node may use its cache)
  };

  SensorSession(std::string host, SensorConfigRequest req, double poll_period_s, double retry_s = 10.0);
  ~SensorSession();
  void start();
  Update take();

 private:
  void run();
  bool wait_for(double seconds);  // false when stopping
  void error(const std::string& e);
  void note(const std::string& n);
  void detail(const std::string& d);
  bool setup();
  void watch();

  const std::string host_;
  SensorConfigRequest req_;
  std::atomic<bool> cancel_{false};
  const double poll_s_, retry_s_;
  std::thread thread_;
  std::mutex mu_;
  std::condition_variable cv_;
  bool stop_ = false;
  Update pending_;
  std::string last_detail_;
  // worker-only state
  FirmwareVersion fw_;
  SensorSetupResult setup_;
  int64_t cursor_ = -1;
  std::string last_status_, last_poll_error_;
};

}  // namespace fploc::os1
