#include "views.h"

#include <fploc/features_t.hpp>
#include <fploc/frame_pose_t.hpp>
#include <fploc/ground_truth_t.hpp>
#include <fploc/node_status_t.hpp>
#include <fploc/pose_t.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>

#include "fploc/core/pose.h"
#include "fploc/core/text_out.h"

namespace fploc::dashboard {

using nlohmann::json;

namespace {
json num(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }
}  // namespace

double r6(double v) { return std::round(v * 1e6) / 1e6; }

Rpy rpy_of(const double q[4]) {
  const double n = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  if (!(n > 1e-12)) return {};
  fploc::StampedPose p;
  p.q = Eigen::Quaterniond(q[3], q[0], q[1], q[2]);
  const Eigen::Vector3d r = p.rpy();
  return {r[0], r[1], r[2]};
}

std::string pose_view(const fploc::pose_t& m, const Rpy& r, const AteFigure& ate, int64_t wall_us) {
  const double roll = r.roll, pitch = r.pitch, yaw = r.yaw;
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
            {"err", ate.err ? num(r6(*ate.err)) : json(nullptr)},
            {"ate_rmse", num(r6(ate.rmse))},
            {"ate_n", ate.n},
            {"floor_index", int(m.floor_index)},
            {"floor", m.floor},
            {"rx_us", wall_us}};
  return fploc::json_text(j);
}

std::string ground_truth_view(const fploc::ground_truth_t& m, const Rpy& r, const AteFigure& ate, int64_t wall_us) {
  const double roll = r.roll, pitch = r.pitch, yaw = r.yaw;
  json j = {{"utime", m.utime},
            {"seq", m.seq},
            {"x", num(r6(m.position[0]))},
            {"y", num(r6(m.position[1]))},
            {"z", num(r6(m.position[2]))},
            {"roll", num(r6(roll))},
            {"pitch", num(r6(pitch))},
            {"yaw", num(r6(yaw))},
            {"scenario", m.scenario},
            {"ate_rmse", num(r6(ate.rmse))},
            {"ate_n", ate.n},
            {"rx_us", wall_us}};
  return fploc::json_text(j);
}

std::string frame_pose_view(const fploc::frame_pose_t& m, double frame_rate_hz, int64_t wall_us) {
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
            {"frame_rate_hz", num(r6(frame_rate_hz))},
            {"floor_index", int(m.floor_index)},
            {"floor", m.floor},
            {"rx_us", wall_us}};
  return fploc::json_text(j);
}

std::string frame_pose_for_features(const fploc::frame_pose_t& fp, int64_t features_scan_seq) {
  json p = {{"x", num(fp.x)}, {"y", num(fp.y)}, {"yaw", num(fp.yaw)}, {"scan_seq", fp.scan_seq},
            {"exact", fp.scan_seq == features_scan_seq}};
  return fploc::json_text(p);
}

std::string features_view(const fploc::features_t& m, size_t max_points, const std::string& pose_json) {
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

std::string nodes_view(const std::map<std::string, NodeRow>& rows, double silent_after_s, int64_t wall_us) {
  json arr = json::array();
  for (const auto& [name, e] : rows) {
    const auto& s = *e.status;
    const double age = e.age_s;
    std::string health = "ok", reason;
    if (!e.seen) {
      health = age > silent_after_s ? "bad" : "warn";
      reason = "no heartbeat yet";
    } else if (age > silent_after_s) {
      health = "bad";
      char b[64];
      std::snprintf(b, sizeof b, "silent for %.1f s", age);
      reason = b;
    } else if (s.state == "waiting") {  // the launcher: a remote node waiting for its host ("waiting for host 'H': ...")
      health = "bad";
      reason = s.last_error.empty() ? "waiting for its host (launcher)" : s.last_error;
    } else if (s.state == "restarting" || s.state == "dead" || s.state == "hung" || s.state == "stopped") {
      health = "bad";
      reason = s.state + " (" + s.reporter + ")";
    } else if (s.state == "failing") {  // running, but not doing its job: last_error says why
      health = "bad";
      reason = s.last_error.empty() ? s.state : s.last_error;
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
                   {"detail", s.detail},
                   {"uptime_s", num(r6(s.uptime_s))},
                   {"age_s", e.seen ? num(std::round(age * 10) / 10) : json(nullptr)},
                   {"health", health},
                   {"reason", reason},
                   {"ports", ports}});
  }
  json j = {{"silent_after_s", silent_after_s}, {"wall_us", wall_us}, {"nodes", arr}};
  return fploc::json_text(j);
}

}  // namespace fploc::dashboard
