// Test-only publisher for the dashboard tests: heartbeats of a named node and, with --sim, a simulated
// robot driving an ellipse in a 12 m x 8 m room with a round pillar (tests/dashboard/room.json) and a
// cabinet that is not in the plan:
// ground truth, 6-DoF poses, frame poses and ray-cast 2D features. Message times are the wall clock so
// the browser can measure end-to-end latency.
//   fploc-dashboard-fake --name NAME [--sim] [--rate HZ] [--duration S] [--state S --reporter R --once]
#include <fploc/features_t.hpp>
#include <fploc/frame_pose_t.hpp>
#include <fploc/ground_truth_t.hpp>
#include <fploc/node_status_t.hpp>
#include <fploc/pose_t.hpp>
#include <signal.h>
#include <sys/resource.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstring>
#include <iostream>
#include <lcm/lcm-cpp.hpp>
#include <string>
#include <thread>

namespace {
volatile sig_atomic_t g_stop = 0;
void on_signal(int) { g_stop = 1; }
int64_t wall_us() {
  return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}
double cpu_s() {
  rusage ru{};
  getrusage(RUSAGE_SELF, &ru);
  return double(ru.ru_utime.tv_sec + ru.ru_stime.tv_sec) + 1e-6 * double(ru.ru_utime.tv_usec + ru.ru_stime.tv_usec);
}
void quat_from_rpy(double r, double p, double y, double q[4]) {
  const double cr = cos(r / 2), sr = sin(r / 2), cp = cos(p / 2), sp = sin(p / 2), cy = cos(y / 2), sy = sin(y / 2);
  q[0] = sr * cp * cy - cr * sp * sy;
  q[1] = cr * sp * cy + sr * cp * sy;
  q[2] = cr * cp * sy - sr * sp * cy;
  q[3] = cr * cp * cy + sr * sp * sy;
}
// Distance along a ray from (px,py) in direction (dx,dy) to the room walls [0,W]x[0,H] and the pillar.
double cast(double px, double py, double dx, double dy) {
  const double W = 12, H = 8, cx = 6, cy = 4, r = 0.4;
  double t = 1e9;
  if (dx > 1e-9) t = std::min(t, (W - px) / dx);
  if (dx < -1e-9) t = std::min(t, -px / dx);
  if (dy > 1e-9) t = std::min(t, (H - py) / dy);
  if (dy < -1e-9) t = std::min(t, -py / dy);
  const double ox = px - cx, oy = py - cy, b = ox * dx + oy * dy, c = ox * ox + oy * oy - r * r, disc = b * b - c;
  if (disc >= 0) {
    const double tc = -b - std::sqrt(disc);
    if (tc > 0) t = std::min(t, tc);
  }
  // Clutter that is not in the plan: a 1 m x 0.6 m cabinet at (9.5, 1.5).
  const double bx0 = 9.0, bx1 = 10.0, by0 = 1.2, by1 = 1.8;
  double tmin = 0, tmax = 1e9;
  for (int a = 0; a < 2; ++a) {
    const double p = a ? py : px, d = a ? dy : dx, lo = a ? by0 : bx0, hi = a ? by1 : bx1;
    if (std::abs(d) < 1e-12) {
      if (p < lo || p > hi) tmax = -1;
    } else {
      double t1 = (lo - p) / d, t2 = (hi - p) / d;
      if (t1 > t2) std::swap(t1, t2);
      tmin = std::max(tmin, t1);
      tmax = std::min(tmax, t2);
    }
  }
  if (tmax >= tmin && tmin > 0) t = std::min(t, tmin);
  return t;
}
}  // namespace

