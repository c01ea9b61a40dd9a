#include "model.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>

namespace fploc::dashboard {

using nlohmann::json;

namespace {

// roll, pitch, yaw (ZYX) of a quaternion x y z w.
void quat_to_rpy(const double q[4], double& roll, double& pitch, double& yaw) {
  const double x = q[0], y = q[1], z = q[2], w = q[3];
  const double n = std::sqrt(x * x + y * y + z * z + w * w);
  if (!(n > 1e-12)) {
    roll = pitch = yaw = 0;
    return;
  }
  const double qx = x / n, qy = y / n, qz = z / n, qw = w / n;
  roll = std::atan2(2 * (qw * qx + qy * qz), 1 - 2 * (qx * qx + qy * qy));
  const double s = std::clamp(2 * (qw * qy - qz * qx), -1.0, 1.0);
  pitch = std::asin(s);
  yaw = std::atan2(2 * (qw * qz + qx * qy), 1 - 2 * (qy * qy + qz * qz));
}

// JSON numbers: finite values only (NaN/inf become null so the page never sees invalid JSON).
json num(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

// Rounded to micro-units: keeps the pushed text short.
double r6(double v) { return std::round(v * 1e6) / 1e6; }

double rate_over(std::deque<double>& times, double now_s, double window_s) {
  while (!times.empty() && times.front() < now_s - window_s) times.pop_front();
  return double(times.size()) / window_s;
}

void add_time(std::deque<double>& times, double now_s) {
  times.push_back(now_s);
  while (times.size() > 4096) times.pop_front();
}

}  // namespace

Model::Model(ModelConfig cfg) : cfg_(cfg) {}

void Model::set_slot(const std::string& name, std::string j) {
  auto& s = slots_[name];
  s.json = std::move(j);
  s.version = ++global_version_;
  cv_.notify_all();
}

void Model::on_plan_diff(std::string j) {
  std::lock_guard<std::mutex> lk(mu_);
  set_slot("plan_diff", std::move(j));
}

void Model::set_plan_json(std::string j) {
  std::lock_guard<std::mutex> lk(mu_);
  plan_json_ = std::move(j);
  set_slot("plan_changed", "{\"version\":" + std::to_string(global_version_ + 1) + "}");
}

void Model::set_info(const std::string& key, const std::string& j) {
  std::lock_guard<std::mutex> lk(mu_);
  info_[key] = j;
}

// ---- ATE so far ---------------------------------------------------------------------------------
void Model::ate_update_est(int64_t t, double x, double y, double z) {
  est_pos_[t] = {x, y, z};
  const auto tol = int64_t(cfg_.ate_match_tolerance_s * 1e6);
  auto best = gt_pos_.end();
  int64_t best_d = tol + 1;
  auto it = gt_pos_.lower_bound(t - tol);
  for (; it != gt_pos_.end() && it->first <= t + tol; ++it) {
    const int64_t d = std::llabs(it->first - t);
    if (d < best_d) best_d = d, best = it;
  }
  auto old = err_sq_.find(t);
  if (old != err_sq_.end()) {
    err_sum_ -= old->second;
    err_sq_.erase(old);
  }
  if (best != gt_pos_.end()) {
    const auto& g = best->second;
    const double e = (x - g[0]) * (x - g[0]) + (y - g[1]) * (y - g[1]) + (z - g[2]) * (z - g[2]);
    err_sq_[t] = e;
    err_sum_ += e;
  }
  while (est_pos_.size() > cfg_.max_trail * 2) {
    auto first = est_pos_.begin();
    auto e = err_sq_.find(first->first);
    if (e != err_sq_.end()) {
      err_sum_ -= e->second;
      err_sq_.erase(e);
    }
    est_pos_.erase(first);
  }
}

void Model::ate_update_gt(int64_t t, double x, double y, double z) {
  gt_pos_[t] = {x, y, z};
  while (gt_pos_.size() > cfg_.max_trail * 2) gt_pos_.erase(gt_pos_.begin());
  // Estimates that arrived before their ground truth.
  const auto tol = int64_t(cfg_.ate_match_tolerance_s * 1e6);
  for (auto it = est_pos_.lower_bound(t - tol); it != est_pos_.end() && it->first <= t + tol; ++it)
    if (!err_sq_.count(it->first)) ate_update_est(it->first, it->second[0], it->second[1], it->second[2]);
}

double Model::ate_rmse() const {
  return err_sq_.empty() ? NAN : std::sqrt(std::max(0.0, err_sum_) / double(err_sq_.size()));
}
size_t Model::ate_count() const { return err_sq_.size(); }

// ---- inputs ---------------------------------------------------------------------------------------
void Model::on_pose(const fploc::pose_t& m, double now_s, int64_t wall_us) {
  double roll, pitch, yaw;
  quat_to_rpy(m.orientation, roll, pitch, yaw);
  std::lock_guard<std::mutex> lk(mu_);
  add_time(pose_times_, now_s);
  ate_update_est(m.utime, m.position[0], m.position[1], m.position[2]);
  auto e = err_sq_.find(m.utime);
  TrailPoint p{m.utime, m.position[0], m.position[1], m.position[2], roll, pitch, yaw, e != err_sq_.end(),
               e != err_sq_.end() ? std::sqrt(e->second) : 0.0};
  // The optimiser re-publishes poses inside its window: replace the entry with the same time.
  bool replaced = false;
  for (size_t k = 0; k < est_.size() && k < 200; ++k) {
    auto& q = est_[est_.size() - 1 - k];
    if (q.utime == m.utime) {
      q = p;
      replaced = true;
      break;
    }
    if (q.utime < m.utime) break;
  }
  if (!replaced) {
    est_.push_back(p);
    // Keep the trail sorted when an older pose arrives late.
    for (size_t i = est_.size() - 1; i > 0 && est_[i - 1].utime > est_[i].utime; --i) std::swap(est_[i - 1], est_[i]);
    while (est_.size() > cfg_.max_trail) est_.pop_front();
  }
  json j = {{"utime", m.utime},
            {"seq", m.seq},
            {"status", int(m.status)},
            {"keyframe", bool(m.keyframe)},
            {"final", bool(m.final_estimate)},
            {"x", num(r6(m.position[0]))},
            {"y", num(r6(m.position[1]))},
            {"z", num(r6(m.position[2]))},
            {"roll", num(r6(roll))},
            {"pitch", num(r6(pitch))},
            {"yaw", num(r6(yaw))},
            {"sigma_xy", num(r6(std::sqrt(std::max(0.0, m.covariance[0] + m.covariance[7]))))},
            {"err", p.has_err ? num(r6(p.err)) : json(nullptr)},
            {"ate_rmse", num(r6(ate_rmse()))},
            {"ate_n", err_sq_.size()},
            {"rx_us", wall_us}};
  set_slot("pose", j.dump());
}

void Model::on_ground_truth(const fploc::ground_truth_t& m, double now_s, int64_t wall_us) {
  double roll, pitch, yaw;
  quat_to_rpy(m.orientation, roll, pitch, yaw);
  std::lock_guard<std::mutex> lk(mu_);
  ate_update_gt(m.utime, m.position[0], m.position[1], m.position[2]);
  TrailPoint p{m.utime, m.position[0], m.position[1], m.position[2], roll, pitch, yaw, false, 0};
  if (!gt_.empty() && gt_.back().utime == m.utime) gt_.back() = p;
  else if (gt_.empty() || gt_.back().utime < m.utime) gt_.push_back(p);
  while (gt_.size() > cfg_.max_trail) gt_.pop_front();
  json j = {{"utime", m.utime},
            {"seq", m.seq},
            {"x", num(r6(m.position[0]))},
            {"y", num(r6(m.position[1]))},
            {"z", num(r6(m.position[2]))},
            {"roll", num(r6(roll))},
            {"pitch", num(r6(pitch))},
            {"yaw", num(r6(yaw))},
            {"scenario", m.scenario},
            {"ate_rmse", num(r6(ate_rmse()))},
            {"ate_n", err_sq_.size()},
            {"rx_us", wall_us}};
  set_slot("gt", j.dump());
}

void Model::on_frame_pose(const fploc::frame_pose_t& m, double now_s, int64_t wall_us) {
  std::lock_guard<std::mutex> lk(mu_);
  add_time(frame_times_, now_s);
  frame_pose_ = m;
  have_frame_pose_ = true;
  json j = {{"utime", m.utime},
            {"seq", m.seq},
            {"scan_seq", m.scan_seq},
            {"status", int(m.status)},
            {"status_text", m.status_text},
            {"x", num(r6(m.x))},
            {"y", num(r6(m.y))},
            {"yaw", num(r6(m.yaw))},
            {"num_points", m.num_points},
            {"num_inliers", m.num_inliers},
            {"inlier_ratio", num(r6(m.inlier_ratio))},
            {"rms_residual_m", num(r6(m.rms_residual_m))},
            {"solve_ms", num(r6(m.solve_ms))},
            {"frame_rate_hz", num(r6(rate_over(frame_times_, now_s, 2.0)))},
            {"rx_us", wall_us}};
  set_slot("frame_pose", j.dump());
  // The features of this scan arrived first (the matcher consumes them): re-project them now.
  if (have_features_ && features_.scan_seq == m.scan_seq) publish_features();
}

void Model::on_features(const fploc::features_t& m, double now_s, int64_t wall_us) {
  std::lock_guard<std::mutex> lk(mu_);
  add_time(feature_times_, now_s);
  features_ = m;
  have_features_ = true;
  publish_features();
}

void Model::publish_features() {
  std::string pose = "null";
  if (have_frame_pose_) {
    json p = {{"x", num(frame_pose_.x)}, {"y", num(frame_pose_.y)}, {"yaw", num(frame_pose_.yaw)},
              {"scan_seq", frame_pose_.scan_seq}, {"exact", frame_pose_.scan_seq == features_.scan_seq}};
    pose = p.dump();
  }
  set_slot("features", features_json(features_, cfg_.max_feature_points, pose));
}

std::string Model::features_json(const fploc::features_t& m, size_t max_points, const std::string& pose_json) {
  const size_t n = size_t(std::max(0, std::min<int32_t>(m.num_points, int32_t(std::min(m.x.size(), m.y.size())))));
  const size_t step = (max_points > 0 && n > max_points) ? (n + max_points - 1) / max_points : 1;
  std::string out;
  out.reserve(64 + n / step * 18);
  char buf[96];
  std::snprintf(buf, sizeof buf, "{\"utime\":%lld,\"seq\":%lld,\"scan_seq\":%lld,\"status\":%d,\"n\":%zu,\"shown\":%zu,",
                (long long)m.utime, (long long)m.seq, (long long)m.scan_seq, int(m.status), n, (n + step - 1) / step);
  out += buf;
  std::snprintf(buf, sizeof buf, "\"roll\":%.6f,\"pitch\":%.6f,\"z\":%.4f,\"num_groups\":%d,",
                std::isfinite(m.roll) ? m.roll : 0.0, std::isfinite(m.pitch) ? m.pitch : 0.0,
                std::isfinite(m.z) ? m.z : 0.0, m.num_groups);
  out += buf;
  out += "\"pose\":" + pose_json + ",\"xy\":[";
  bool first = true;
  for (size_t i = 0; i < n; i += step) {
    const float x = m.x[i], y = m.y[i];
    if (!std::isfinite(x) || !std::isfinite(y)) continue;
    std::snprintf(buf, sizeof buf, first ? "%.3f,%.3f" : ",%.3f,%.3f", double(x), double(y));
    out += buf;
    first = false;
  }
  out += "],\"kind\":\"";
  for (size_t i = 0; i < n; i += step) {
    if (!std::isfinite(m.x[i]) || !std::isfinite(m.y[i])) continue;
    out += (i < m.kind.size() && m.kind[i] == 0) ? 'c' : 's';
  }
  out += "\"}";
  return out;
}

void Model::on_status(const fploc::node_status_t& m, double now_s) {
  std::lock_guard<std::mutex> lk(mu_);
  auto& e = nodes_[m.node];
  // A launcher report about a node never overrides a newer heartbeat from the node itself unless it
  // says the node is gone (restarting/dead/stopped/hung).
  e.status = m;
  e.received_s = now_s;
  e.seen = true;
  const int64_t wall = std::chrono::duration_cast<std::chrono::microseconds>(
                           std::chrono::system_clock::now().time_since_epoch()).count();
  rebuild_nodes(now_s, wall);
}

void Model::expect_node(const std::string& name, const std::string& executable, double now_s) {
  std::lock_guard<std::mutex> lk(mu_);
  if (nodes_.count(name)) return;
  auto& e = nodes_[name];
  e.status.node = name;
  e.status.executable = executable;
  e.status.state = "not seen";
  e.status.reporter = "graph";
  e.received_s = now_s;
}

void Model::tick(double now_s, int64_t wall_us) {
  std::lock_guard<std::mutex> lk(mu_);
  rebuild_nodes(now_s, wall_us);
  json s = {{"frame_rate_hz", num(r6(rate_over(frame_times_, now_s, 2.0)))},
            {"pose_rate_hz", num(r6(rate_over(pose_times_, now_s, 2.0)))},
            {"features_rate_hz", num(r6(rate_over(feature_times_, now_s, 2.0)))},
            {"clients", clients_},
            {"pushes", pushes_},
            {"ate_rmse", num(r6(ate_rmse()))},
            {"ate_n", err_sq_.size()},
            {"wall_us", wall_us}};
  set_slot("stats", s.dump());
}

void Model::rebuild_nodes(double now_s, int64_t wall_us) {
  json arr = json::array();
  for (const auto& [name, e] : nodes_) {
    const auto& s = e.status;
    const double age = now_s - e.received_s;
    std::string health = "ok", reason;
    if (!e.seen) {
      health = age > cfg_.silent_after_s ? "bad" : "warn";
      reason = "no heartbeat yet";
    } else if (age > cfg_.silent_after_s) {
      health = "bad";
      char b[64];
      std::snprintf(b, sizeof b, "silent for %.1f s", age);
      reason = b;
    } else if (s.state == "restarting" || s.state == "dead" || s.state == "hung" || s.state == "stopped") {
      health = "bad";
      reason = s.state + " (" + s.reporter + ")";
    } else if (s.state == "starting") {
      health = "warn";
      reason = "starting";
    } else if (s.state != "running") {
      health = "warn";
      reason = s.state;
    }
    double out_rate = 0, in_rate = 0;
    bool has_out = false;
    json ports = json::array();
    // The input whose handler takes longest (p50) is where the node does its work: the matcher's
    // features, not its 100 Hz IMU, whose microseconds would otherwise be the node's median.
    const fploc::port_stats_t* work = nullptr;
    for (const auto& p : s.ports) {
      (p.output ? out_rate : in_rate) += p.rate_hz;
      has_out = has_out || p.output;
      ports.push_back({{"port", p.port},
                       {"channel", p.channel},
                       {"output", bool(p.output)},
                       {"messages", p.messages},
                       {"rate_hz", num(p.rate_hz)},
                       {"dropped", p.dropped},
                       {"latency_p50_ms", num(r6(p.latency_p50_ms))},
                       {"latency_p99_ms", num(r6(p.latency_p99_ms))}});
      if (!p.output && p.rate_hz > 0 && (!work || p.latency_p50_ms > work->latency_p50_ms)) work = &p;
    }
    arr.push_back({{"node", name},
                   {"executable", s.executable},
                   {"pid", s.pid},
                   {"state", s.state},
                   {"reporter", s.reporter},
                   {"restarts", s.restarts},
                   {"cpu_percent", num(r6(s.cpu_percent))},
                   {"latency_p50_ms", num(r6(s.latency_p50_ms))},
                   {"latency_p99_ms", num(r6(s.latency_p99_ms))},
                   {"work_port", work ? json(work->port) : json(nullptr)},
                   {"work_p50_ms", work ? num(r6(work->latency_p50_ms)) : json(nullptr)},
                   {"work_p99_ms", work ? num(r6(work->latency_p99_ms)) : json(nullptr)},
                   {"messages_in", s.messages_in},
                   {"messages_out", s.messages_out},
                   {"rate_hz", num(r6(has_out ? out_rate : in_rate))},
                   {"rate_kind", has_out ? "out" : "in"},
                   {"dropped", s.dropped},
                   {"undecodable", s.undecodable},
                   {"last_error", s.last_error},
                   {"uptime_s", num(r6(s.uptime_s))},
                   {"age_s", e.seen ? num(std::round(age * 10) / 10) : json(nullptr)},
                   {"health", health},
                   {"reason", reason},
                   {"ports", ports}});
  }
  json j = {{"silent_after_s", cfg_.silent_after_s}, {"wall_us", wall_us}, {"nodes", arr}};
  std::string text = j.dump();
  auto it = slots_.find("nodes");
  // Only the ages change between heartbeats; push when health or content changed, or once a second.
  if (it == slots_.end() || it->second.json != text) set_slot("nodes", std::move(text));
}

// ---- outputs --------------------------------------------------------------------------------------
std::string Model::plan_json() const {
  std::lock_guard<std::mutex> lk(mu_);
  return plan_json_;
}

std::string Model::state_json() const {
  std::lock_guard<std::mutex> lk(mu_);
  std::string out = "{";
  bool first = true;
  for (const auto& [name, s] : slots_) {
    out += (first ? "\"" : ",\"") + name + "\":" + s.json;
    first = false;
  }
  return out + "}";
}

std::string Model::history_json(int64_t since) const {
  std::lock_guard<std::mutex> lk(mu_);
  json est = json::array(), gt = json::array();
  for (const auto& p : est_)
    if (p.utime > since) est.push_back({p.utime, num(r6(p.x)), num(r6(p.y)), num(r6(p.z)), num(r6(p.roll)), num(r6(p.pitch)),
                   num(r6(p.yaw)), p.has_err ? num(r6(p.err)) : json(nullptr)});
  for (const auto& p : gt_)
    if (p.utime > since) gt.push_back({p.utime, num(r6(p.x)), num(r6(p.y)), num(r6(p.z))});
  json j = {{"fields_est", {"utime", "x", "y", "z", "roll", "pitch", "yaw", "err"}},
            {"fields_gt", {"utime", "x", "y", "z"}},
            {"est", est},
            {"gt", gt},
            {"ate_rmse", num(ate_rmse())},
            {"ate_n", err_sq_.size()}};
  return j.dump();
}

std::string Model::info_json() const {
  std::lock_guard<std::mutex> lk(mu_);
  std::string out = "{";
  bool first = true;
  for (const auto& [k, v] : info_) {
    out += (first ? "\"" : ",\"") + k + "\":" + v;
    first = false;
  }
  return out + "}";
}

void Model::client_count(int delta) {
  std::lock_guard<std::mutex> lk(mu_);
  clients_ += delta;
}

uint64_t Model::pushes() const {
  std::lock_guard<std::mutex> lk(mu_);
  return pushes_;
}

void Model::stop() {
  std::lock_guard<std::mutex> lk(mu_);
  stopping_ = true;
  cv_.notify_all();
}

bool Model::next_push(ClientCursor& c, double max_hz, double keepalive_s, std::string& out) {
  using clock = std::chrono::steady_clock;
  auto secs = [] { return std::chrono::duration<double>(clock::now().time_since_epoch()).count(); };
  out.clear();
  std::unique_lock<std::mutex> lk(mu_);
  if (stopping_) return false;
  if (!c.greeted) {
    c.greeted = true;
    out = "retry: 1000\n\n";
  }
  // Each stream is capped on its own (at most max_hz events per second per stream), so a burst of
  // different streams from one scan goes out at once. Values are read when they are sent: whatever
  // arrived in between is skipped, never queued.
  const double period = max_hz > 0 ? 1.0 / max_hz : 0.0;
  const double keepalive_at = secs() + keepalive_s;
  for (;;) {
    const double now = secs();
    double next_due = keepalive_at;
    c.seen_global = global_version_;
    for (const auto& [name, s] : slots_) {
      auto& sent = c.sent[name];
      if (s.version <= sent) continue;
      double& last = c.last_sent_s[name];
      if (last + period <= now) {
        out += "event: " + name + "\ndata: " + s.json + "\n\n";
        sent = s.version;
        last = now;
      } else {
        next_due = std::min(next_due, last + period);
      }
    }
    if (!out.empty()) {
      ++pushes_;
      return true;
    }
    if (now >= keepalive_at) return true;  // nothing new: the caller sends a keep-alive comment
    cv_.wait_for(lk, std::chrono::duration<double>(std::max(0.0, next_due - now)),
                 [&] { return stopping_ || global_version_ > c.seen_global; });
    if (stopping_) return false;
  }
}

}  // namespace fploc::dashboard
