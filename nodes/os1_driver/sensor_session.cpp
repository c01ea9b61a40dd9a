#include "sensor_session.h"

#include <chrono>

namespace fploc::os1 {

SensorSession::SensorSession(std::string host, SensorConfigRequest req, double poll_period_s, double retry_s)
    : host_(std::move(host)), req_(std::move(req)), poll_s_(poll_period_s), retry_s_(retry_s) {
  req_.cancel = &cancel_;
}

SensorSession::~SensorSession() {
  cancel_ = true;  // ends a wait for RUNNING within one poll period
  {
    std::lock_guard<std::mutex> l(mu_);
    stop_ = true;
  }
  cv_.notify_all();
  if (thread_.joinable()) thread_.join();
}

void SensorSession::start() { thread_ = std::thread([this] { run(); }); }

SensorSession::Update SensorSession::take() {
  std::lock_guard<std::mutex> l(mu_);
  Update u = std::move(pending_);
  pending_ = Update{};
  pending_.setup_failed = u.setup_failed;
  return u;
}

bool SensorSession::wait_for(double seconds) {
  std::unique_lock<std::mutex> l(mu_);
  return !cv_.wait_for(l, std::chrono::duration<double>(seconds), [this] { return stop_; });
}

void SensorSession::error(const std::string& e) {
  std::lock_guard<std::mutex> l(mu_);
  pending_.errors.push_back(e);
}
void SensorSession::note(const std::string& n) {
  std::lock_guard<std::mutex> l(mu_);
  pending_.notes.push_back(n);
}
void SensorSession::detail(const std::string& d) {
  std::lock_guard<std::mutex> l(mu_);
  if (d == last_detail_) return;
  last_detail_ = d;
  pending_.detail = d;
}

bool SensorSession::setup() {
  detail("sensor " + host_ + ": setting up");
  try {
    setup_ = configure_sensor(host_, req_, [this](const std::string& m) {
      note("sensor " + host_ + ": " + m);
      detail("sensor " + host_ + ": " + m);
    });
  } catch (const SensorConfigError& e) {
    error(std::string("sensor set-up failed: ") + e.what() + " (retrying in " + std::to_string(int(retry_s_)) + " s)");
    detail("sensor " + host_ + ": set-up failed: " + e.what());
    std::lock_guard<std::mutex> l(mu_);
    pending_.setup_failed = true;
    return false;
  }
  fw_ = setup_.firmware;
  cursor_ = setup_.alerts.next_cursor;
  last_status_ = setup_.status;
  note("sensor " + host_ + ": " + setup_.summary());
  for (const auto& a : setup_.alerts.active)
    if (a.level != "NOTICE") error("sensor " + host_ + " alert " + a.text());
  {
    std::lock_guard<std::mutex> l(mu_);
    pending_.setup_failed = false;
    if (!setup_.metadata_json.empty()) pending_.metadata = setup_.metadata_json;
  }
  return true;
}

// One poll: status (a change is an error unless it is RUNNING again, then the metadata is re-read) and
// the alert log since the last cursor (new WARNING / ERROR alerts are errors; clears are notes).
void SensorSession::watch() {
  const SensorHttp http(host_, req_.http_timeout_s);
  std::string status;
  AlertReport alerts;
  try {
    status = sensor_status(http, fw_);
    alerts = sensor_alerts(http, cursor_);
  } catch (const SensorConfigError& e) {
    if (e.what() != last_poll_error_) error(std::string("sensor watch: ") + e.what());
    last_poll_error_ = e.what();
    detail("sensor " + host_ + ": no answer (" + e.what() + ")");
    return;
  }
  last_poll_error_.clear();
  for (const auto& a : alerts.log) {
    if (a.cursor >= 0 && a.cursor < cursor_) continue;
    if (!a.active) note("sensor " + host_ + " alert cleared: " + a.text());
    else if (a.level == "NOTICE") note("sensor " + host_ + " notice: " + a.text());
    else error("sensor " + host_ + " alert " + a.text());
  }
  cursor_ = alerts.next_cursor;
  if (status != last_status_) {
    if (status == "RUNNING" && fw_.at_least(2, 2)) {
      note("sensor " + host_ + ": RUNNING again (was " + last_status_ + "); re-reading the metadata");
      try {
        std::string meta = http.get("/api/v1/sensor/metadata");
        std::lock_guard<std::mutex> l(mu_);
        pending_.metadata = std::move(meta);
      } catch (const SensorConfigError& e) {
        error(std::string("sensor metadata: ") + e.what());
      }
    } else {
      error("sensor " + host_ + ": status " + status + " (was " + last_status_ + ")");
    }
    last_status_ = status;
  }
  std::string d = "sensor " + host_ + " " + (setup_.prod_line.empty() ? "" : setup_.prod_line + " ") + "fw " +
                  fw_.str() + ": " + status + ", " + setup_.lidar_mode + " " + setup_.udp_profile_lidar + " " +
                  setup_.timestamp_mode + " -> " + setup_.udp_dest + ":" + std::to_string(req_.udp_port_lidar);
  if (alerts.active.empty()) {
    d += "; no active alerts";
  } else {
    d += "; " + std::to_string(alerts.active.size()) + " active alert(s):";
    for (const auto& a : alerts.active) d += " [" + a.text() + "]";
  }
  detail(d);
}

void SensorSession::run() {
  bool ready = false;
  for (;;) {
    if (!ready) {
      ready = setup();
      if (!wait_for(ready ? 0.0 : retry_s_)) return;
      continue;
    }
    watch();
    if (!wait_for(poll_s_)) return;
  }
}

}  // namespace fploc::os1