int main(int argc, char** argv) {
  std::string name = "fake", url, state = "running", reporter = "node";
  bool sim = false, once = false;
  double rate = 10, duration = 0;
  // --pose-lag-at S --pose-lag-for D: from S s after the start, for D s, the pose falls behind the sensor (its stamp
  // advances at a quarter of the sensor's pace: 0.75 s behind per second, a localizer slower than its input), then
  // catches up at once (a node that keeps only the newest input). Ground truth and the frame stay at sensor time.
  double lag_at = 0, lag_for = 0;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string { return i + 1 < argc ? argv[++i] : ""; };
    if (a == "--name") name = next();
    else if (a == "--sim") sim = true;
    else if (a == "--rate") rate = std::stod(next());
    else if (a == "--duration") duration = std::stod(next());
    else if (a == "--state") state = next();
    else if (a == "--reporter") reporter = next();
    else if (a == "--once") once = true;
    else if (a == "--lcm-url") url = next();
    else if (a == "--pose-lag-at") lag_at = std::stod(next());
    else if (a == "--pose-lag-for") lag_for = std::stod(next());
    else {
      std::cerr << "usage: fploc-dashboard-fake --name NAME [--sim] [--rate HZ] [--duration S] [--state S] "
                   "[--reporter R] [--once] [--lcm-url URL] [--pose-lag-at S --pose-lag-for D]\n";
      return 2;
    }
  }
  signal(SIGINT, on_signal);
  signal(SIGTERM, on_signal);
  lcm::LCM lc(url.empty() ? "udpm://239.255.76.67:7667?ttl=0" : url);
  if (!lc.good()) {
    std::cerr << "fploc-dashboard-fake: no LCM\n";
    return 1;
  }
  const auto t0 = std::chrono::steady_clock::now();
  auto elapsed = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(); };
  int64_t seq = 0, out_period = 0, out_total = 0;
  double next_beat = 0, next_msg = 0, last_cpu = cpu_s(), last_beat_t = 0;
  auto poor = [&](int64_t k) { return k % 100 >= 40 && k % 100 < 70; };
  auto beat = [&] {
    fploc::node_status_t s{};
    s.utime = wall_us();
    s.node = name;
    s.executable = "fploc-dashboard-fake";
    s.pid = getpid();
    s.state = state;
    s.reporter = reporter;
    const double t = elapsed(), c = cpu_s();
    s.cpu_percent = t > last_beat_t ? 100.0 * (c - last_cpu) / (t - last_beat_t) : 0;
    last_cpu = c;
    s.latency_p50_ms = 0.4;
    s.latency_p99_ms = 1.1;
    s.messages_out = out_total;
    s.uptime_s = t;
    if (sim) {
      fploc::port_stats_t p{};
      p.port = "pose";
      p.channel = "FPLOC_POSE";
      p.output = true;
      p.messages = out_total;
      p.rate_hz = t > last_beat_t ? double(out_period) / (t - last_beat_t) : 0;
      s.ports.push_back(p);
    }
    if (sim && poor(seq)) s.detail = "POOR: a second fit 1.20 m / 0.0 deg away explains 95 %";
    s.num_ports = int32_t(s.ports.size());
    last_beat_t = t;
    out_period = 0;
    lc.publish("FPLOC_TELEMETRY", &s);
  };
  if (once) {
    beat();
    return 0;
  }
  while (!g_stop && (duration <= 0 || elapsed() < duration)) {
    const double t = elapsed();
    if (t >= next_beat) {
      beat();
      next_beat += 1.0;
    }
    if (sim && t >= next_msg) {
      next_msg += 1.0 / rate;
      const int64_t ut = wall_us();
      const double w = 2 * M_PI / 30.0, ang = w * t;
      const double x = 6 + 4 * cos(ang), y = 4 + 2.5 * sin(ang);
      const double yaw = atan2(2.5 * cos(ang), -4 * sin(ang));
      const double roll = 0.02 * sin(3 * ang), pitch = 0.015 * cos(2 * ang), z = 1.2 + 0.02 * sin(5 * ang);
      fploc::ground_truth_t g{};
      g.utime = ut;
      g.seq = seq;
      g.position[0] = x, g.position[1] = y, g.position[2] = z;
      quat_from_rpy(roll, pitch, yaw, g.orientation);
      g.scenario = "fake-ellipse";
      lc.publish("FPLOC_GROUND_TRUTH", &g);

      fploc::features_t f{};
      f.utime = ut;
      f.seq = seq;
      f.scan_seq = seq;
      f.roll = roll, f.pitch = pitch, f.z = z;
      for (int k = 0; k < 720; ++k) {
        const double a = yaw + k * M_PI / 360, dx = cos(a), dy = sin(a);
        const double d = cast(x, y, dx, dy);
        if (d > 30) continue;
        const double wx = x + d * dx, wy = y + d * dy;
        const double sx = cos(yaw) * (wx - x) + sin(yaw) * (wy - y), sy = -sin(yaw) * (wx - x) + cos(yaw) * (wy - y);
        const bool corner = (std::min(wx, 12 - wx) < 0.3 && std::min(wy, 8 - wy) < 0.3);
        f.x.push_back(float(sx));
        f.y.push_back(float(sy));
        f.kind.push_back(corner ? 0 : 1);
        f.group.push_back(-1);
        f.t_offset_s.push_back(0.f);
      }
      f.num_points = int32_t(f.x.size());
      lc.publish("FPLOC_FEATURES", &f);

      const double ex = x + 0.05 * sin(0.7 * t), ey = y + 0.04 * cos(0.5 * t), eyaw = yaw + 0.01 * sin(t);
      fploc::frame_pose_t fp{};
      fp.utime = ut;
      fp.seq = seq;
      fp.scan_seq = seq;
      fp.status = 0;
      fp.status_text = "ok";
      fp.x = ex, fp.y = ey, fp.yaw = eyaw;
      fp.roll = roll, fp.pitch = pitch, fp.z = z;
      fp.num_points = f.num_points;
      fp.num_inliers = f.num_points * 9 / 10;
      fp.inlier_ratio = 0.9;
      fp.rms_residual_m = 0.02;
      fp.iterations = 4;
      fp.solve_ms = 1.5;
      fp.floor_index = 0;
      fp.floor = "0";
      lc.publish("FPLOC_FRAME_POSE", &fp);

      const double lag_s = lag_for > 0 && t >= lag_at && t < lag_at + lag_for ? 0.75 * (t - lag_at) : 0.0;
      fploc::pose_t p{};
      p.utime = ut - int64_t(lag_s * 1e6);
      p.seq = seq;
      p.keyframe = (seq % 5) == 0;
      p.status = poor(seq) ? 1 : 0;  // POOR for 3 s of every 10 (the status row names the reason: telemetry detail)
      p.floor_index = 0;
      p.floor = "0";
      p.position[0] = ex, p.position[1] = ey, p.position[2] = z + 0.01;
      quat_from_rpy(roll, pitch, eyaw, p.orientation);
      p.covariance[0] = p.covariance[7] = 0.0004;
      lc.publish("FPLOC_POSE", &p);
      ++seq;
      ++out_total;
      ++out_period;
    }
    const double wake = std::min(next_beat, sim ? next_msg : next_beat) - elapsed();
    if (wake > 0) std::this_thread::sleep_for(std::chrono::duration<double>(std::min(wake, 0.05)));
  }
  if (state == "running") {
    state = "stopped";
    beat();
  }
  return 0;
}
